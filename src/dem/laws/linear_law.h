// The PFC linear law (thesis section 2.3.4-2.3.5) as a part of the engine: everything the
// force pass, the energy ledger, the automatic step and the checkpoint need to know of a law,
// in one place (docs/engine.md, "Contact laws").
//
//   Params          per pair of materials (disc-disc) or material and wall: the series
//                   stiffnesses and the friction coefficient, computed once at finalize()
//   history         the fields a contact record carries from step to step (DiscContact,
//                   WallContact): shear spring force fs, dashpot coefficients cn and cs, last
//                   dashpot forces damp_n and damp_s; for_each_history_field lists them for
//                   the checkpoint and the cross contacts' copies
//   start_history   a new contact's history
//   step            one step of a touching contact (force, updated history, dissipation)
//   elastic_energy  the energy a touching contact stores
//   k_tran, k_rot   what a touching contact adds to the automatic step's stiffness sums
//   open_work       what an opening contact's history still does (its last dashpot force)
//   kDiscFriction   whether the law's friction acts per disc in the integrator (DebrisLaw)
//                   rather than at the contacts
//   kWideKernels    whether the AVX2 and AVX-512 pair kernels (pair_kernel_avx2.cpp,
//                   pair_kernel_avx512.cpp) compute this law; a law without them runs the
//                   scalar kernels
//
// A law is registered in contact_laws.h; the force pass, the ledger and the checkpoint are
// templates over it and need no edit for a new one.
//
// The kernels that apply a law to a disc pair (pair_kernel.h, with its AVX2 and AVX-512
// forms) and to a disc-wall contact (wall_kernel.h) hold the contact's geometry and
// kinematics; the law holds the constitutive part.
#pragma once
#include <algorithm>
#include <cmath>

#include "dem/laws/contact_law.h"
#include "dem/laws/law_part.h"
#include "dem/material.h"
#include "geometry/wall.h"

namespace demlab {

// Series stiffnesses and friction of a pair of materials (eq. 2.59, 2.61).
struct PairMaterial {
    double kn, ks, mu;
    double k_tran;  // max(kn, ks): the pair's share of the automatic step's translational stiffness
    double inv_ks;  // 1 / ks, m/N (a division per contact cost the force pass 10 %)
};

struct LinearLaw : LawDefaults {
    using Params = PairMaterial;
    static constexpr const char* kName = "linear";
    static constexpr const char* kSummary =  // contact.law's text
        "PFC's linear model with dashpots, thesis 2.3.4-2.3.5";
    static constexpr bool kCentredDashpots = true;  // the dashpots at the step's centre when timestep.dashpots says so
    static constexpr bool kWideKernels = true;
    static constexpr bool kDiscFriction = false;  // friction at the contacts (DebrisLaw: per disc)
    static constexpr bool kStepAhead = false;     // open contacts add nothing to the step (DebrisLaw: they may)
    // The ledger's elastic energy at x(t), as its dashpots' work is booked (DebrisLaw: at t - dt/2).
    static constexpr bool kElasticAtHalfStep = false;
    static double k_ahead(const Params&, double, double, double, double, double) { return 0.0; }

    // kn, ks: the series stiffnesses (N/m); mu: the combined friction coefficient
    static Params params(double kn, double ks, double mu) { return {kn, ks, mu, std::max(kn, ks), 1.0 / ks}; }
    // A pair of discs (eq. 2.59, 2.61: springs in series) and a disc with a wall (the wall's material).
    static Params pair_params(const MaterialDef& a, const MaterialDef& b, FrictionRule rule) {
        return params(series_stiffness(a.kn, b.kn), series_stiffness(a.ks, b.ks), combine_friction(rule, a.friction, b.friction));
    }
    static Params wall_params(const MaterialDef& a, const MaterialDef& w, FrictionRule rule) {
        return params(series_stiffness(a.kn, w.kn), series_stiffness(a.ks, w.ks), combine_friction(rule, a.friction, w.friction));
    }

    // A new contact: no shear spring force, dashpots of critical damping scaled by beta
    // (eq. 2.56-2.57) for its effective mass (eq. 2.60, 2.62: a wall's mass is infinite, so a
    // disc-wall contact takes the disc's mass), no dashpot force yet.
    template <typename Contact>
    static void start_history(Contact& c, const Params& p, double m_eff, double beta_n, double beta_s) {
        c.fs = 0.0;
        c.cn = dashpot_coefficient(beta_n, m_eff, p.kn);
        c.cs = dashpot_coefficient(beta_s, m_eff, p.ks);
        c.damp_n = c.damp_s = 0.0f;
    }

