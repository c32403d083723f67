// DEBRIS (Mikhailov 2010; docs/debris.md, DEBRIS.md): equal discs that do not rotate, an
// elastic normal force scaled by Young's modulus and the geometric contact area, and one
// friction force per disc against its own velocity (integrate.cpp, debris_friction).
//
// 2-D, per metre of thickness t = 1 m (the disc a cylinder lying on the bed, cut by the bed in
// a rectangle 2a x t where a sphere is cut in a circle pi a^2):
//   bed  (D2): delta = R - d > 0,  F = E S delta / R,            S = 2a, a^2 = R^2 - d^2
//   pair (D3): delta = Ri + Rj - d, F = E S delta / (Ri + Rj),   S = 2a, a = half the common chord
//   "diameter" (comparison only): S = 2R (bed), 2 min(Ri, Rj) (pair): linear springs
//   energy (D8): U = int_0^delta F, by 8-point Gauss-Legendre in w = sqrt(delta) (the
//   integrand is smooth in w; no cancellation at small overlaps)
//   tangent stiffness (D12): dF/d delta, closed form, at the overlap 2.5 steps ahead, also of a
//   pair or wall not touching yet but closing in (kStepAhead): impacts set the step
// No tangential force, no history, no dissipation at the contacts: the friction is the disc's
// (D4), applied by the integrator from the two sums of its contacts' forces: the walls'
// (WorldDef::debris, World::wall_reaction_) and the discs' (the rest of the contact force).
#pragma once
#include <algorithm>
#include <array>
#include <cmath>
#include <string>

#include "dem/laws/contact_law.h"
#include "dem/laws/law_part.h"
#include "dem/laws/linear_law.h"
#include "dem/material.h"
#include "core/error.h"
#include "core/validate.h"
#include "geometry/wall.h"

