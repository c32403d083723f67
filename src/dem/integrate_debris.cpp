// The integration of DEBRIS discs (debris_law.h; DEBRIS.md sec. 4.2): translation only, and
// one friction force per disc against its own velocity (Mikhailov's force 4, D4):
//   F_fr = -[mu (N + P) + eta |v|] v/|v|, only while the disc touches something,
//   N = |sum of the bed reactions|, P = |sum of the pair forces| (friction_normal "resultant";
//   "sum": the sums of their moduli).
// "trial" (the default): v* = v(n-1/2) + dt (F/m + g), J = dt mu (N + P)/m; static friction
// holds the disc (v = 0) when |v*| <= J, else v = v*/|v*| (|v*| - J)/(1 + dt eta/m): the
// Coulomb part explicit, the viscous part implicit, never reversing the velocity (AvaFrame's
// account4FrictionForce stops a particle the same way). "previous": the friction against
// v(n-1/2), explicitly (Mikhailov literally; it jitters at rest and creeps on slopes).
// The friction impulse I = m (v(n+1/2) - v*) works over the mean velocity of the step,
// I . (v(n-1/2) + v(n+1/2))/2: that work, negated, is booked as the contacts' dissipation.
#include <algorithm>
#include <cmath>

#include "dem/laws/debris_law.h"
#include "dem/world.h"

namespace demlab {

void World::integrate_discs_debris(size_t begin, size_t end, int chunk, const IntegrateConsts& k) {
    const double dt = k.dt;
    // The step varies from one step to the next (an impact shrinks it tenfold and lets it grow
    // again), and a force at x_n acts from t_n - dt_(n-1)/2 to t_n + dt_n/2: its impulse is
    // h = (dt_(n-1) + dt_n)/2 times it (variable-step Stormer-Verlet). With dt_n alone, as for
    // the linear law, a contact left while the step grows gained energy: e = 1.03 for an
    // undamped wall impact at safety 0.8, 1.007 still at 0.1. The first step: v is given at
    // -dt/2 (PFC's convention), h = dt.
    const double h = last_dt_ > 0.0 ? 0.5 * (last_dt_ + dt) : dt;
    const Vec2 g = k.g;
    const DebrisDef& dd = def_.law_def<DebrisLaw>();
    const bool resultant = dd.friction_normal == DebrisNormal::Resultant;
    const bool trial = dd.friction_direction == DebrisDirection::Trial;
    Vec2* const pos = pos_.data();
    Vec2* const vel = vel_.data();
    const double* const mass = mass_.data();
    const double* const inv_mass = inv_mass_.data();
    const double* const radius = radius_.data();
    const DiscLoad* const load = load_.data();
    const Vec2* const wall_reaction = wall_reaction_.data();
    LedgerBlock* const ledger_blocks = ledger_blocks_.data();
    const Vec2* const fat_lo = broad_.fat_lo_data();
    const Vec2* const fat_hi = broad_.fat_hi_data();
    const Vec2 lo = def_.domain_lo, hi = def_.domain_hi;
    double best_sq = INFINITY;
    bool any_escaped = false;
    size_t fault = SIZE_MAX;
    double speed_l1 = 0.0, extent_l1 = 0.0;
    double block_friction = 0.0;
    double kinetic_lanes[4] = {0.0, 0.0, 0.0, 0.0};
    for (size_t i = begin; i < end; ++i) {
        const DiscLoad& l = load[i];
        // the automatic step from the tangent stiffness one step ahead (D12); no contact:
        // debris.dt_max (step_from_critical_squared)
        if (k.auto_dt && l.k_tran > 0.0) best_sq = std::min(best_sq, mass[i] / l.k_tran);
        const Vec2 v_old = vel[i];
        const Vec2 v_star = v_old + (l.force + mass[i] * g) * (inv_mass[i] * h);
        Vec2 v_new = v_star;
        if (l.n_wall + l.n_disc > 0) {
            // N and P: the bed's and the pairs' parts of the contact force (debris_law.h: the
            // pairs' moduli are summed in k_rot, the walls' in wall_normal)
            // (a disc off the walls, most of them, skips the walls' square root: its sum is 0)
            const double normal = resultant ? (l.n_wall > 0 ? wall_reaction[i].norm() : 0.0) + (l.force - wall_reaction[i]).norm()
                                            : l.wall_normal + l.k_rot;
            if (trial) {
                v_new = debris::friction_trial(v_star, h * dd.mu * normal * inv_mass[i], h * dd.eta * inv_mass[i]);
            } else {
                const double speed = v_old.norm();
                if (speed > 0.0) v_new = v_star - (h * inv_mass[i] * (dd.mu * normal + dd.eta * speed) / speed) * v_old;
            }
            // the friction impulse's work over the step's mean velocity (centred, as a dashpot's)
            block_friction -= 0.5 * mass[i] * (v_new - v_star).dot(v_old + v_new);
        }
        vel[i] = v_new;
        const Vec2 p = pos[i] + v_new * dt;
        pos[i] = p;
        speed_l1 = std::max(speed_l1, std::abs(v_new.x()) + std::abs(v_new.y()));
        extent_l1 = std::max(extent_l1, std::abs(p.x()) + std::abs(p.y()));
        kinetic_lanes[i % 4] += (0.5 * mass[i]) * (v_new.x() * v_new.x() + v_new.y() * v_new.y());
        if ((i + 1) % kLedgerBlock == 0 || i + 1 == end) {
            LedgerBlock& b = ledger_blocks[i / kLedgerBlock];
            b.contacts += block_friction;  // after block_ledger's (zero) contact terms
            b.local = 0.0;
            b.rotation = 0.0;
            b.kinetic = (kinetic_lanes[0] + kinetic_lanes[1]) + (kinetic_lanes[2] + kinetic_lanes[3]);
            block_friction = 0.0;
            kinetic_lanes[0] = kinetic_lanes[1] = kinetic_lanes[2] = kinetic_lanes[3] = 0.0;
        }
        const bool inside = (int(p.x() >= lo.x()) & int(p.x() <= hi.x()) & int(p.y() >= lo.y()) & int(p.y() <= hi.y())) != 0;
        if (!inside && fault == SIZE_MAX) fault = i;
        const double r = radius[i];
        any_escaped = any_escaped || !(fat_lo[i].x() <= p.x() - r && fat_lo[i].y() <= p.y() - r &&
                                       p.x() + r <= fat_hi[i].x() && p.y() + r <= fat_hi[i].y());
    }
    integrate_note(chunk, fault, k.auto_dt ? best_sq : INFINITY, any_escaped, speed_l1, extent_l1);
}

}  // namespace demlab
