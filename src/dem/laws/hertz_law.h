// PFC's simplified Hertz-Mindlin law (Itasca, PFC 2D/3D 4.0, "Hertz-Mindlin contact model";
// docs/engine.md, "Hertz-Mindlin"): the normal force of Hertz's elastic spheres and a shear
// stiffness that grows with the normal force as Mindlin's, without Mindlin's micro-slip.
//
//   normal, secant   K_n = 2 G sqrt(2 R~) / (3 (1 - nu)) sqrt(U),   F_n = K_n U
//   shear, tangent   k_s = 2 (3 G^2 (1 - nu) R~)^(1/3) / (2 - nu) |F_n|^(1/3)
//                    dF_s = -k_s v_s dt, |F_s| <= mu F_n (the linear law's slider)
//   R~ = 2 R_A R_B / (R_A + R_B) for two discs, R_disc for a disc on a wall
// With G = E / (2 (1 + nu)) this is Hertz's F = 4/3 E* sqrt(R*) U^(3/2) for two equal spheres
// (E* = E / (2 (1 - nu^2)), R* = R~ / 2). As PFC2D does, demlab applies the sphere's form to
// its discs (forces per metre of thickness): the force's growth with the overlap, the contact
// time's dependence on the speed and the shear stiffness tied to the normal force are Hertz's
// and Mindlin's; the magnitudes of a cylinder pressed along its length are not.
//
// Dashpots (PFC: viscous damping with the critical ratios of the contact's current tangent
// stiffnesses): c_n = 2 beta_n sqrt(m k_n), k_n = dF_n/dU = 3/2 K_n, and c_s = 2 beta_s
// sqrt(m k_s); the history keeps 2 beta sqrt(m) and the step multiplies by sqrt(k). The
// dashpot modes and the ledger are the linear law's (linear_contact).
//
// The step: the stiffness grows with the overlap, so, as for DEBRIS, the rule takes the
// tangent stiffness at the overlap 2.5 steps ahead (of a touching contact and of one closing
// in), capped by hertz.dt_max, the step of discs in flight. Unlike DEBRIS's it never grows
// again: the leapfrog takes a step's impulse as F dt_n where a changing step needs
// F (dt_(n-1) + dt_n) / 2, and a step that shrinks at once as an impact compresses and grows
// back as it rebounds gains energy in every impact (measured: an undamped gas of 36 discs
// gained 14 % in 0.2 s at safety 0.8 with DEBRIS's growth of 1.05 a step; 1.4 % with none,
// test Hertz.UndampedGasKeepsItsEnergy). The run keeps the step of its hardest contact so far.
// Materials: G and nu are the scenario's [hertz] keys for every contact, walls included (a
// wall is rigid: PFC's disc-wall contact takes the disc's moduli); the friction is the
// materials' (material.friction_*), combined as for the linear law.
#pragma once
#include <algorithm>
#include <array>
#include <cmath>
#include <string>

#include "core/error.h"
#include "core/validate.h"
#include "dem/laws/contact_law.h"
#include "dem/laws/law_part.h"
#include "dem/laws/linear_law.h"
#include "dem/material.h"
#include "geometry/wall.h"

