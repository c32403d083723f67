// Elastic bonds that break (AvaFrame com5SnowSlide's cohesion, docs/spec/COHESION.md): a
// persistent interaction between two discs, a central spring along the bond that acts at any
// distance and beside the contact law, removed for good past a maximum strain. This file is
// the bond's law; the world keeps the bond list (World::add_bond), which survives the broad
// phase's refreshes, adds each disc's bond terms after its contact terms, books the energy
// and saves the list in checkpoints.
//
//   eps = (L - L0) / L0                                   C1 (> 0: stretched)
//   F_on_k = -F_on_l = eps A E e_kl, e_kl = (x_l - x_k)/L  C2
//   A = t L / sqrt(3) ("current") or t L0 / sqrt(3) ("rest"), t = 1 m (PFC2D)   C3'
//   so with k0 = E t / sqrt(3): |F| = k0 (L - L0) L / L0 ("current"), k0 (L - L0) ("rest")   C6
//   broken when |eps| > eps_c ("both") or eps > eps_c ("tension"); skipped when L <= d_min  C4
//   U_b = k0 L0^2 (eps^2/2 + eps^3/3) ("current"), k0 L0^2 eps^2 / 2 ("rest")   C7
//   the automatic step adds k_b,max = k0 (1 + 2 eps_c) ("current") or k0 to both discs  C10
//   predict: the length (strain, force, break) from x + dt v, a dashpot c = k_b dt     C5, C11
// Between spheres (the 3-D solver, dem3/world3.h) the face is the Voronoi face between two
// neighbours of a close-packed lattice of spacing L0: the cell is a rhombic dodecahedron of
// volume L0^3/sqrt(2) with 12 faces at L0/2, so each face is L0^2/(2 sqrt 2). "current" scales
// one of its sides with L, as AvaFrame's face width (A = L0 L/(2 sqrt 2)), "rest" keeps it:
// the same algebra as above with k0 = E L0/(2 sqrt 2) per bond (k0_sphere). A face-centred
// cubic network of these bonds (cube side a = sqrt(2) L0, k0/a = E/4) has C11 = E/2,
// C12 = C44 = E/4: Young's modulus E/3 along a cube axis, Poisson's ratio 1/3 (derived).
#pragma once
#include <cmath>
#include <cstdint>

#include "core/vec2.h"

namespace demlab {

enum class BondArea { Current, Rest };
enum class BondBreak { Both, Tension };

struct BondDef {
    double modulus = 5.0e4;         // Pa, E (AvaFrame's cohesiveSurfaceTension), > 0
    double max_strain = 0.2;        // -, eps_c in (0, 0.5]
    double min_distance = 1.0e-3;   // m, a bond this short or shorter is skipped (no force, no break)
    BondArea area = BondArea::Current;
    BondBreak break_mode = BondBreak::Both;
    double thickness = 1.0;         // m, t: PFC2D's unit thickness
    // C5, AvaFrame's lengths from positions predicted one step: d = x_l - x_k + dt (v_l - v_k).
    // With the leapfrog's v(t - dt/2) that is the spring plus a dashpot c = k_b dt (C11); the
    // difference to the spring alone is booked as dissipation (the ledger's contacts' term).
    bool predict = false;
};

// A bond between discs k < l, rest length L0 (m) taken when the world is finalized.
struct Bond {
    int32_t k, l;
    double rest_length;
    uint8_t broken;
};

// A bond that broke: when, which, at what strain, and the energy it took with it (J/m).
struct BondBreakEvent {
    double t;
    int32_t k, l;
    double strain, energy;
};

struct ElasticBond {
    // k0 = E t / sqrt(3), N/m
    static double k0(const BondDef& d) { return d.modulus * d.thickness / std::sqrt(3.0); }
    // between spheres, k0 = E L0 / (2 sqrt 2), N/m (the face above)
    static double k0_sphere(const BondDef& d, double rest_length) { return d.modulus * rest_length / (2.0 * std::sqrt(2.0)); }

    // eps = L / L0 - 1, with 1 / L0 taken once per bond (a division per bond and step saved)
    static double strain(double length, double inv_rest_length) { return length * inv_rest_length - 1.0; }

    // The bond with d = x_l - x_k: whether it is skipped (too short), breaks (no force this
    // step), or acts with force f d on k and -f d on l (f in N/m per m of d).
    struct Eval {
        double f = 0.0;
        double strain = 0.0;
        bool skipped = false, breaks = false;
    };
    template <class Vec>  // Vec2 (discs) or Vec3 (spheres)
    static Eval evaluate(const BondDef& def, double k0_, double rest_length, double inv_rest_length, const Vec& d) {
        Eval e;
        const double length_sq = d.squaredNorm();
        if (length_sq <= def.min_distance * def.min_distance) {
            e.skipped = true;
            return e;
        }
        const double length = std::sqrt(length_sq);
        e.strain = strain(length, inv_rest_length);
        e.breaks = def.break_mode == BondBreak::Both ? std::abs(e.strain) > def.max_strain : e.strain > def.max_strain;
        if (e.breaks) return e;
        // eps E A / L: "current" A = t L/sqrt(3) gives eps k0; "rest" eps k0 L0 / L
        e.f = def.area == BondArea::Current ? e.strain * k0_ : e.strain * k0_ * rest_length / length;
        return e;
    }

    static double energy(const BondDef& def, double k0_, double rest_length, double strain) {
        const double s2 = strain * strain;
        const double base = k0_ * rest_length * rest_length;
        return def.area == BondArea::Current ? base * (0.5 * s2 + s2 * strain / 3.0) : base * 0.5 * s2;
    }

    // the largest tangent stiffness an intact bond reaches, N/m (the automatic step)
    static double max_stiffness(const BondDef& def, double k0_) {
        return def.area == BondArea::Current ? k0_ * (1.0 + 2.0 * def.max_strain) : k0_;
    }
};

}  // namespace demlab