    // The dashpot coefficients again, the rest of the history kept (a radius or mass changed).
    template <typename Contact>
    static void refresh_dashpots(Contact& c, const Params& p, double m_eff, double beta_n, double beta_s) {
        c.cn = dashpot_coefficient(beta_n, m_eff, p.kn);
        c.cs = dashpot_coefficient(beta_s, m_eff, p.ks);
    }

    // The history's fields, listed once: fn is called on each field of one contact, or on the
    // same field of several contacts (checkpoints, copies).
    template <typename Fn, typename... Contact>
    static void for_each_history_field(Fn fn, Contact&... c) {
        fn(c.fs...);
        fn(c.cn...);
        fn(c.cs...);
        fn(c.damp_n...);
        fn(c.damp_s...);
    }

    // One step of the law for a touching contact: updates the history (shear spring, last
    // dashpot forces) and returns the forces; `dissipated` receives the energy the step took
    // out: sliding, plus the dashpots' work centred on v(t - dt/2) (this step's force over the
    // first half of the velocity interval, the last step's over the second half).
    template <typename Contact>
    static LinearContactForce step(const Params& pm, DashpotMode mode, double overlap, double vn, double vs, double dt,
                                   double last_dt, Contact& c, double& dissipated, double /*ri*/ = 0.0,
                                   double /*rj: 0 for a wall*/ = 0.0) {
        const LinearContactParams p{pm.kn, pm.ks, pm.mu, c.cn, c.cs, mode, pm.inv_ks};
        const LinearContactForce f = linear_contact(p, overlap, vn, vs, dt, c.fs);
        dissipated = keep_history(f, c, vn, vs, dt, last_dt);
        return f;
    }
    // The history after a step of linear_contact (any law built on it, HertzLaw too): the
    // capped shear spring and the dashpot forces; returns the energy the step took out.
    template <typename Contact>
    static double keep_history(const LinearContactForce& f, Contact& c, double vn, double vs, double dt, double last_dt) {
        c.fs = f.fs_spring;
        const double dissipated =
            f.slip_work - 0.5 * ((f.damp_n * dt + c.damp_n * last_dt) * vn + (f.damp_s * dt + c.damp_s * last_dt) * vs);
        c.damp_n = float(f.damp_n);
        c.damp_s = float(f.damp_s);
        return dissipated;
    }

    // A contact that opened: PFC deletes it, so its history starts again at zero; its last
    // dashpot force still acted over the second half of the previous step (open_work, J/m,
    // from the relative velocity along the normal and the tangent, when open_work_due).
    template <typename Contact>
    static bool open_work_due(const Contact& c) {
        return c.damp_n != 0.0f || c.damp_s != 0.0f;
    }
    template <typename Contact>
    static double open_work(const Contact& c, double vn, double vs, double last_dt) {
        return -0.5 * last_dt * (c.damp_n * vn + c.damp_s * vs);
    }
    template <typename Contact>
    static void clear_history(Contact& c) {
        c.fs = 0.0;
        c.damp_n = c.damp_s = 0.0f;
    }

    // The energy a touching contact stores: the normal spring's (kn U^2 / 2, from the secant
    // overlap) and the shear spring's (fs^2 / (2 ks)), J per metre of thickness.
    template <typename Contact>
    static double elastic_energy(const Params& p, double overlap, const Contact& c, double /*ri*/ = 0.0, double /*rj*/ = 0.0) {
        return 0.5 * p.kn * overlap * overlap + 0.5 * c.fs * c.fs / p.ks;
    }

    // A touching contact's share of the automatic step (timestep.h): translational and
    // rotational stiffness, N/m. A disc without contacts takes its material's own
    // (default_k_tran, default_k_rot).
    static double k_tran(const Params& p, const LinearContactForce& = {}) { return p.k_tran; }
    static double k_rot(const Params& p, const LinearContactForce& = {}) { return p.ks; }
    static double default_k_tran(double kn, double ks) { return std::max(kn, ks); }
    static double default_k_rot(double /*kn*/, double ks) { return ks; }
};

}  // namespace demlab
