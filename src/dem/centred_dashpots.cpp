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
// force pass applies the lagged forces (the law and the kernels are the lagged scheme's);
// behind it, block by block, each range adds the difference to the discs' sums, the walls'
// records and the ledger, and integrates the block (force_pass.cpp, range_pass): a block is
// centred once every disc its pairs reach has its sums, and integrated once its own discs
// have every shift. Along the normal the effective mass is
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
// centred pass). Their shifts' sums start from zero here, before any pair adds to them.
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
        dash_[d] = DashSum{};
    }
}

CentreConsts World::centre_consts(const PairPassParams& pp) const {
    const DashpotMode mode = pp.mode;
    const bool no_tension = mode == DashpotMode::NoTension || mode == DashpotMode::NoTensionNoShearWhileSliding;
    const bool no_shear_sliding =
        mode == DashpotMode::NoShearWhileSliding || mode == DashpotMode::NoTensionNoShearWhileSliding;
    return CentreConsts{dt_, 0.5 * dt_, def_.rotation.model != 1, no_tension, no_shear_sliding};
}

// The step's arrays for the centred pass, sized before the ranges start (no allocation in
// the ranges but a late share list's first growth).
void World::prepare_centred_pass() {
    const size_t r = size_t(force_ranges_);
    touching_list_.resize(r);
    for (size_t t = 0; t < r; ++t) touching_list_[t].resize(contact_split_[t + 1] - contact_split_[t]);
    dash_.resize(pos_.size());
    centre_discs_.resize(pos_.size());
    while (centre_blocks_.size() < r) centre_blocks_.push_back(std::make_unique<CentreBlock>());
    late_shares_.resize(r);
    dash_ok_.assign(r, 1);
    cross_shift_.resize(cross_.size());
    fuse_touching_end_.resize(fuse_blocks_.size());
    fuse_sums_end_.resize(fuse_blocks_.size());
}

// Range t's touching pairs touching_list_[t][e0, e1), which the range's pass has listed and
// whose discs it has packed. A disc adds its shifts in contact-list order, as a serial pass
// over every pair would: first those of the cross contacts whose second disc it is (their
// first disc lies in an earlier range, so they come first in the list), then its own pairs'.
// So a share for a disc below late_end (the discs an earlier range's cross pairs reach) is
// kept back in late_shares_ until the cross shifts are in (finish_late_discs); the others are
// added now. A cross pair's second share goes to cross_shift_, for the range owning its disc.
// The pairs go through centre_lanes.h a block at a time: gathered in list order, computed
// lane by lane, added in list order.
void World::centre_rows(size_t tr, const PairPassParams& pp, const CentreConsts& k, size_t e0, size_t e1,
                        size_t late_end, size_t& cross_cursor, bool prefetch) {
    if (e0 >= e1) return;
    const Vec2* const pos = pos_.data();
    const double* const radius = radius_.data();
    const int32_t* const material = material_.data();
    DashSum* const dash = dash_.data();
    DiscContact* const dd = dd_.data();
    const size_t d1 = disc_split_[tr + 1];
    const uint64_t pass = cross_pass_;
    std::vector<LateShare>& late = late_shares_[tr];
    CentreBlock& b = *centre_blocks_[tr];
    const CentreDisc* const cd = centre_discs_.data();
    // a listed pair into the block, kept if it touches
    auto gather = [&](const DiscContact& c, size_t ck) {
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
        b.contact[l] = ck;
        b.i[l] = int32_t(i);
        b.j[l] = int32_t(j);
    };
    auto add = [&]() {
        for (size_t l = 0; l < b.count; ++l) {
            const size_t ck = b.contact[l];
            DiscContact& c = dd[ck];
            c.damp_n = float(b.damp_n[l]);
            c.damp_s = float(b.damp_s[l]);
            const size_t i = size_t(b.i[l]), j = size_t(b.j[l]);
            const double fx = b.fx[l], fy = b.fy[l];
            if (j >= d1) {  // a cross contact: its second share is the range owning j's
                while (size_t(cross_[cross_cursor]) < ck) ++cross_cursor;
                cross_shift_[cross_cursor] = CrossShift{fx, fy, b.torque_j[l], b.dissipated[l], pass};
                // the contact's own copy, which the owning range's next pass reads (force_pass.cpp)
                if (!cross_copies_stale_) {
                    DiscContact& copy = cross_dd_[size_t(cross_pos_[cross_cursor])];
                    copy.damp_n = float(b.damp_n[l]);
                    copy.damp_s = float(b.damp_s[l]);
                }
            }
            if (i < late_end) {
                late.push_back(LateShare{int32_t(i), int32_t(j), fx, fy, b.torque_i[l], b.torque_j[l], b.dissipated[l]});
                if (j < late_end || j >= d1) continue;
            } else {
                DashSum& di = dash[i];
                di.force -= Vec2(fx, fy);
                di.torque += b.torque_i[l];
                di.dissipated += 0.5 * b.dissipated[l];
                if (j >= d1) continue;
            }
            DashSum& dj = dash[j];
            dj.force += Vec2(fx, fy);
            dj.torque += b.torque_j[l];
            dj.dissipated += 0.5 * b.dissipated[l];
        }
        b.count = 0;
    };
    b.count = 0;
    const uint32_t* const touching = touching_list_[tr].data();
    if (avx2_) {
        // gathered into lanes a block at a time (centre_wide.h); the same bits
        static_assert(sizeof(CentreDisc) == 64 && alignof(CentreDisc) == 64, "one aligned row of eight doubles");
        // (the arrays as raw doubles without a member call: a world without discs has none)
        static_assert(sizeof(Vec2) == 2 * sizeof(double), "(x, y) side by side");
        const CentrePairArrays arrays{reinterpret_cast<const double*>(pos_.data()), radius, material, pp.materials,
                                      pp.n_materials, dd, reinterpret_cast<const double*>(cd), prefetch};
        for (size_t e = e0; e < e1; e += CentreBlock::kSize) {
            const size_t n = std::min(CentreBlock::kSize, e1 - e);
            const bool done = avx512_ ? centre_touching_avx512(arrays, touching + e, n, b, k)
                                      : centre_touching_avx2(arrays, touching + e, n, b, k);
            if (!done) {  // a listed pair that does not touch: the scalar gather leaves it out
                for (size_t x = e; x < e + n; ++x) gather(dd[touching[x]], touching[x]);
                centre_block(b, k, avx2_, avx512_);
            }
            add();
        }
        return;
    }
    for (size_t e = e0; e < e1; ++e) {
        gather(dd[touching[e]], touching[e]);
        if (b.count == CentreBlock::kSize) {
            centre_block(b, k, avx2_, avx512_);
            add();
        }
    }
    if (b.count > 0) {
        centre_block(b, k, avx2_, avx512_);
        add();
    }
}