namespace demlab {

struct HertzDef {
    double shear_modulus = 2.9e10;  // Pa, G (quartz, as commonly quoted: 29 GPa)
    double poisson_ratio = 0.15;    // -, nu (quartz: 0.08-0.17)
    double dt_max = 1e-4;           // s, the automatic step's ceiling (discs in flight)
};

// The force of a touching contact and what the step and the ledger need of it.
struct HertzContactForce : LinearContactForce {
    double k = 0.0;   // N/m, the larger tangent stiffness 2.5 steps ahead (normal) or now (shear)
    double ks = 0.0;  // N/m, the shear tangent stiffness
};

namespace hertz {

// the contact's radius R~ (rj = 0: a wall)
inline double contact_radius(double ri, double rj) { return rj > 0.0 ? 2.0 * ri * rj / (ri + rj) : ri; }
// K_n / sqrt(U) = a sqrt(R~), a = 2 G sqrt 2 / (3 (1 - nu)); F_n = a sqrt(R~) U^(3/2)
inline double normal_force(double a, double r, double overlap) { return a * std::sqrt(r * overlap) * overlap; }
// dF_n/dU = 3/2 a sqrt(R~ U)
inline double normal_stiffness(double a, double r, double overlap) { return 1.5 * a * std::sqrt(r * overlap); }
// k_s = b (R~ |F_n|)^(1/3), b = 2 (3 G^2 (1 - nu))^(1/3) / (2 - nu)
inline double shear_stiffness(double b, double r, double fn) { return b * std::cbrt(r * std::abs(fn)); }

}  // namespace hertz

struct HertzLaw : LawDefaults {
    struct Params {
        double a = 0.0;   // Pa, 2 G sqrt 2 / (3 (1 - nu))
        double b = 0.0;   // Pa^(2/3), 2 (3 G^2 (1 - nu))^(1/3) / (2 - nu)
        double mu = 0.0;  // -, the combined friction coefficient
    };
    using Def = HertzDef;
    static constexpr const char* kName = "hertz";
    static constexpr const char* kSummary =  // contact.law's text
        "PFC's simplified Hertz-Mindlin model: normal force from the shear modulus and Poisson's ratio, shear stiffness from the normal force; [hertz], docs/engine.md";
    static constexpr const char* kSection = "hertz";
    static constexpr bool kWideKernels = false;   // the scalar kernels
    static constexpr bool kDiscFriction = false;  // friction at the contacts
    static constexpr bool kStepAhead = true;      // closing contacts count for the step
    static constexpr bool kElasticAtHalfStep = false;
    static constexpr double kStepGrowth = 1.0;    // never grows (below)
    static constexpr double kAheadSteps = 2.5;

    template <typename Add>
    static void keys(Add& add) {
        add.real("shear_modulus", "Pa", "G of the discs (contact.law = \"hertz\"): F_n = 2 G sqrt(2 R~) / (3 (1 - nu)) U^(3/2) (PFC's Hertz-Mindlin; quartz, as commonly quoted: 29 GPa)", &Def::shear_modulus, 0, 1e12, true);
        add.real("poisson_ratio", "-", "nu of the discs: in the normal force and the shear stiffness k_s = 2 (3 G^2 (1 - nu) R~)^(1/3) / (2 - nu) F_n^(1/3)", &Def::poisson_ratio, 0, 0.5, false, true);
        add.real("dt_max", "s", "the automatic step's ceiling, the step of discs in flight (the step follows the contacts' stiffness below it)", &Def::dt_max, 0, 1, true);
    }
    // the stiffness keys of the linear law, which Hertz does not read
    static constexpr std::array<const char*, 4> kUnusedKeys{"material.kn", "material.ks", "material.wall_kn", "material.wall_ks"};
    static constexpr const char* kUnusedWhy = "its stiffnesses come from hertz.shear_modulus and hertz.poisson_ratio";
    template <typename WorldDefT>
    static void validate(const Def& h, const WorldDefT&) {
        if (!(h.shear_modulus > 0.0 && h.shear_modulus <= 1e12))
            throw InputError("hertz.shear_modulus = " + format_number(h.shear_modulus) + " Pa: must be in (0, 1e12]");
        if (!(h.poisson_ratio >= 0.0 && h.poisson_ratio < 0.5))
            throw InputError("hertz.poisson_ratio = " + format_number(h.poisson_ratio) + ": must be in [0, 0.5)");
        if (!(h.dt_max > 0.0 && h.dt_max <= 1.0))
            throw InputError("hertz.dt_max = " + format_number(h.dt_max) + " s: must be in (0, 1]");
    }
    static Params moduli(const Def& h, double mu) {
        const double g = h.shear_modulus, nu = h.poisson_ratio;
        return {2.0 * g * std::sqrt(2.0) / (3.0 * (1.0 - nu)), 2.0 * std::cbrt(3.0 * g * g * (1.0 - nu)) / (2.0 - nu), mu};
    }
    // the friction from the materials; the moduli from [hertz] (fill_tables)
    static Params pair_params(const MaterialDef& a, const MaterialDef& b, FrictionRule rule) {
        return {0.0, 0.0, combine_friction(rule, a.friction, b.friction)};
    }
    static Params wall_params(const MaterialDef& a, const MaterialDef& w, FrictionRule rule) {
        return {0.0, 0.0, combine_friction(rule, a.friction, w.friction)};
    }
    template <typename Tables>
    static void fill_tables(Tables& t, const Def& h) {
        for (auto* table : {&t.disc_disc, &t.disc_wall})
            for (Params& p : *table) p = moduli(h, p.mu);
    }
    static double first_dt(const Def& h) { return h.dt_max; }
    static double step_from_rule(const Def& h, double safety, double, double best_sq, double last_dt) {
        return capped_growing_step(h.dt_max, kStepGrowth, safety, best_sq, last_dt);
    }