namespace demlab {

enum class DebrisArea { Chord, Diameter };
enum class DebrisNormal { Resultant, Sum };       // |sum F| or sum |F| (D4; DEBRIS.md sec. 7 item 3)
enum class DebrisDirection { Trial, Previous };   // friction against v* or v(n-1/2) (sec. 4.2)

struct DebrisDef {
    double youngs_modulus = 4e10;  // Pa, E (Mikhailov, Attabad: 40 GPa)
    double mu = 0.3;               // -, dry friction coefficient in [0, 1]
    double eta = 0.0;              // N s/m per metre of thickness, viscous friction
    DebrisArea contact_area = DebrisArea::Chord;
    DebrisNormal friction_normal = DebrisNormal::Resultant;
    DebrisDirection friction_direction = DebrisDirection::Trial;
    double dt_max = 0.01;          // s, the automatic step's ceiling (Mikhailov's step)
};

// The force of a contact and its tangent stiffness (pair or bed; rj = 0 for a bed).
struct DebrisContactForce {
    double fn = 0.0;         // N/m, repulsive, along n
    double ft = 0.0;         // always 0 (no tangential force)
    double fn_spring = 0.0;  // = fn
    double k = 0.0;          // N/m, dF/d delta at the overlap one step ahead (D12)
    double pair_force = 0.0; // N/m, fn of a disc pair, 0 of a wall ("sum": P, the pairs' moduli)
};

namespace debris {

// a^2 of the contact for overlap delta: bed a^2 = delta (2R - delta); pair, with
// d = Ri + Rj - delta and x the distance of the chord from i's centre,
// a^2 = Ri^2 - x^2 = delta (Rj + d - Ri)(Ri + x) / (2 d) (written so: no cancellation)
// (one division: both quotients by 2d share its reciprocal)
inline double half_width_sq(double delta, double ri, double rj) {
    if (rj <= 0.0) return std::max(delta * (2.0 * ri - delta), 0.0);
    const double d = ri + rj - delta;
    const double inv_2d = 0.5 / d;
    const double x = (d * d + ri * ri - rj * rj) * inv_2d;
    return std::max(delta * (rj + d - ri) * (ri + x) * inv_2d, 0.0);
}

// F(delta), N/m (t = 1 m)
inline double force(double E, DebrisArea area, double delta, double ri, double rj) {
    if (!(delta > 0.0)) return 0.0;
    const double rsum = rj > 0.0 ? ri + rj : ri;
    if (area == DebrisArea::Diameter) return E * 2.0 * (rj > 0.0 ? std::min(ri, rj) : ri) * delta / rsum;
    return E * 2.0 * std::sqrt(half_width_sq(delta, ri, rj)) * delta / rsum;
}

// dF/d delta, N/m per m. Bed: F = (2E/R) a delta, a^2 = delta q with q = 2R - delta, da/d delta
// = d/a; pair: F = 2E a delta/(Ri + Rj), a^2 = delta q with q = (Rj + d - Ri)(Ri + x)/(2d),
// da/d delta = x (1 - x/d)/a. The term delta da/d delta = (delta/a) c, with c = d (bed) or
// x (1 - x/d) (pair), is written with delta/a = a/q, finite as delta -> 0 (where the form
// tends to Hertz's D7, k = 3 E sqrt(2 R* delta)/(Ri + Rj)):
//   k = 2E (a + a c/q)/(Ri + Rj) = 2E a (q + c)/(q (Ri + Rj)),
// one square root and one division (two for a pair, with 1/(2d)), as force() takes: the step
// needs it for every contact in every step.
// The chord's terms of a^2 = delta q, with c = a da/d delta (so delta dq/d delta = 2c - q):
// bed q = 2R - delta, c = R - delta; pair q as half_width_sq's, c = x (1 - x/d). The same in
// 2-D and 3-D: the section's half-width a is the same.
inline void chord_terms(double delta, double ri, double rj, double& q, double& c) {
    if (rj <= 0.0) {
        q = 2.0 * ri - delta;
        c = ri - delta;
    } else {
        const double d = ri + rj - delta;
        const double inv_2d = 0.5 / d;
        const double x = (d * d + ri * ri - rj * rj) * inv_2d;
        q = (rj + d - ri) * (ri + x) * inv_2d;
        c = x * (1.0 - 2.0 * x * inv_2d);
    }
}

inline double stiffness(double E, DebrisArea area, double delta, double ri, double rj) {
    const double rsum = rj > 0.0 ? ri + rj : ri;
    if (area == DebrisArea::Diameter) return E * 2.0 * (rj > 0.0 ? std::min(ri, rj) : ri) / rsum;
    if (!(delta > 0.0)) return 0.0;
    double q, c;
    chord_terms(delta, ri, rj, q, c);
    const double a = std::sqrt(delta * q);
    return 2.0 * E * a * (q + c) / (q * rsum);
}

// U(delta) = int_0^delta F: 8-point Gauss-Legendre over w in [0, sqrt(delta)], F(w^2) 2w dw
template <typename Force>
double gauss_energy(Force force_at, double delta) {
    if (!(delta > 0.0)) return 0.0;
    static constexpr std::array<double, 4> x = {0.1834346424956498, 0.5255324099163290, 0.7966664774136267,
                                                0.9602898564975363};
    static constexpr std::array<double, 4> wt = {0.3626837833783620, 0.3137066458778873, 0.2223810344533745,
                                                 0.1012285362903763};
    const double h = 0.5 * std::sqrt(delta);
    double u = 0.0;
    for (size_t k = 0; k < 4; ++k)
        for (const double sgn : {-1.0, 1.0}) {
            const double w = h * (1.0 + sgn * x[k]);
            u += wt[k] * force_at(w * w) * 2.0 * w;
        }
    return h * u;
}

// J/m (t = 1 m)
inline double energy(double E, DebrisArea area, double delta, double ri, double rj) {
    return gauss_energy([&](double s) { return force(E, area, s, ri, rj); }, delta);
}

// --- the 3-D forms (DEBRIS.md D1-D3: spheres, S = pi a^2), for the 3-D solver (src/dem3/)

// N: F = E pi a^2 delta / (Ri + Rj) (bed: / R)
inline double sphere_force(double E, double delta, double ri, double rj) {
    if (!(delta > 0.0)) return 0.0;
    const double rsum = rj > 0.0 ? ri + rj : ri;
    return E * kPi * half_width_sq(delta, ri, rj) * delta / rsum;
}

// N/m: dF/d delta = E pi (a^2 + delta d(a^2)/d delta)/(Ri + Rj) = E pi delta (q + 2c)/(Ri + Rj)
// (a^2 = delta q, d(a^2)/d delta = 2c); bed E pi delta (4R - 3 delta)/R. It vanishes at first
// touch (Hertz's exponent: F ~ delta^2 in 3-D), so the step is set by the overlap ahead.
inline double sphere_stiffness(double E, double delta, double ri, double rj) {
    if (!(delta > 0.0)) return 0.0;
    const double rsum = rj > 0.0 ? ri + rj : ri;
    double q, c;
    chord_terms(delta, ri, rj, q, c);
    return E * kPi * delta * (q + 2.0 * c) / rsum;
}

// J: int_0^delta F. The bed's and an equal pair's in closed form (a^2 is a polynomial in delta:
// bed E pi (2R delta^3/3 - delta^4/4)/R, equal pair E pi (R delta^3/3 - delta^4/16)/(2R)),
// an unequal pair's by the quadrature: the ledger takes it for every contact in every step.
inline double sphere_energy(double E, double delta, double ri, double rj) {
    if (!(delta > 0.0)) return 0.0;
    const double d3 = delta * delta * delta;
    if (rj <= 0.0) return E * kPi * (2.0 * ri * d3 / 3.0 - d3 * delta / 4.0) / ri;
    if (ri == rj) return E * kPi * (ri * d3 / 3.0 - d3 * delta / 16.0) / (2.0 * ri);
    return gauss_energy([&](double s) { return sphere_force(E, s, ri, rj); }, delta);
}

// The disc's or sphere's friction, "trial" (DEBRIS.md sec. 4.2): the velocity after the other
// forces, v*, slowed by the Coulomb impulse j (m/s) explicitly and the viscous part
// implicitly (h_eta_m = h eta / m), never reversed; static friction holds it at rest when
// |v*| <= j. Vec2 or Vec3.
template <typename V>
V friction_trial(const V& v_star, double j, double h_eta_m) {
    const double speed = v_star.norm();
    // one division: (speed - j)/speed/(1 + h eta/m), the same bits when eta = 0
    return speed <= j ? V(V::Zero()) : V(v_star * ((speed - j) / (speed * (1.0 + h_eta_m))));
}

}  // namespace debris

struct DebrisLaw : LawDefaults {
    struct Params {
        double E = 0.0;  // Pa
        DebrisArea area = DebrisArea::Chord;
    };
    using Def = DebrisDef;
    static constexpr const char* kName = "debris";
    static constexpr const char* kSummary =  // contact.law's text
        "Mikhailov's DEBRIS: elastic force from Young's modulus and the contact's chord, one friction force per disc; [debris], docs/debris.md";
    static constexpr const char* kSection = "debris";
    template <typename Add>
    static void keys(Add& add) {
        add.real("youngs_modulus", "Pa", "E of the discs and of the bed (Mikhailov, Attabad: 40 GPa): F = E S delta / R (bed), E S delta / (Ri + Rj) (pair)", &Def::youngs_modulus, 0, 1e12, true);
        add.real("mu", "-", "dry friction coefficient of a disc's friction force mu (N + P) against its velocity (Attabad: 0.3); < 1 lets an impact rebound", &Def::mu, 0, 1);
        add.real("eta", "N s/m", "viscous friction eta v, per metre of thickness (Attabad: 0); a sphere's eta_3D maps to eta_3D 3t/(4R)", &Def::eta, 0, 1e12);
        add.choice("contact_area", "S of the elastic force: chord (2a t, the geometric section: grows with the overlap) or diameter (2R t: linear springs, for comparison)", &Def::contact_area, {{"chord", DebrisArea::Chord}, {"diameter", DebrisArea::Diameter}});
        add.choice("friction_normal", "N and P of the friction: resultant (the moduli of the summed bed and pair forces, Mikhailov's \"modulus of the total elastic force\") or sum (the sums of their moduli)", &Def::friction_normal, {{"resultant", DebrisNormal::Resultant}, {"sum", DebrisNormal::Sum}});
        add.choice("friction_direction", "the friction against the velocity after the other forces (trial: static friction holds a disc at rest) or the last step's (previous: Mikhailov literally; jitters at rest)", &Def::friction_direction, {{"trial", DebrisDirection::Trial}, {"previous", DebrisDirection::Previous}});
        add.real("dt_max", "s", "the automatic step's ceiling, and the step of a disc without contacts (Mikhailov's 0.01 s)", &Def::dt_max, 0, 1, true);
    }
    // the linear law's keys, which DEBRIS does not read
    static constexpr std::array<const char*, 8> kUnusedKeys{"damping.", "material.kn", "material.ks", "material.wall_kn",
                                                           "material.wall_ks", "material.friction_", "rotation.u_rr",
                                                           "rotation.mu_br"};
    static constexpr const char* kUnusedWhy =
        "its elastic force comes from debris.youngs_modulus, its friction from debris.mu and debris.eta";
    template <typename WorldDefT>
    static void validate(const Def& b, const WorldDefT& d) {
        if (!(b.youngs_modulus > 0.0 && b.youngs_modulus <= 1e12))
            throw InputError("debris.youngs_modulus = " + format_number(b.youngs_modulus) + " Pa: must be in (0, 1e12]");
        require_range("debris.mu", b.mu, 0.0, 1.0, false, "(coefficient)");
        require_range("debris.eta", b.eta, 0.0, 1e12, false, "N s/m");
        if (!(b.dt_max > 0.0 && b.dt_max <= 1.0))
            throw InputError("debris.dt_max = " + format_number(b.dt_max) + " s: must be in (0, 1]");
        // Mikhailov's particles do not rotate: the law has no torque to turn them
        if (d.rotation.model != 1)
            throw InputError("rotation.model = " + std::to_string(d.rotation.model) +
                             ": contact.law = \"debris\" needs rotation.model = 1 (DEBRIS's discs do not rotate)");
    }
    // one modulus for every contact, the walls' too (Mikhailov: "E of particle i")
    template <typename Tables>
    static void fill_tables(Tables& t, const Def& b) {
        for (auto* table : {&t.disc_disc, &t.disc_wall})
            for (Params& p : *table) p = {b.youngs_modulus, b.contact_area};
    }
    static constexpr bool kTranslationOnly = true;  // no dashpots, rotation locked
    // its closing contacts look one step of the ceiling ahead; nothing else in its pass
    // depends on the step
    static double first_dt(const Def& b) { return b.dt_max; }
    // the rule capped by debris.dt_max, which a disc without contacts takes (D12), shrinking at
    // once and growing slowly (kStepGrowth)
    static double step_from_rule(const Def& b, double safety, double, double best_sq, double last_dt) {
        return capped_growing_step(b.dt_max, kStepGrowth, safety, best_sq, last_dt);
    }
    static constexpr bool kWideKernels = false;  // the scalar kernels only (no AVX2 / AVX-512 form yet)
    static constexpr bool kDiscFriction = true;  // friction per disc, by the integrator
    static constexpr bool kStepAhead = true;     // open contacts closing in count for the step (D12)
    // The ledger's elastic energy at the kinetic energy's time level, t - dt/2 (World::energy).
    static constexpr bool kElasticAtHalfStep = true;

