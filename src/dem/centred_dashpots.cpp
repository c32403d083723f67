// Centred dashpots (timestep.dashpots = "centred", the default; docs/engine.md, "Dashpots").
//
// PFC's central differences keep velocities at half steps, and the lagged scheme computes a
// dashpot force at t from the relative velocity u(t - dt/2). In the fastest mode (x alternates
// every step) that velocity is as large as it gets while the true u(t) is zero, so the
// dashpot pumps the mode: a mode of frequency w and damping ratio z is then stable only for
// w dt < 2 (sqrt(1 + z^2) - z) (timestep.h), and a free pair's shear mode with rotation
// (z = sqrt(3) beta_s = 0.87) needs about half of PFC's step.
//
// The centred scheme takes the dashpot at u(t) = (u(t - dt/2) + u(t + dt/2)) / 2, the
// trapezoidal rule, which the velocity update then makes implicit:
//     u(t + dt/2) = u(t - dt/2) + dt (a_other - c u(t) / m)
// for a contact of dashpot coefficient c and effective mass m along its direction, where
// a_other is the relative acceleration from every other force. With u(t) = (u- + u+) / 2:
//     u(t) = (u* + (g / 2) u-) / (1 + g / 2),   g = c dt / m,
// where u* = u- + (dt / 2) (a_other - c u- / m) is what the discs' velocities at t would be
// with the lagged dashpot, known once the pass has summed every force. For a single mode of
// frequency w the recursion is
//     (1 + g/2) l^2 - (2 - (w dt)^2) l + (1 - g/2) = 0,
// stable (|l| < 1) for w dt < 2 whatever g: PFC's undamped limit, so PFC's rule as printed
// needs no damping correction. Its restitution tends to the closed form (eq. 2.56-2.62) as
// dt -> 0 (second order; tests Dashpots.*).
//
// Each contact solves its own dashpot implicitly, as if its two bodies had no other dashpot:
// exact for a pair or a disc on a wall; in a pack the other dashpots enter through u*. The
// pass without integration has already applied the lagged forces (the law and the kernels
// are the lagged scheme's); this pass adds the difference to the discs' sums, the walls'
// records and the ledger, then the ranges integrate. Along the normal the effective mass is
// m_i m_j / (m_i + m_j) (a wall's is infinite); along the tangent the contact point also
// turns with each disc, 1/m = 1/m_i + 1/m_j + r_i^2/I_i + r_j^2/I_j (rotation free).
//
// PFC's dashpot modes apply to the centred force as to the lagged one: no tension (the total
// normal force kept >= 0), no shear dashpot while the contact slides (the pass' capped shear
// force tells: |F_s| = mu F_n exactly).
#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "core/thread_pool.h"
#include "dem/centre_lanes.h"
#include "dem/world.h"

