// The disc-disc force kernel: one candidate pair, one step of the linear law (linear_law.h),
// as a small function over the discs' state and the pair's history. World's force pass calls
// it either to add a pair straight into both discs' sums (the common case) or to park the
// result in a slot when the two discs belong to different threads (force_pass.cpp).
#pragma once
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "dem/laws/linear_law.h"
#include "core/vec2.h"

namespace demlab {

// A disc-disc contact candidate (i < j) and its history.
struct DiscContact {
    int32_t i, j;
    double fs;   // shear spring force along t, N (history)
    double cn;   // normal dashpot coefficient, N s/m
    double cs;   // shear dashpot coefficient, N s/m
    float damp_n, damp_s;  // last step's dashpot forces, N (energy ledger only)
};

// What one pair adds to its discs in a step.
struct PairOut {
    Vec2 f;                      // force on j (B); i gets -f
    double torque_i, torque_j;   // N m / m
    double dissipated;           // J/m, shared half and half by the two discs
    double k_tran, k_rot;        // stiffnesses for the automatic step (0 when not touching)
    bool touching;
};

// The discs' state the kernel reads, as raw arrays (no aliasing with the histories it writes).
struct DiscArrays {
    const Vec2* pos;
    const Vec2* vel;
    const double* radius;
    const double* omega;
    const int32_t* material;
};

// The step's constants, with the law's parameter table (Params: the law's per-pair record).
template <typename Params>
struct PairPassParamsT {
    const Params* materials;  // [mi * n_materials + mj]
    size_t n_materials;
    DashpotMode mode;
    double dt, last_dt;  // s, this step's and the last one's
    double max_overlap_ratio;
};
// the linear law's, which the AVX2 and AVX-512 kernels take
using PairPassParams = PairPassParamsT<PairMaterial>;

// Pair (c.i, c.j): n from i (A) to j (B); the force on j is F = fn n + ft t, on i -F.
// Returns false, with `overlap` set, when the overlap exceeds max_overlap_ratio of the smaller
// radius (or the centres coincide): a blown-up run, which the caller reports.
// Inlined by force: GCC kept it out of line (it has two callers), and the PairOut then went
// through the stack, with a call per candidate; perf put a third of the range pass on the
// return and on reloading the result (docs/performance.md).
template <typename Law = LinearLaw>
[[gnu::always_inline]] inline bool disc_pair_force(const DiscArrays& d, const PairPassParamsT<typename Law::Params>& p,
                                                   DiscContact& c, PairOut& out, double& overlap) {
    const size_t i = size_t(c.i), j = size_t(c.j);
    const Vec2 dx = d.pos[j] - d.pos[i];
    const double rsum = d.radius[i] + d.radius[j];
    const double dist2 = dx.squaredNorm();
    out.touching = false;
    out.dissipated = 0.0;
    out.k_tran = 0.0;
    if (dist2 >= rsum * rsum) {
        if (Law::open_work_due(c)) {
            const Vec2 vrel = d.vel[j] - d.vel[i];
            const Vec2 nrm = dx / std::sqrt(dist2);
            const double vs = vrel.dot(perp(nrm)) - (d.omega[i] * d.radius[i] + d.omega[j] * d.radius[j]);
            out.dissipated = Law::open_work(c, vrel.dot(nrm), vs, p.last_dt);
        }
        Law::clear_history(c);
        if constexpr (Law::kStepAhead) {
            const typename Law::Params& pm = p.materials[size_t(d.material[i]) * p.n_materials + size_t(d.material[j])];
            out.k_tran = Law::pair_k_ahead(pm, dist2, rsum, dx, d.vel[j] - d.vel[i], p.dt, d.radius[i], d.radius[j]);
        }
        return true;
    }
    const double dist = std::sqrt(dist2);
    overlap = rsum - dist;
    if (!(overlap <= p.max_overlap_ratio * std::min(d.radius[i], d.radius[j])) || dist == 0.0) return false;
    const Vec2 nrm = dx / dist;
    const Vec2 t = perp(nrm);
    // PFC's contact point: x_A + (r_A - U/2) n; the lever arms of both discs
    const double ra = d.radius[i] - 0.5 * overlap, rb = d.radius[j] - 0.5 * overlap;
    const Vec2 vrel = d.vel[j] - d.vel[i];
    const double vn = vrel.dot(nrm);
    // eq. 2.46: tangential velocity of B relative to A at the contact point
    const double vs = vrel.dot(t) - (d.omega[i] * ra + d.omega[j] * rb);
    const typename Law::Params& pm = p.materials[size_t(d.material[i]) * p.n_materials + size_t(d.material[j])];
    const auto f = Law::step(pm, p.mode, overlap, vn, vs, p.dt, p.last_dt, c, out.dissipated, d.radius[i], d.radius[j]);
    out.f = f.fn * nrm + f.ft * t;
    // torque = lever x force; both levers give -r * ft (docs/engine.md)
    out.torque_i = -ra * f.ft;
    out.torque_j = -rb * f.ft;
    out.k_tran = Law::k_tran(pm, f);
    out.k_rot = Law::k_rot(pm, f);
    out.touching = true;
    return true;
}

// What a disc's contacts add up to in a step, in one cache line: the force pass adds a
// contact's terms to two discs, and one line per disc instead of eight arrays cut its L1
// misses (docs/performance.md). The first four fields are one AVX2 register and the next two
// an SSE one, in the order PairBatch keeps a pair's results, so the AVX2 pass adds a pair to a
// disc with two additions (add_pair_batch_avx2).
struct alignas(64) DiscLoad {
    Vec2 force{0.0, 0.0};      // N/m, contact forces
    double torque = 0.0;       // N m/m
    double k_tran = 0.0;       // N/m, sum of max(kn, ks) over touching contacts (automatic step)
    double k_rot = 0.0;        // N/m, sum of ks
    double dissipated = 0.0;   // J/m, half the dissipation of each of its disc-disc contacts
    double wall_normal = 0.0;  // N/m, elastic normal force from walls (rolling resistance)
    int32_t n_disc = 0, n_wall = 0;  // touching contacts
};

// A batch of pairs' results, a record per pair and disc in DiscLoad's order: what
// disc_pairs_avx2 leaves for add_pair_batch_avx2 to add into the discs in list order. Only
// the pairs with something to do are there: those touching, and those open with a history
// to end (a pair open before and after the step, with an all-zero history, adds +0 to every
// sum and writes back the zeros it read, so it is left out; in DB-9k half the candidates are
// such). index[b] is result b's contact, counted from the batch's first; the results are in
// list order. An open pair's terms are +0 (-0 for the force on i), so every result is added
// without a branch: x + (+0) is x for every x but -0, and a sum that starts at +0 never
// becomes -0 (round to nearest); x + (-0) is x for every x. So the sums are the bits the
// scalar pass gets by skipping the open pairs. (i's force is added as -f: x + (-f) is x - f.)
struct PairBatch {
    static constexpr size_t kSize = 128;  // pairs; the batch stays in L1 between kernel and sums (64: 2-3 % slower, 256: slower again)
    size_t count = 0;                          // results in the batch
    alignas(32) uint32_t index[kSize + 8];     // result b is contact index[b] of the batch
    alignas(32) uint32_t check[kSize + 4];     // the contacts the clearance test did not skip
    size_t skipped = 0;                        // pairs skipped by the clearance test, summed over calls
    // (64-byte aligned: the AVX-512 law stores two records of to_i, to_j and four of to_both at once)
    alignas(64) double to_i[kSize][4];         // into disc i: -fx, -fy (N/m), torque_i (N m/m), k_tran (N/m)
    alignas(64) double to_j[kSize][4];         // into disc j: fx, fy, torque_j, k_tran
    alignas(64) double to_both[kSize][2];      // into both: k_rot (N/m), half the dissipation (J/m)
    alignas(32) int32_t touching[kSize];       // 1 or 0