    // How fast the automatic step may grow, a factor a step (it shrinks at once). A step that
    // follows the stiffness of the moment rises and falls with every oscillation of a contact,
    // and a step that varies with the state breaks the leapfrog's symplectic structure: an
    // undamped pile of 30 discs ringing on the floor gained 42 % of its energy in 100,000 steps
    // at safety 0.8 with a growth of 1.5 (2.2 % at 1.05; a fixed step of the same mean size,
    // 4.3e-4 s: 1.9 %); the box gas of Debris.ConservesEnergy drifted 4.2 % (0.5 % at
    // 1.05). The Attabad section takes 2.4 % more steps at 1.05.
    static constexpr double kStepGrowth = 1.05;
    // The tangent stiffness of an open contact that may touch by the end of the next step (0
    // otherwise): a disc falling at 40 m/s onto the bed with the 0.01 s ceiling would otherwise
    // go 0.4 m into it in its first step of contact. The pass at x_n sets the step after this
    // one, which moves from x_(n+1) to x_(n+2): dt_n + dt_(n+1) <= (1 + kStepGrowth) dt_n ahead
    // (World::step_from_critical_squared); 2.5 looks a little further.
    static constexpr double kAheadSteps = 2.5;
    static_assert(kAheadSteps >= 1.0 + kStepGrowth);
    static double k_ahead(const Params& p, double gap, double vn, double dt, double ri, double rj) {
        const double ahead = -gap + kAheadSteps * dt * std::max(0.0, -vn);
        return ahead > 0.0 ? stiffness_at(p, ahead, ri, rj) : 0.0;
    }
    // the same for an open pair from its squared distance (law_part.h)
    static double pair_k_ahead(const Params& p, double dist2, double rsum, const Vec2& dx, const Vec2& vrel, double dt,
                               double ri, double rj) {
        return closing_pair_stiffness<DebrisLaw>(p, dist2, rsum, dx, vrel, dt, ri, rj);
    }
    // the tangent stiffness at an overlap ahead, kept below the smaller radius (the chord's
    // half-width is not defined past it)
    static double stiffness_at(const Params& p, double ahead, double ri, double rj) {
        return debris::stiffness(p.E, p.area, std::min(ahead, 0.999 * (rj > 0.0 ? std::min(ri, rj) : ri)), ri, rj);
    }

