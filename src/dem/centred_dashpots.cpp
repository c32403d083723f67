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
#include "dem/world.h"

namespace demlab {

bool World::centred_dashpots() const {
    return def_.law == ContactLawKind::Linear && def_.timestep.dashpots == DashpotScheme::Centred;
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

// One range's share (t): the shifts of its discs' contacts into dash_, in contact-list order
// per disc, as a serial pass would add them: first the cross contacts whose second disc it
// owns (their first disc lies in an earlier range, so they come first in the list), then its
// own contacts (a cross contact's second disc is left to the range that owns it, which
// computes the same shift again), then its wall contacts. The velocities at t are computed
// where they are needed from the pass' sums, which nothing writes in this phase.
bool World::centre_range(size_t tr, const PairPassParams& pp) {
    const double dt = dt_;
    const double h = 0.5 * dt;
    const bool rotation_free = def_.rotation.model != 1;
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
    const DashpotMode mode = pp.mode;
    const bool no_tension = mode == DashpotMode::NoTension || mode == DashpotMode::NoTensionNoShearWhileSliding;
    const bool no_shear_sliding =
        mode == DashpotMode::NoShearWhileSliding || mode == DashpotMode::NoTensionNoShearWhileSliding;
    auto centre_vel = [&](size_t d) { return vel[d] + (load[d].force * inv_mass[d] + g) * h; };
    auto centre_omega = [&](size_t d) { return rotation_free ? omega[d] + load[d].torque * inv_inertia[d] * h : 0.0; };
    struct Shift {
        Vec2 f;            // on j
        double torque_i, torque_j, dissipated;
        float damp_n, damp_s;
    };
    // a touching pair's shift (false: it does not touch)
    auto pair_shift = [&](const DiscContact& c, Shift& out) {
        const size_t i = size_t(c.i), j = size_t(c.j);
        const Vec2 dx = pos[j] - pos[i];
        const double rsum = radius[i] + radius[j];
        const double dist2 = dx.squaredNorm();
        if (dist2 >= rsum * rsum) return false;
        const double dist = std::sqrt(dist2);
        const double overlap = rsum - dist;
        const Vec2 nrm = dx / dist;
        const Vec2 t = perp(nrm);
        const double ra = radius[i] - 0.5 * overlap, rb = radius[j] - 0.5 * overlap;
        const Vec2 vrel = vel[j] - vel[i];
        const double vn = vrel.dot(nrm);
        const double vs = vrel.dot(t) - (omega[i] * ra + omega[j] * rb);
        const Vec2 prel = centre_vel(j) - centre_vel(i);
        const double pn = prel.dot(nrm);
        const double ps = prel.dot(t) - (centre_omega(i) * ra + centre_omega(j) * rb);
        const PairMaterial& pm = pp.materials[size_t(material[i]) * pp.n_materials + size_t(material[j])];
        const double inv_mn = inv_mass[i] + inv_mass[j];
        const double inv_ms = rotation_free ? inv_mn + ra * ra * inv_inertia[i] + rb * rb * inv_inertia[j] : inv_mn;
        const double fn_spring = pm.kn * overlap;
        const bool sliding = std::abs(c.fs) >= pm.mu * fn_spring;
        const DashpotShift sn = normal_shift(c.cn, vn, pn, c.cn * dt * inv_mn, fn_spring, no_tension);
        const DashpotShift ss = shear_shift(c.cs, vs, ps, c.cs * dt * inv_ms, no_shear_sliding && sliding);
        const double dn = sn.d_new - sn.d_old, ds = ss.d_new - ss.d_old;
        out.f = dn * nrm + ds * t;
        out.torque_i = -ra * ds;
        out.torque_j = -rb * ds;
        // the law booked this step's force over the first half of the velocity interval
        out.dissipated = -h * (dn * vn + ds * vs);
        out.damp_n = float(sn.d_new);
        out.damp_s = float(ss.d_new);
        return true;
    };
    const size_t d0 = disc_split_[tr], d1 = disc_split_[tr + 1];
    std::fill(dash + d0, dash + d1, DashSum{});
    Shift sh;
    if (force_ranges_ > 1)
        for (int32_t e = cross_in_start_[tr]; e < cross_in_start_[tr + 1]; ++e) {
            const DiscContact& c = dd_[size_t(cross_[size_t(cross_in_[size_t(e)])])];
            if (!pair_shift(c, sh)) continue;
            DashSum& dj = dash[size_t(c.j)];
            dj.force += sh.f;
            dj.torque += sh.torque_j;
            dj.dissipated += 0.5 * sh.dissipated;
            // the cross contact's own copy, which the next pass reads (force_pass.cpp)
            if (!cross_copies_stale_) {
                cross_dd_[size_t(e)].damp_n = sh.damp_n;
                cross_dd_[size_t(e)].damp_s = sh.damp_s;
            }
        }
    for (size_t k = contact_split_[tr]; k < contact_split_[tr + 1]; ++k) {
        DiscContact& c = dd_[k];
        if (!pair_shift(c, sh)) continue;
        c.damp_n = sh.damp_n;
        c.damp_s = sh.damp_s;
        DashSum& di = dash[size_t(c.i)];
        di.force -= sh.f;
        di.torque += sh.torque_i;
        di.dissipated += 0.5 * sh.dissipated;
        if (size_t(c.j) >= d1) continue;  // a cross contact: its second disc is another range's
        DashSum& dj = dash[size_t(c.j)];
        dj.force += sh.f;
        dj.torque += sh.torque_j;
        dj.dissipated += 0.5 * sh.dissipated;
    }
    // its wall contacts, with their records (WallSum: one per touching contact, in list
    // order, among those of open contacts that still dissipate)
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
    if (force_ranges_ == 1) {
        if (!centre_range(0, pp)) throw RunError(missing);
        integrate_range(0);
        return;
    }
    dash_ok_.resize(size_t(force_ranges_));
    pool_->for_each_thread([&](int t) { dash_ok_[size_t(t)] = centre_range(size_t(t), pp) ? 1 : 0; });
    for (const uint8_t ok : dash_ok_)
        if (!ok) throw RunError(missing);
    pool_->for_each_thread(integrate_range);
}

}  // namespace demlab