    // force on j (B), N/m; i gets the opposite
    double fx(size_t b) const { return to_j[b][0]; }
    double fy(size_t b) const { return to_j[b][1]; }
    double torque_i(size_t b) const { return to_i[b][2]; }
    double torque_j(size_t b) const { return to_j[b][2]; }
    double k_tran(size_t b) const { return to_j[b][3]; }
    double k_rot(size_t b) const { return to_both[b][0]; }
    double half_dissipated(size_t b) const { return to_both[b][1]; }
};

// The clearance test, which lets the AVX2 pass skip the candidates that cannot touch yet
// without reading them. approach is a bound, accumulated since the clearances were reset, on
// how much closer any two discs can have come: each integration adds twice the largest
// distance a disc moved (World::integrate_finish). When the pass finds pair k open with a zero
// history, it records clearance[k] = approach + (a lower bound of its gap): the pair cannot
// touch, and its history stays zero, until approach has grown past that; until then it adds
// +0 to every sum and writes back the zeros it holds, so the pass skips it and no bit
// changes. A pair the law found touching gets clearance -1: it is to do in the next step
// without a look (were it open by then, the law adds +0 for it, see PairBatch); one it found
// open (its history just zeroed) gets 0: looked at next step. The floats are
// rounded towards safety: approach_lo <= approach <= approach_hi, and the gap's lower bound
// is shrunk by 2^-20 of the lengths it is made of (far more than the rounding of the float
// arithmetic, 2^-24 per operation).
struct PairSkip {
    float* clearance;   // per contact, m (parallel to the contact list)
    float approach_lo;  // the approach rounded down, m
    float approach_hi;  // the approach rounded up, m
};

// Does this CPU run disc_pairs_avx2? (checked once per World)
bool cpu_has_avx2();

// disc_pair_force for contacts c[0, n) (n <= PairBatch::kSize), four at a time with AVX2, the
// same bits; the results of the pairs with something to do into out (see PairBatch). With
// skip, it first leaves out the pairs whose clearances (skip->clearance[0, n), parallel to c)
// exceed the approach, and updates the clearances of the others (PairSkip). Returns
// how many contacts it covered, from the first: n less n % 4 (the rest do not fill a group of
// four), or fewer when a group of four of the pairs with something to do holds a blown-up pair:
// then it stops before that group's first pair, and writes nothing from there on, for the
// scalar kernel to report. Only call it when cpu_has_avx2().
size_t disc_pairs_avx2(const DiscArrays& d, const PairPassParams& p, DiscContact* c, size_t n, PairBatch& out,
                       const PairSkip* skip = nullptr);

// Does this CPU run disc_pairs_avx512 (AVX-512 F, DQ and VL)? (checked once per World)
bool cpu_has_avx512();

// disc_pairs_avx2 with the law eight pairs at a time in AVX-512 registers (pair_kernel_avx512.cpp):
// the same selection, the same results and bits; a blown-up pair stops it before its group of
// eight. Only call it when cpu_has_avx512().
size_t disc_pairs_avx512(const DiscArrays& d, const PairPassParams& p, DiscContact* c, size_t n, PairBatch& out,
                         const PairSkip* skip = nullptr);

// The law alone for the contacts c + out.index[b], b < out.count (out.count <= PairBatch::kSize,
// filled by the caller; any contacts, touching or not), results into out in that order, the
// histories updated in place: what disc_pair_force gives, the same bits, with an open pair's
// terms +0 (PairBatch). No clearance test. Returns how many it did: out.count, or fewer when a
// group (of four, of eight) holds a blown-up pair; the rest is the scalar kernel's. Only call
// them when cpu_has_avx2(), cpu_has_avx512().
size_t pair_law_avx2(const DiscArrays& d, const PairPassParams& p, DiscContact* c, PairBatch& out);
size_t pair_law_avx512(const DiscArrays& d, const PairPassParams& p, DiscContact* c, PairBatch& out);

// Adds the batch's results into the discs' loads, in the batch's order; c is the batch's first
// contact. Only call it when cpu_has_avx2().
void add_pair_batch_avx2(const PairBatch& batch, const DiscContact* c, DiscLoad* load);

}  // namespace demlab
