// The centred dashpots' arithmetic for a block of touching disc pairs (centred_dashpots.cpp),
// written once over arrays so that the compiler runs it as many pairs at a time as the CPU's
// vectors hold (centre_lanes.cpp compiles it for AVX-512, AVX2 and the baseline).
//
// Why a block: per touching pair the shift is about 60 operations with a square root and three
// divisions, and one pair at a time they ran at a quarter of the speed of the vector law
// (measured: the scalar centre pass took 65 % of a flume step, the law 18 %). Gathering the
// pairs' inputs stays one pair at a time, as in the law's kernels (gathers are no faster than
// loads on the CPUs at hand); the arithmetic runs lane by lane.
//
// Same bits whatever the width: every lane does the operations of the scalar formulas in
// centred_dashpots.cpp's header in the same order; no FMA (centre_lanes.cpp is compiled with
// -ffp-contract=off); the square root and the divisions are correctly rounded in every width.
#pragma once

#include <cstddef>
#include <cstdint>

#include "dem/laws/pair_kernel.h"

namespace demlab {

struct CentreBlock {
    static constexpr size_t kSize = 64;
    // inputs per touching pair (disc i -> disc j)
    alignas(64) double dx[kSize], dy[kSize];    // m, pos_j - pos_i
    alignas(64) double dist2[kSize];            // m^2
    alignas(64) double ri[kSize], rj[kSize];    // m
    alignas(64) double vrx[kSize], vry[kSize];  // m/s, v_j - v_i at t - dt/2
    alignas(64) double wi[kSize], wj[kSize];    // rad/s at t - dt/2
    alignas(64) double prx[kSize], pry[kSize];  // m/s, v*_j - v*_i at t (other forces and the lagged dashpots)
    alignas(64) double pwi[kSize], pwj[kSize];  // rad/s at t
    alignas(64) double inv_mn[kSize];           // 1/kg: 1/m_i + 1/m_j
    alignas(64) double inv_ii[kSize], inv_ij[kSize];  // 1/(kg m^2): the discs' inverse inertias
    alignas(64) double cn[kSize], cs[kSize];    // N s/m, the dashpot coefficients
    alignas(64) double kn[kSize], mu[kSize];    // N/m and -, the pair's normal stiffness and friction
    alignas(64) double fs[kSize];               // N, the capped shear spring force of this step's pass
    // outputs
    alignas(64) double fx[kSize], fy[kSize];    // N, the shift of the force on j (i gets its opposite)
    alignas(64) double torque_i[kSize], torque_j[kSize];  // N m
    alignas(64) double dissipated[kSize];       // J, the ledger's correction for the pair
    alignas(64) double damp_n[kSize], damp_s[kSize];  // N, the centred dashpot forces
    // bookkeeping, not read by the arithmetic
    size_t contact[kSize];
    int32_t i[kSize], j[kSize];
    size_t count = 0;
};

struct CentreConsts {
    double dt;              // s
    double half_dt;         // s
    bool rotation_free;     // the shear's effective mass includes the discs' turning
    bool no_tension;        // PFC dashpot modes 1 and 3
    bool no_shear_sliding;  // PFC dashpot modes 2 and 3
};

// The shifts of b's pairs (centre_lanes.cpp picks the width).
void centre_block(CentreBlock& b, const CentreConsts& k, bool avx2, bool avx512);

// What the wide gather (centre_wide.h) reads: the discs' and contacts' arrays of the pass.
struct CentrePairArrays {
    const double* pos;                // m, (x, y) per disc
    const double* radius;             // m
    const int32_t* material;
    const PairMaterial* materials;    // [mi * n_materials + mj]
    size_t n_materials;
    const DiscContact* contacts;
    const double* discs;              // the centre pass' disc records: eight doubles per disc, 64-byte aligned
    bool prefetch = false;            // ask for disc j's record ahead (World::prefetching)
};

// The touching pairs contacts[list[0, n)], n <= CentreBlock::kSize, gathered into lanes and
// computed by centre_lanes' formulas kWidth at a time (centre_avx2.cpp, centre_avx512.cpp):
// b's outputs, contact, i and j for each, b.count = n. False, with b.count = 0, when a listed
// pair does not touch (the pass listed them from the same positions: not expected).
bool centre_touching_avx2(const CentrePairArrays& a, const uint32_t* list, size_t n, CentreBlock& b, const CentreConsts& k);
bool centre_touching_avx512(const CentrePairArrays& a, const uint32_t* list, size_t n, CentreBlock& b, const CentreConsts& k);

// The formulas, lane l of a block; the template flags are constant per pass.
template <bool kRotationFree, bool kNoTension, bool kNoShearSliding>
[[gnu::always_inline]] inline void centre_lanes(CentreBlock& b, double dt, double h) {
    const size_t n = b.count;
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC ivdep
#endif
    for (size_t l = 0; l < n; ++l) {
        const double dist = __builtin_sqrt(b.dist2[l]);
        const double overlap = (b.ri[l] + b.rj[l]) - dist;
        const double nx = b.dx[l] / dist, ny = b.dy[l] / dist;
        const double tx = -ny, ty = nx;
        const double ra = b.ri[l] - 0.5 * overlap, rb = b.rj[l] - 0.5 * overlap;
        const double vn = b.vrx[l] * nx + b.vry[l] * ny;
        const double vs = (b.vrx[l] * tx + b.vry[l] * ty) - (b.wi[l] * ra + b.wj[l] * rb);
        const double pn = b.prx[l] * nx + b.pry[l] * ny;
        const double ps = (b.prx[l] * tx + b.pry[l] * ty) - (b.pwi[l] * ra + b.pwj[l] * rb);
        const double inv_mn = b.inv_mn[l];
        const double inv_ms = kRotationFree ? inv_mn + ra * ra * b.inv_ii[l] + rb * rb * b.inv_ij[l] : inv_mn;
        const double fn_spring = b.kn[l] * overlap;
        // normal: u(t) = (u* + (g/2) u-) / (1 + g/2), g = c dt / m
        const double cn = b.cn[l];
        const double gn = cn * dt * inv_mn;
        double dn_old = -cn * vn;
        double dn_new = -cn * ((pn + 0.5 * gn * vn) / (1.0 + 0.5 * gn));
        if (kNoTension) {
            dn_old = dn_old < -fn_spring ? -fn_spring : dn_old;  // std::max(d, -fn_spring)
            dn_new = dn_new < -fn_spring ? -fn_spring : dn_new;
        }
        // shear: none while the contact slides (|F_s| = mu F_n exactly after the pass' cap)
        const double cs = b.cs[l];
        const double gs = cs * dt * inv_ms;
        double ds_old = -cs * vs;
        double ds_new = -cs * ((ps + 0.5 * gs * vs) / (1.0 + 0.5 * gs));
        if (kNoShearSliding) {
            const bool sliding = __builtin_fabs(b.fs[l]) >= b.mu[l] * fn_spring;
            ds_old = sliding ? 0.0 : ds_old;
            ds_new = sliding ? 0.0 : ds_new;
        }
        const double dn = dn_new - dn_old, ds = ds_new - ds_old;
        b.fx[l] = dn * nx + ds * tx;
        b.fy[l] = dn * ny + ds * ty;
        b.torque_i[l] = -ra * ds;
        b.torque_j[l] = -rb * ds;
        // the law booked this step's force over the first half of the velocity interval
        b.dissipated[l] = -h * (dn * vn + ds * vs);
        b.damp_n[l] = dn_new;
        b.damp_s[l] = ds_new;
    }
}

}  // namespace demlab
