// The integration of a range of discs (PFC's central differences, World::integrate_discs), four
// discs at a time with AVX2 or eight with AVX-512, for the runs that use the per-disc
// rotational damping (every run but those that ask for damping per contact), with or without
// local damping (eq. 2.51: the release's settling uses it): the same operations in the same
// order, lane by lane, so the same bits as the scalar loop (integrate.cpp).
#pragma once
#include <cstddef>
#include <cstdint>

#include "dem/laws/pair_kernel.h"
#include "core/vec2.h"

namespace demlab {

// The discs' arrays the integration reads and writes.
struct IntegrateArrays {
    Vec2* pos;
    Vec2* vel;
    double* omega;
    double* angle;
    const double* mass;
    const double* inv_mass;
    const double* inertia;
    const double* inv_inertia;
    const double* radius;
    const double* rr_factor;      // Preh-Poisel factor, 1/m
    const int32_t* material;
    const DiscLoad* load;
    const Vec2* fat_lo;           // the broad phase's fat boxes
    const Vec2* fat_hi;
    const double* default_k_tran; // per material: max(kn, ks), N/m (a disc without contacts)
    const double* default_k_rot;  // per material: ks, N/m
    size_t n_materials;           // entries of the two tables (1: every disc reads entry 0)
};

// The step's constants.
struct IntegrateParams {
    double dt;                  // s
    Vec2 g;                     // m/s^2
    double alpha;               // local damping (eq. 2.51), 0: none (the flow unless damping.local_alpha is set)
    double g_abs;               // |g|, m/s^2
    int rotation_model;         // 1, 2 or 3
    bool rolling_literal;       // RollingForm::Literal: g_eff = |g|; else the wall's normal force / m
    double mu_br;               // Model 3's factor per step for a disc touching another
    bool auto_dt;               // compute the discs' critical steps
    bool rotation_free;         // and with the rotational bound (DtFactors)
    double phi_sq, phi_t_sq;
    Vec2 domain_lo, domain_hi;  // m
    double best_sq_start;       // s^2, the smallest squared step already found by this range's
                                // earlier blocks (INFINITY: none); the result is no larger
};

// The energy ledger's sums of a step for a block of discs (World's ledger: the blocks are
// added in order, so the bits do not depend on how the discs are shared among threads).
struct LedgerBlock {
    double contacts = 0.0;  // J/m, half of each disc-disc contact's dissipation, per disc (DiscLoad)
    double local = 0.0;     // J/m, local damping
    double rotation = 0.0;  // J/m, rolling resistance and rotational damping
    double kinetic = 0.0;   // J/m, the discs' kinetic energy after the step: per disc
                            // 0.5 m |v|^2 + 0.5 I omega^2 (the second term unless rotation is locked),
                            // summed in four lanes (disc i in lane i % 4, each in disc order) and
                            // then (lane 0 + lane 1) + (lane 2 + lane 3)
};

// What the range's integration found.
struct IntegrateOut {
    double best_sq;     // the smallest squared critical step (INFINITY if !auto_dt)
    size_t fault;       // the first disc outside the domain or not finite (SIZE_MAX: none)
    bool any_escaped;   // a disc left its fat box
    double speed_l1;    // the largest |vx| + |vy| of the new velocities, m/s (the clearance test)
    double extent_l1;   // the largest |x| + |y| of the new positions, m (their rounding)
    long touching_dd;   // the discs' touching disc-disc contacts (each pair counted twice)
};

// Integrates discs [begin, end), and writes the ledger's sums for their blocks: block k holds
// discs [k block_size, (k + 1) block_size) (begin and end at block ends, or the range's ends),
// each sum taken in disc order: the contacts' share from the discs' loads, the energy the
// rolling resistance and the rotational damping took out, the local damping's, and the
// discs' kinetic energy after the step. Only call
// it when cpu_has_avx2().
// begin is a multiple of 4 (the World's ranges and blocks are whole ledger blocks).
IntegrateOut integrate_avx2(const IntegrateArrays& a, const IntegrateParams& p, size_t begin, size_t end,
                            LedgerBlock* blocks, size_t block_size);

// integrate_avx2 eight discs at a time in AVX-512 registers (integrate_avx512.cpp): the same
// results and bits. Only call it when cpu_has_avx512().
IntegrateOut integrate_avx512(const IntegrateArrays& a, const IntegrateParams& p, size_t begin, size_t end,
                              LedgerBlock* blocks, size_t block_size);

}  // namespace demlab
