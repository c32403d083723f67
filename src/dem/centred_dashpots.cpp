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

void World::centre_dashpots(const PairPassParams& pp) {
    const size_t n = pos_.size();
    const double dt = dt_;
    const double h = 0.5 * dt;
    const bool rotation_free = def_.rotation.model != 1;
    const Vec2 g = def_.gravity;
    vel_centre_.resize(n);
    omega_centre_.resize(n);
    // u*: each disc's velocity at t from its sums (the lagged dashpots included) and gravity
    for (size_t i = 0; i < n; ++i) {
        const DiscLoad& l = load_[i];
        vel_centre_[i] = vel_[i] + (l.force * inv_mass_[i] + g) * h;
        omega_centre_[i] = rotation_free ? omega_[i] + l.torque * inv_inertia_[i] * h : 0.0;
    }
    const DashpotMode mode = pp.mode;
    const bool no_tension = mode == DashpotMode::NoTension || mode == DashpotMode::NoTensionNoShearWhileSliding;
    const bool no_shear_sliding =
        mode == DashpotMode::NoShearWhileSliding || mode == DashpotMode::NoTensionNoShearWhileSliding;
    const auto& table = tables<LinearLaw>();
    // The shifts go into the discs' sums in contact-list order after the pass' terms, on one
    // thread: the same bits for any thread count.
    for (DiscContact& c : dd_) {
        const size_t i = size_t(c.i), j = size_t(c.j);
        const Vec2 dx = pos_[j] - pos_[i];
        const double rsum = radius_[i] + radius_[j];
        const double dist2 = dx.squaredNorm();
        if (dist2 >= rsum * rsum) continue;
        const double dist = std::sqrt(dist2);
        const double overlap = rsum - dist;
        const Vec2 nrm = dx / dist;
        const Vec2 t = perp(nrm);
        const double ra = radius_[i] - 0.5 * overlap, rb = radius_[j] - 0.5 * overlap;
        const Vec2 vrel = vel_[j] - vel_[i];
        const double vn = vrel.dot(nrm);
        const double vs = vrel.dot(t) - (omega_[i] * ra + omega_[j] * rb);
        const Vec2 prel = vel_centre_[j] - vel_centre_[i];
        const double pn = prel.dot(nrm);
        const double ps = prel.dot(t) - (omega_centre_[i] * ra + omega_centre_[j] * rb);
        const PairMaterial& pm = pp.materials[size_t(material_[i]) * pp.n_materials + size_t(material_[j])];
        const double inv_mn = inv_mass_[i] + inv_mass_[j];
        const double inv_ms = rotation_free ? inv_mn + ra * ra * inv_inertia_[i] + rb * rb * inv_inertia_[j] : inv_mn;
        const double fn_spring = pm.kn * overlap;
        const bool sliding = std::abs(c.fs) >= pm.mu * fn_spring;
        const DashpotShift sn = normal_shift(c.cn, vn, pn, c.cn * dt * inv_mn, fn_spring, no_tension);
        const DashpotShift ss = shear_shift(c.cs, vs, ps, c.cs * dt * inv_ms, no_shear_sliding && sliding);
        const double dn = sn.d_new - sn.d_old, ds = ss.d_new - ss.d_old;
        // the law booked this step's force over the first half of the velocity interval
        const double dissipated = -h * (dn * vn + ds * vs);
        c.damp_n = float(sn.d_new);
        c.damp_s = float(ss.d_new);
        const Vec2 f = dn * nrm + ds * t;  // on j
        DiscLoad& li = load_[i];
        DiscLoad& lj = load_[j];
        li.force -= f;
        lj.force += f;
        li.torque += -ra * ds;
        lj.torque += -rb * ds;
        li.dissipated += 0.5 * dissipated;
        lj.dissipated += 0.5 * dissipated;
    }
    // The cross contacts' own copies (force_pass.cpp) keep the histories the next pass reads:
    // their dashpot forces, which the ledger books over the next step's first half, too.
    if (!cross_copies_stale_)
        for (size_t m = 0; m < cross_.size(); ++m) {
            const DiscContact& c = dd_[size_t(cross_[m])];
            DiscContact& copy = cross_dd_[size_t(cross_pos_[m])];
            copy.damp_n = c.damp_n;
            copy.damp_s = c.damp_s;
        }
    // The wall contacts, range by range, with their records (WallSum: one per touching
    // contact, in list order, among those of open contacts that still dissipate).
    const size_t nw = walls_.size();
    for (size_t tr = 0; tr < wall_sums_.size(); ++tr) {
        WallSum* const sums = wall_sums_[tr].data();
        const size_t n_sums = range_clock_[tr].wall_sums;
        size_t e = 0;
        for (size_t kw = wall_split_[tr]; kw < wall_split_[tr + 1]; ++kw) {
            WallContact& c = dw_[kw];
            const size_t i = size_t(c.disc), w = size_t(c.wall);
            WallHit hit;
            if (!wall_active_[w] || !disc_wall_contact(geom_[w], pos_[i], radius_[i], hit)) continue;
            while (e < n_sums && sums[e].wall < 0) ++e;
            if (e == n_sums || sums[e].disc != int32_t(i) || sums[e].wall != int32_t(w))
                throw RunError("internal: a wall contact's record is missing (centred dashpots)");
            WallSum& rec = sums[e++];
            const Vec2 vwall = wall_moving_[w] ? walls_[w].velocity : Vec2::Zero();
            const Vec2 nrm = hit.normal;
            const Vec2 t = perp(nrm);
            const double rb = radius_[i] - 0.5 * hit.overlap;
            const Vec2 vrel = vel_[i] - vwall;
            const double vn = vrel.dot(nrm);
            const double vs = vrel.dot(t) - omega_[i] * rb;
            const Vec2 prel = vel_centre_[i] - vwall;
            const double pn = prel.dot(nrm);
            const double ps = prel.dot(t) - omega_centre_[i] * rb;
            const PairMaterial& pm = table.disc_wall[size_t(material_[i]) * nw + w];
            const double inv_mn = inv_mass_[i];
            const double inv_ms = rotation_free ? inv_mn + rb * rb * inv_inertia_[i] : inv_mn;
            const double fn_spring = pm.kn * hit.overlap;
            const bool sliding = std::abs(c.fs) >= pm.mu * fn_spring;
            const DashpotShift sn = normal_shift(c.cn, vn, pn, c.cn * dt * inv_mn, fn_spring, no_tension);
            const DashpotShift ss = shear_shift(c.cs, vs, ps, c.cs * dt * inv_ms, no_shear_sliding && sliding);
            const double dn = sn.d_new - sn.d_old, ds = ss.d_new - ss.d_old;
            c.damp_n = float(sn.d_new);
            c.damp_s = float(ss.d_new);
            const Vec2 f = dn * nrm + ds * t;  // on the disc
            DiscLoad& l = load_[i];
            l.force += f;
            l.torque += -rb * ds;
            rec.fx += f.x();
            rec.fy += f.y();
            rec.moment += cross(pos_[i] - rb * nrm, f);
            rec.dissipated += -h * (dn * vn + ds * vs);
        }
    }
}

// Every range's discs integrated, block by block as the fused pass does (the same chunks, so
// the same ledger blocks and notes), after centre_dashpots.
void World::integrate_ranges(const IntegrateConsts& ic) {
    const bool avx2 = avx2_integration();
    auto range = [&](int t) {
        const size_t tr = size_t(t);
        range_clock_[tr].touching_dd = 0;
        size_t b0 = disc_split_[tr];
        for (size_t fbi = fuse_start_[tr]; fbi < fuse_start_[tr + 1]; ++fbi) {
            const size_t b1 = fuse_blocks_[fbi].disc_end;
            if (!avx2) block_ledger(b0, b1, tr);
            integrate_discs(b0, b1, t, ic);
            b0 = b1;
        }
    };
    if (force_ranges_ == 1)
        range(0);
    else
        pool_->for_each_thread(range);
}

}  // namespace demlab
