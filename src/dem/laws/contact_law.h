// The PFC "linear model" with viscous dashpots (thesis section 2.3.4-2.3.5, eq. 2.44-2.62),
// as a small stateless function over a parameter struct and the contact's kinematics.
//
// Frame: the unit normal n points from body A to body B, t = perp(n) (n turned +90 deg).
// All forces returned are the forces ON B; A receives the opposite. vn and vs are B's
// velocity relative to A at the contact point along n and t (vn > 0: separating).
#pragma once
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>

namespace demlab {

// PFC's dashpot modes (dp_mode): whether the normal dashpot may make the total normal force
// tensile, and whether the shear dashpot stays active while the contact slides.
enum class DashpotMode : int {
    Full = 0,                        // PFC default: both dashpots always active
    NoTension = 1,                   // total normal force kept >= 0
    NoShearWhileSliding = 2,         // shear dashpot off while sliding
    NoTensionNoShearWhileSliding = 3 // both of the above
};

// Parameters of one contact. Stiffnesses are already the series values (eq. 2.59, 2.61).
struct LinearContactParams {
    double kn = 0.0;   // normal stiffness, N/m
    double ks = 0.0;   // shear stiffness, N/m
    double mu = 0.0;   // Coulomb friction coefficient, -
    double cn = 0.0;   // normal dashpot coefficient, N s/m: beta_n * 2 sqrt(m_eff kn) (eq. 2.56-2.57)
    double cs = 0.0;   // shear dashpot coefficient, N s/m: beta_s * 2 sqrt(m_eff ks)
    DashpotMode mode = DashpotMode::Full;
    double inv_ks = 0.0;  // 1 / ks, m/N (for the slip work; a division per contact costs the
                          // force pass 10 %, so the force passes take it per material pair)

    LinearContactParams() = default;
    LinearContactParams(double kn_, double ks_, double mu_, double cn_, double cs_, DashpotMode mode_)
        : LinearContactParams(kn_, ks_, mu_, cn_, cs_, mode_, 1.0 / ks_) {}
    LinearContactParams(double kn_, double ks_, double mu_, double cn_, double cs_, DashpotMode mode_, double inv_ks_)
        : kn(kn_), ks(ks_), mu(mu_), cn(cn_), cs(cs_), mode(mode_), inv_ks(inv_ks_) {}
};

// Result of one evaluation; the caller stores fs_spring as the contact's shear history.
struct LinearContactForce {
    double fn = 0.0;         // total normal force on B along n (spring + dashpot), N
    double ft = 0.0;         // total tangential force on B along t (spring + dashpot), N
    double fs_spring = 0.0;  // updated shear spring force (history), N
    double fn_spring = 0.0;  // elastic normal force kn*U, N
    double damp_n = 0.0;     // normal dashpot force on B, N (for the energy ledger)
    double damp_s = 0.0;     // shear dashpot force on B, N
    double slip_work = 0.0;  // energy dissipated by sliding in this step, J
    bool sliding = false;
};

// c ? a : b without a branch (the bits of a or b exactly). The dashpot modes' conditions
// (tension, sliding) flip from step to step in a flow, and as branches they were mispredicted
// often enough to show in perf (docs/performance.md).
inline double select(bool c, double a, double b) {
    const uint64_t m = uint64_t(0) - uint64_t(c);
    return std::bit_cast<double>((std::bit_cast<uint64_t>(a) & m) | (std::bit_cast<uint64_t>(b) & ~m));
}

// Critical damping coefficient scaled by beta (eq. 2.56-2.57): c = beta * 2 sqrt(m k).
inline double dashpot_coefficient(double beta, double m_eff, double k) { return beta * 2.0 * std::sqrt(m_eff * k); }

// One step of the linear law for a contact with overlap U > 0.
//   F_n = kn U                         (eq. 2.45, secant: from the overlap)
//   dF_s = -ks vs dt, F_s += dF_s      (eq. 2.48-2.49, incremental; the scalar history is
//                                       measured along the current t, so it turns with the
//                                       contact plane exactly)
//   |F_s| <= mu F_n                    (eq. 2.50, on the spring part only)
//   D_n = -cn vn, D_s = -cs vs          (eq. 2.55, added on top of the springs)
inline LinearContactForce linear_contact(const LinearContactParams& p, double overlap, double vn, double vs,
                                         double dt, double fs_old) {
    LinearContactForce out;
    const double fn_spring = p.kn * overlap;
    const double fn_free = fn_spring + -p.cn * vn;
    // dp_mode 1, 3: no tension; the dashpot then cancels the spring exactly
    const bool no_tension = p.mode == DashpotMode::NoTension || p.mode == DashpotMode::NoTensionNoShearWhileSliding;
    const bool cut_tension = no_tension && fn_free < 0.0;
    const double fn = select(cut_tension, 0.0, fn_free);
    const double fn_damp = select(cut_tension, -fn_spring, -p.cn * vn);

    const double fs_trial = fs_old - p.ks * vs * dt;
    const double fs_max = p.mu * fn_spring;
    // the Coulomb cap as a clamp, without a branch: about a third of a collapsing column's
    // contacts change between sticking and sliding from one step to the next, and a branch
    // on it was mispredicted every third time (cachegrind, docs/performance.md)
    const double excess = std::abs(fs_trial) - fs_max;
    out.sliding = excess > 0.0;
    const double fs = std::min(std::max(fs_trial, -fs_max), fs_max);
    // energy lost by the slider: the capped force times the slip it let through
    const double slip_work = fs_max * std::max(excess, 0.0) * p.inv_ks;
    // dp_mode 2, 3: no shear dashpot while sliding
    const bool no_shear_dashpot_sliding =
        p.mode == DashpotMode::NoShearWhileSliding || p.mode == DashpotMode::NoTensionNoShearWhileSliding;
    const double fs_damp = select(out.sliding && no_shear_dashpot_sliding, 0.0, -p.cs * vs);

    out.fn = fn;
    out.ft = fs + fs_damp;
    out.fs_spring = fs;
    out.fn_spring = fn_spring;
    out.damp_n = fn_damp;
    out.damp_s = fs_damp;
    out.slip_work = slip_work;
    return out;
}

}  // namespace demlab