namespace demlab {

bool World::centred_dashpots() const {
    return with_contact_law(def_.law, [](auto law) { return decltype(law)::kCentredDashpots; }) &&
           def_.timestep.dashpots == DashpotScheme::Centred;
}

namespace {

// The centred dashpot force and the lagged one it replaces, along one direction.
struct DashpotShift {
    double d_new, d_old;
};

// u_lag: the relative velocity u(t - dt/2); u_pred: u* at t; g = c dt / m.
inline double centred_velocity(double u_lag, double u_pred, double g) {
    return (u_pred + 0.5 * g * u_lag) / (1.0 + 0.5 * g);
}

// Normal: the lagged and centred dashpot forces, both cut by the no-tension mode.
inline DashpotShift normal_shift(double cn, double u_lag, double u_pred, double g, double fn_spring, bool no_tension) {
    double d_old = -cn * u_lag, d_new = -cn * centred_velocity(u_lag, u_pred, g);
    if (no_tension) {
        d_old = std::max(d_old, -fn_spring);
        d_new = std::max(d_new, -fn_spring);
    }
    return {d_new, d_old};
}

inline DashpotShift shear_shift(double cs, double u_lag, double u_pred, double g, bool off) {
    if (off) return {0.0, 0.0};
    return {-cs * centred_velocity(u_lag, u_pred, g), -cs * u_lag};
}

}  // namespace

// The discs' velocities at t - dt/2 and at t (v* from the pass' sums, gravity included), with
// their inverse masses and inertias, one cache line per disc: the pairs then read two lines
// where they read nine arrays (measured: the pairs' gathering was three quarters of the
// centred pass).
void World::pack_centre_discs(size_t d0, size_t d1) {
    const double h = 0.5 * dt_;
    const bool rotation_free = def_.rotation.model != 1;
    const Vec2 g = def_.gravity;
    for (size_t d = d0; d < d1; ++d) {
        const DiscLoad& ld = load_[d];
        const Vec2 pv = vel_[d] + (ld.force * inv_mass_[d] + g) * h;
        centre_discs_[d] = CentreDisc{vel_[d].x(), vel_[d].y(), omega_[d], pv.x(), pv.y(),
                                      rotation_free ? omega_[d] + ld.torque * inv_inertia_[d] * h : 0.0,
                                      inv_mass_[d], inv_inertia_[d]};
    }
}

// One range's share (t): the shifts of its discs' contacts into dash_, in contact-list order
// per disc, as a serial pass would add them: first the cross contacts whose second disc it
// owns (their first disc lies in an earlier range, so they come first in the list), then its
// own contacts (a cross contact's second disc is left to the range that owns it, which
// computes the same shift again), then its wall contacts. The velocities at t are computed
// where they are needed from the pass' sums, which nothing writes in this phase. The pairs go
// through centre_lanes.h a block at a time: gathered in list order, computed lane by lane,
// added in list order.
bool World::centre_range(size_t tr, const PairPassParams& pp) {
    const double dt = dt_;
    const double h = 0.5 * dt;
    const bool rotation_free = def_.rotation.model != 1;
    const Vec2* const pos = pos_.data();
    const double* const radius = radius_.data();
    const int32_t* const material = material_.data();
    DashSum* const dash = dash_.data();
    DiscContact* const dd = dd_.data();
    const DashpotMode mode = pp.mode;
    const bool no_tension = mode == DashpotMode::NoTension || mode == DashpotMode::NoTensionNoShearWhileSliding;
    const bool no_shear_sliding =
        mode == DashpotMode::NoShearWhileSliding || mode == DashpotMode::NoTensionNoShearWhileSliding;
    const CentreConsts consts{dt, h, rotation_free, no_tension, no_shear_sliding};
    CentreBlock& b = *centre_blocks_[tr];
    const CentreDisc* const cd = centre_discs_.data();
    // a candidate pair into the block, kept if it touches
    auto gather = [&](const DiscContact& c, size_t k) {
        const size_t i = size_t(c.i), j = size_t(c.j);
        const Vec2 dx = pos[j] - pos[i];
        const double rsum = radius[i] + radius[j];
        const double dist2 = dx.squaredNorm();
        if (dist2 >= rsum * rsum) return;
        const size_t l = b.count++;
        const CentreDisc& ci = cd[i];
        const CentreDisc& cj = cd[j];
        b.dx[l] = dx.x();
        b.dy[l] = dx.y();
        b.dist2[l] = dist2;
        b.ri[l] = radius[i];
        b.rj[l] = radius[j];
        b.vrx[l] = cj.vx - ci.vx;
        b.vry[l] = cj.vy - ci.vy;
        b.wi[l] = ci.w;
        b.wj[l] = cj.w;
        b.prx[l] = cj.pvx - ci.pvx;
        b.pry[l] = cj.pvy - ci.pvy;
        b.pwi[l] = ci.pw;
        b.pwj[l] = cj.pw;
        b.inv_mn[l] = ci.inv_mass + cj.inv_mass;
        b.inv_ii[l] = ci.inv_inertia;
        b.inv_ij[l] = cj.inv_inertia;
        const PairMaterial& pm = pp.materials[size_t(material[i]) * pp.n_materials + size_t(material[j])];
        b.cn[l] = c.cn;
        b.cs[l] = c.cs;
        b.kn[l] = pm.kn;
        b.mu[l] = pm.mu;
        b.fs[l] = c.fs;
        b.contact[l] = k;
        b.i[l] = int32_t(i);
        b.j[l] = int32_t(j);
    };
    const size_t d0 = disc_split_[tr], d1 = disc_split_[tr + 1];
    std::fill(dash + d0, dash + d1, DashSum{});
    // the cross contacts into this range: their second disc's share, and the cross copies
    auto add_cross_in = [&]() {
        centre_block(b, consts, avx2_, avx512_);
        for (size_t l = 0; l < b.count; ++l) {
            DashSum& dj = dash[size_t(b.j[l])];
            dj.force += Vec2(b.fx[l], b.fy[l]);
            dj.torque += b.torque_j[l];
            dj.dissipated += 0.5 * b.dissipated[l];
            // the cross contact's own copy, which the next pass reads (force_pass.cpp)
            if (!cross_copies_stale_) {
                DiscContact& copy = cross_dd_[b.contact[l]];
                copy.damp_n = float(b.damp_n[l]);
                copy.damp_s = float(b.damp_s[l]);
            }
        }
        b.count = 0;
    };
    // own contacts: both discs' shares (a cross contact's second disc is another range's)
    auto add_own_computed = [&]() {
        for (size_t l = 0; l < b.count; ++l) {
            DiscContact& c = dd[b.contact[l]];
            c.damp_n = float(b.damp_n[l]);
            c.damp_s = float(b.damp_s[l]);
            const Vec2 f(b.fx[l], b.fy[l]);
            DashSum& di = dash[size_t(b.i[l])];
            di.force -= f;
            di.torque += b.torque_i[l];
            di.dissipated += 0.5 * b.dissipated[l];
            if (size_t(b.j[l]) >= d1) continue;
            DashSum& dj = dash[size_t(b.j[l])];
            dj.force += f;
            dj.torque += b.torque_j[l];
            dj.dissipated += 0.5 * b.dissipated[l];
        }
        b.count = 0;
    };
    auto add_own = [&]() {
        centre_block(b, consts, avx2_, avx512_);
        add_own_computed();
    };
    b.count = 0;
    if (force_ranges_ > 1) {
        for (int32_t e = cross_in_start_[tr]; e < cross_in_start_[tr + 1]; ++e) {
            gather(dd[size_t(cross_[size_t(cross_in_[size_t(e)])])], size_t(e));
            if (b.count == CentreBlock::kSize) add_cross_in();
        }
        if (b.count > 0) add_cross_in();
    }
    // the pass listed its touching pairs (its own and its cross ones, in list order): the
    // others add nothing, and testing every candidate here cost more than the shifts
    const uint32_t* const touching = touching_list_[tr].data();
    const size_t n_touching = touching_count_[tr];
    if (avx2_) {
        // gathered into lanes a block at a time (centre_wide.h); the same bits
        static_assert(sizeof(CentreDisc) == 64 && alignof(CentreDisc) == 64, "one aligned row of eight doubles");
        // (the arrays as raw doubles without a member call: a world without discs has none)
        static_assert(sizeof(Vec2) == 2 * sizeof(double), "(x, y) side by side");
        const CentrePairArrays arrays{reinterpret_cast<const double*>(pos_.data()), radius, material, pp.materials,
                                      pp.n_materials, dd, reinterpret_cast<const double*>(cd), prefetching()};
        for (size_t e = 0; e < n_touching; e += CentreBlock::kSize) {
            const size_t n = std::min(CentreBlock::kSize, n_touching - e);
            const bool done = avx512_ ? centre_touching_avx512(arrays, touching + e, n, b, consts)
                                      : centre_touching_avx2(arrays, touching + e, n, b, consts);
            if (!done) {  // a listed pair that does not touch: the scalar gather leaves it out
                for (size_t x = e; x < e + n; ++x) gather(dd[touching[x]], touching[x]);
                centre_block(b, consts, avx2_, avx512_);
            }
            add_own_computed();
        }
        return centre_walls(tr, consts);
    }
    for (size_t e = 0; e < n_touching; ++e) {
        const size_t k = touching[e];
        gather(dd[k], k);
        if (b.count == CentreBlock::kSize) add_own();
    }
    if (b.count > 0) add_own();
    return centre_walls(tr, consts);
}

// One range's wall contacts (centre_range's last share): their shifts into dash_ and their
// records (WallSum: one per touching contact, in list order, among those of open contacts
// that still dissipate). False: a touching contact without its record.
bool World::centre_walls(size_t tr, const CentreConsts& k) {
    const double dt = k.dt, h = k.half_dt;
    const bool rotation_free = k.rotation_free, no_tension = k.no_tension, no_shear_sliding = k.no_shear_sliding;
    const Vec2 g = def_.gravity;
    const Vec2* const pos = pos_.data();
    const Vec2* const vel = vel_.data();
    const double* const omega = omega_.data();
    const double* const radius = radius_.data();
    const double* const inv_mass = inv_mass_.data();
    const double* const inv_inertia = inv_inertia_.data();
    const int32_t* const material = material_.data();
    const DiscLoad* const load = load_.data();
    DashSum* const dash = dash_.data();
    auto centre_vel = [&](size_t d) { return vel[d] + (load[d].force * inv_mass[d] + g) * h; };
    auto centre_omega = [&](size_t d) { return rotation_free ? omega[d] + load[d].torque * inv_inertia[d] * h : 0.0; };
    const size_t nw = walls_.size();
    const auto& table = tables<LinearLaw>();
    WallSum* const sums = wall_sums_[tr].data();
    const size_t n_sums = range_clock_[tr].wall_sums;
    size_t e = 0;
    for (size_t kw = wall_split_[tr]; kw < wall_split_[tr + 1]; ++kw) {
        WallContact& c = dw_[kw];
        const size_t i = size_t(c.disc), w = size_t(c.wall);
        WallHit hit;
        if (!wall_active_[w] || !disc_wall_contact(geom_[w], pos[i], radius[i], hit)) continue;
        while (e < n_sums && sums[e].wall < 0) ++e;
        if (e == n_sums || sums[e].disc != int32_t(i) || sums[e].wall != int32_t(w)) return false;
        WallSum& rec = sums[e++];
        const Vec2 vwall = wall_moving_[w] ? walls_[w].velocity : Vec2::Zero();
        const Vec2 nrm = hit.normal;
        const Vec2 t = perp(nrm);
        const double rb = radius[i] - 0.5 * hit.overlap;
        const Vec2 vrel = vel[i] - vwall;
        const double vn = vrel.dot(nrm);
        const double vs = vrel.dot(t) - omega[i] * rb;
        const Vec2 prel = centre_vel(i) - vwall;
        const double pn = prel.dot(nrm);
        const double ps = prel.dot(t) - centre_omega(i) * rb;
        const PairMaterial& pm = table.disc_wall[size_t(material[i]) * nw + w];
        const double inv_mn = inv_mass[i];
        const double inv_ms = rotation_free ? inv_mn + rb * rb * inv_inertia[i] : inv_mn;
        const double fn_spring = pm.kn * hit.overlap;
        const bool sliding = std::abs(c.fs) >= pm.mu * fn_spring;
        const DashpotShift sn = normal_shift(c.cn, vn, pn, c.cn * dt * inv_mn, fn_spring, no_tension);
        const DashpotShift ss = shear_shift(c.cs, vs, ps, c.cs * dt * inv_ms, no_shear_sliding && sliding);
        const double dn = sn.d_new - sn.d_old, ds = ss.d_new - ss.d_old;
        c.damp_n = float(sn.d_new);
        c.damp_s = float(ss.d_new);
        const Vec2 f = dn * nrm + ds * t;  // on the disc
        DashSum& di = dash[i];
        di.force += f;
        di.torque += -rb * ds;
        rec.fx += f.x();
        rec.fy += f.y();
        rec.moment += cross(pos[i] - rb * nrm, f);
        rec.dissipated += -h * (dn * vn + ds * vs);
    }
    return true;
}

// The shifts of every range (centre_range), then every range's discs: their shifts added to
// their sums and integrated block by block as the fused pass does (the same chunks, so the
// same ledger blocks and notes). Two phases: no disc moves while a range still reads it.
void World::centre_dashpots(const PairPassParams& pp, const IntegrateConsts& ic) {
    dash_.resize(pos_.size());
    while (centre_blocks_.size() < size_t(force_ranges_)) centre_blocks_.push_back(std::make_unique<CentreBlock>());
    const bool avx2 = avx2_integration();
    auto integrate_range = [&](int t) {
        const size_t tr = size_t(t);
        range_clock_[tr].touching_dd = 0;
        DiscLoad* const load = load_.data();
        const DashSum* const dash = dash_.data();
        size_t b0 = disc_split_[tr];
        for (size_t fbi = fuse_start_[tr]; fbi < fuse_start_[tr + 1]; ++fbi) {
            const size_t b1 = fuse_blocks_[fbi].disc_end;
            for (size_t d = b0; d < b1; ++d) {
                load[d].force += dash[d].force;
                load[d].torque += dash[d].torque;
                load[d].dissipated += dash[d].dissipated;
            }
            if (!avx2) block_ledger(b0, b1, tr);
            integrate_discs(b0, b1, t, ic);
            b0 = b1;
        }
    };
    // (a wall contact without its record would be a bug of the pass: stop, naming it)
    const char* const missing = "internal: a wall contact's record is missing (centred dashpots)";
    centre_discs_.resize(pos_.size());
    if (force_ranges_ == 1) {
        pack_centre_discs(0, pos_.size());
        if (!centre_range(0, pp)) throw RunError(missing);
        integrate_range(0);
        return;
    }
    dash_ok_.resize(size_t(force_ranges_));
    pool_->for_each_thread([&](int t) { pack_centre_discs(disc_split_[size_t(t)], disc_split_[size_t(t) + 1]); });
    pool_->for_each_thread([&](int t) { dash_ok_[size_t(t)] = centre_range(size_t(t), pp) ? 1 : 0; });
    for (const uint8_t ok : dash_ok_)
        if (!ok) throw RunError(missing);
    pool_->for_each_thread(integrate_range);
}

}  // namespace demlab
