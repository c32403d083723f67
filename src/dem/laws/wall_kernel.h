// The disc-wall force kernel: one candidate contact of a disc with a wall, one step of the
// contact law (a law of contact_laws.h), as a small function over the disc's state and the contact's
// history; the counterpart of disc_pair_force (pair_kernel.h) for walls. The normal points
// from the wall (A) to the disc (B); a wall is of infinite mass and moves at a given velocity.
#pragma once
#include <cstdint>

#include "dem/laws/linear_law.h"
#include "geometry/wall.h"

namespace demlab {

// A disc-wall contact candidate and its history (LinearLaw's fields).
struct WallContact {
    int32_t disc, wall;
    double fs, cn, cs;
    float damp_n, damp_s;
};

// What one disc-wall contact gives in a step.
struct WallOut {
    Vec2 force{0.0, 0.0};  // N/m, on the disc (the wall gets the opposite)
    Vec2 point{0.0, 0.0};  // m, the contact point (for the wall's moment)
    double torque = 0.0;   // N m/m, on the disc
    double dissipated = 0.0;  // J/m, this step (an open contact: its last dashpot force's second half)
    double fn_spring = 0.0;   // N/m, the elastic normal force (rolling resistance, eq. 2.71)
    double k_tran = 0.0, k_rot = 0.0;  // N/m, for the automatic step
    bool touching = false;
};

// Contact c of a disc (pos, vel, omega, radius) with wall geometry g, which is present
// (active) and moves at vwall. Returns false, with `overlap` set, when the overlap exceeds
// max_ratio of the radius: a blown-up run, which the caller reports.
template <typename Law = LinearLaw>
[[gnu::always_inline]] inline bool disc_wall_force(const WallGeom& g, bool active, const Vec2& vwall, const Vec2& pos,
                                                   const Vec2& vel, double omega, double radius,
                                                   const typename Law::Params& pm,
                                                   DashpotMode mode, double dt, double last_dt, double max_ratio,
                                                   WallContact& c, WallOut& out, double& overlap,
                                                   const Vec2& gravity = Vec2::Zero()) {
    WallHit hit;
    if (!active || !disc_wall_contact(g, pos, radius, hit)) {
        out.touching = false;
        out.dissipated = 0.0;
        if (Law::open_work_due(c)) {
            // along the normal it had
            const Vec2 vrel = vel - vwall;
            const Vec2 q = closest_point(g, pos);
            const Vec2 nrm = (pos - q).normalized();
            const double vs = vrel.dot(perp(nrm)) - omega * radius;
            out.dissipated = Law::open_work(c, vrel.dot(nrm), vs, last_dt);
        }
        Law::clear_history(c);
        if constexpr (Law::kStepAhead) {
            if (active) {
                const Vec2 q = closest_point(g, pos);
                const double dist = (pos - q).norm();
                // towards the wall at the speed one step of gravity gives (a disc at rest on it
                // would otherwise see nothing coming)
                if (dist > 0.0) {
                    const Vec2 nrm = (pos - q) / dist;
                    out.k_tran = Law::k_ahead(pm, dist - radius, (vel - vwall + dt * gravity).dot(nrm), dt, radius, 0.0);
                }
            }
        }
        return true;
    }
    overlap = hit.overlap;
    if (!(hit.overlap <= max_ratio * radius)) return false;
    const Vec2 nrm = hit.normal;
    const Vec2 tan = perp(nrm);
    // PFC's contact point on the disc's side: the lever arm r - U/2
    const double rb = radius - 0.5 * hit.overlap;
    const Vec2 vrel = vel - vwall;
    const double vn = vrel.dot(nrm);
    const double vs = vrel.dot(tan) - omega * rb;
    const auto f = Law::step(pm, mode, hit.overlap, vn, vs, dt, last_dt, c, out.dissipated, radius, 0.0);
    out.force = f.fn * nrm + f.ft * tan;
    out.point = pos - rb * nrm;
    out.torque = -rb * f.ft;
    out.fn_spring = f.fn_spring;
    out.k_tran = Law::k_tran(pm, f);
    out.k_rot = Law::k_rot(pm, f);
    out.touching = true;
    return true;
}

// The energy a touching disc-wall contact stores, J/m (0 when it does not touch).
template <typename Law = LinearLaw>
inline double wall_contact_elastic_energy(const WallGeom& g, const Vec2& pos, double radius,
                                          const typename Law::Params& pm, const WallContact& c) {
    WallHit hit;
    if (!disc_wall_contact(g, pos, radius, hit)) return 0.0;
    return Law::elastic_energy(pm, hit.overlap, c, radius, 0.0);
}

}  // namespace demlab