// Range t's discs below its late end: first the cross shifts into them (cross_in_ order, their
// list order), then the shares kept back, in list order.
void World::finish_late_discs(size_t tr) {
    DashSum* const dash = dash_.data();
    const uint64_t pass = cross_pass_;
    for (int32_t e = cross_in_start_[tr]; e < cross_in_start_[tr + 1]; ++e) {
        const CrossShift& s = cross_shift_[size_t(cross_in_[size_t(e)])];
        if (s.pass != pass) continue;  // not touching
        DashSum& dj = dash[size_t(cross_dd_[size_t(e)].j)];
        dj.force += Vec2(s.fx, s.fy);
        dj.torque += s.torque_j;
        dj.dissipated += 0.5 * s.dissipated;
    }
    const size_t late_end = cross_in_reach_[tr];
    for (const LateShare& s : late_shares_[tr]) {
        DashSum& di = dash[size_t(s.i)];
        di.force -= Vec2(s.fx, s.fy);
        di.torque += s.torque_i;
        di.dissipated += 0.5 * s.dissipated;
        if (size_t(s.j) >= late_end) continue;  // added already (or another range's)
        DashSum& dj = dash[size_t(s.j)];
        dj.force += Vec2(s.fx, s.fy);
        dj.torque += s.torque_j;
        dj.dissipated += 0.5 * s.dissipated;
    }
    late_shares_[tr].clear();
}

// Wall contacts dw_[kw0, kw1) of range t (the last shifts of their discs): their shifts into
// dash_ and their records (WallSum: one per touching contact, in list order, among those of
// open contacts that still dissipate), from sums[e] on. False: a touching contact without
// its record.
bool World::centre_walls(size_t tr, const CentreConsts& k, size_t kw0, size_t kw1, size_t& e) {
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
    for (size_t kw = kw0; kw < kw1; ++kw) {
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

// Discs [b0, b1) of range t, their shifts complete: added to their sums, then integrated as
// the fused pass does (the same ledger blocks and notes).
void World::integrate_centred(size_t b0, size_t b1, int t, const IntegrateConsts& ic) {
    DiscLoad* const load = load_.data();
    const DashSum* const dash = dash_.data();
    for (size_t d = b0; d < b1; ++d) {
        load[d].force += dash[d].force;
        load[d].torque += dash[d].torque;
        load[d].dissipated += dash[d].dissipated;
    }
    if (!avx2_integration()) block_ledger(b0, b1, size_t(t));
    integrate_discs(b0, b1, t, ic);
}

}  // namespace demlab