    // the history: the linear law's fields; cn and cs hold 2 beta sqrt(m_eff), the step
    // multiplies them by the square root of the current tangent stiffness
    template <typename Contact>
    static void start_history(Contact& c, const Params&, double m_eff, double beta_n, double beta_s) {
        c.fs = 0.0;
        refresh_dashpots(c, Params{}, m_eff, beta_n, beta_s);
        c.damp_n = c.damp_s = 0.0f;
    }
    template <typename Contact>
    static void refresh_dashpots(Contact& c, const Params&, double m_eff, double beta_n, double beta_s) {
        c.cn = 2.0 * beta_n * std::sqrt(m_eff);
        c.cs = 2.0 * beta_s * std::sqrt(m_eff);
    }
    template <typename Fn, typename... Contact>
    static void for_each_history_field(Fn fn, Contact&... c) {
        LinearLaw::for_each_history_field(fn, c...);
    }

    // One step of a touching contact (ri, rj: the radii; rj = 0 for a wall): the linear law's
    // slider and dashpots with the secant normal and tangent shear stiffness of this overlap.
    template <typename Contact>
    static HertzContactForce step(const Params& p, DashpotMode mode, double overlap, double vn, double vs, double dt,
                                  double last_dt, Contact& c, double& dissipated, double ri, double rj) {
        const double r = hertz::contact_radius(ri, rj);
        const double kn_secant = p.a * std::sqrt(r * overlap);
        const double kn_tangent = 1.5 * kn_secant;
        const double ks = hertz::shear_stiffness(p.b, r, kn_secant * overlap);
        const LinearContactParams lp{kn_secant, ks, p.mu, c.cn * std::sqrt(kn_tangent), c.cs * std::sqrt(ks), mode, 1.0 / ks};
        HertzContactForce f;
        static_cast<LinearContactForce&>(f) = linear_contact(lp, overlap, vn, vs, dt, c.fs);
        dissipated = LinearLaw::keep_history(f, c, vn, vs, dt, last_dt);
        f.k = std::max(hertz::normal_stiffness(p.a, r, overlap + kAheadSteps * dt * std::abs(vn)), ks);
        f.ks = ks;
        return f;
    }
    // an opening contact: as the linear law's (its last dashpot forces' second half)
    template <typename Contact>
    static bool open_work_due(const Contact& c) {
        return LinearLaw::open_work_due(c);
    }
    template <typename Contact>
    static double open_work(const Contact& c, double vn, double vs, double last_dt) {
        return LinearLaw::open_work(c, vn, vs, last_dt);
    }
    template <typename Contact>
    static void clear_history(Contact& c) {
        LinearLaw::clear_history(c);
    }

    // stored energy: the normal force's integral 2/5 K_n U^2 and the shear spring's F_s^2 / (2 k_s)
    template <typename Contact>
    static double elastic_energy(const Params& p, double overlap, const Contact& c, double ri, double rj) {
        const double r = hertz::contact_radius(ri, rj);
        const double fn = hertz::normal_force(p.a, r, overlap);
        const double ks = hertz::shear_stiffness(p.b, r, fn);
        return 0.4 * fn * overlap + (ks > 0.0 ? 0.5 * c.fs * c.fs / ks : 0.0);
    }

    // the automatic step: the tangent stiffnesses (translation: the normal one 2.5 steps ahead)
    static double k_tran(const Params&, const HertzContactForce& f) { return f.k; }
    static double k_rot(const Params&, const HertzContactForce& f) { return f.ks; }
    static double default_k_tran(double, double) { return 0.0; }  // in flight: hertz.dt_max
    static double default_k_rot(double, double) { return 0.0; }
    // an open contact that may touch within 2.5 steps: the normal tangent stiffness there
    static double k_ahead(const Params& p, double gap, double vn, double dt, double ri, double rj) {
        const double ahead = -gap + kAheadSteps * dt * std::max(0.0, -vn);
        return ahead > 0.0 ? hertz::normal_stiffness(p.a, hertz::contact_radius(ri, rj), ahead) : 0.0;
    }
    static double pair_k_ahead(const Params& p, double dist2, double rsum, const Vec2& dx, const Vec2& vrel, double dt,
                               double ri, double rj) {
        return closing_pair_stiffness<HertzLaw>(p, dist2, rsum, dx, vrel, dt, ri, rj);
    }
};

}  // namespace demlab