    // E is the scenario's [debris] modulus for every contact, walls included (Mikhailov: the
    // bed's reaction with "E of the material of particle i"): set by the world after the tables
    static Params pair_params(const MaterialDef&, const MaterialDef&, FrictionRule) { return {}; }
    static Params wall_params(const MaterialDef&, const MaterialDef&, FrictionRule) { return {}; }

    // no history: every field of DiscContact / WallContact stays 0
    template <typename Contact>
    static void start_history(Contact& c, const Params&, double, double, double) {
        c.fs = 0.0;
        c.cn = c.cs = 0.0;
        c.damp_n = c.damp_s = 0.0f;
    }
    template <typename Contact>
    static void refresh_dashpots(Contact&, const Params&, double, double, double) {}
    // (the records' fields, as the linear law lists them: checkpoints and copies move them whole)
    template <typename Fn, typename... Contact>
    static void for_each_history_field(Fn fn, Contact&... c) {
        LinearLaw::for_each_history_field(fn, c...);
    }

    // One step of a touching contact (ri, rj: the radii; rj = 0 for a wall). The tangent
    // stiffness is taken at the overlap ahead, delta + 2.5 dt |vn| (D12; k_ahead says why 2.5
    // steps; |vn|: the step stays small while the contact opens again, as it closed).
    template <typename Contact>
    static DebrisContactForce step(const Params& p, DashpotMode, double overlap, double vn, double, double dt, double,
                                   Contact&, double& dissipated, double ri, double rj) {
        DebrisContactForce f;
        f.fn = f.fn_spring = debris::force(p.E, p.area, overlap, ri, rj);
        f.pair_force = rj > 0.0 ? f.fn : 0.0;
        f.k = stiffness_at(p, overlap + kAheadSteps * dt * std::abs(vn), ri, rj);
        dissipated = 0.0;
        return f;
    }
    template <typename Contact>
    static bool open_work_due(const Contact&) {
        return false;
    }
    template <typename Contact>
    static double open_work(const Contact&, double, double, double) {
        return 0.0;
    }
    template <typename Contact>
    static void clear_history(Contact&) {}

    template <typename Contact>
    static double elastic_energy(const Params& p, double overlap, const Contact&, double ri, double rj) {
        return debris::energy(p.E, p.area, overlap, ri, rj);
    }

    // the automatic step: translation only (rotation is locked), the tangent stiffness. With
    // rotation locked no rotational stiffness is needed, and the discs' k_rot sums carry the
    // moduli of their pair forces instead (P of friction_normal = "sum"; the walls add 0).
    static double k_tran(const Params&, const DebrisContactForce& f) { return f.k; }
    static double k_rot(const Params&, const DebrisContactForce& f) { return f.pair_force; }
    // a disc without contacts: no stiffness (its step is debris.dt_max)
    static double default_k_tran(double, double) { return 0.0; }
    static double default_k_rot(double, double) { return 0.0; }
};

}  // namespace demlab
