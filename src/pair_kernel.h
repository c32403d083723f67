// The disc-disc force kernel: one candidate pair, one step of the linear law (contact_law.h),
// as a small function over the discs' state and the pair's history. World's force pass calls
// it either to add a pair straight into both discs' sums (the common case) or to park the
// result in a slot when the two discs belong to different threads (world.cpp).
#pragma once
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "contact_law.h"
#include "vec2.h"

namespace demlab {

// Series stiffnesses and friction of a pair of materials (eq. 2.59, 2.61).
struct PairMaterial {
    double kn, ks, mu;
    double k_tran;  // max(kn, ks): the pair's share of the automatic step's translational stiffness
    double inv_ks;  // 1 / ks, m/N
};

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

// The step's constants.
struct PairPassParams {
    const PairMaterial* materials;  // [mi * n_materials + mj]
    size_t n_materials;
    DashpotMode mode;
    double dt, last_dt;  // s, this step's and the last one's
    double max_overlap_ratio;
};

// One step of the law for a touching contact: updates the history (shear spring, last
// dashpot forces) and returns the forces; `dissipated` receives the energy the step took out:
// sliding, plus the dashpots' work centred on v(t - dt/2) (this step's force over the first
// half of the velocity interval, the last step's over the second half).
template <typename Contact>
inline LinearContactForce step_contact(const LinearContactParams& p, double overlap, double vn, double vs, double dt,
                                       double last_dt, Contact& c, double& dissipated) {
    const LinearContactForce f = linear_contact(p, overlap, vn, vs, dt, c.fs);
    c.fs = f.fs_spring;
    dissipated = f.slip_work - 0.5 * ((f.damp_n * dt + c.damp_n * last_dt) * vn + (f.damp_s * dt + c.damp_s * last_dt) * vs);
    c.damp_n = float(f.damp_n);
    c.damp_s = float(f.damp_s);
    return f;
}

// Pair (c.i, c.j): n from i (A) to j (B); the force on j is F = fn n + ft t, on i -F.
// Returns false, with `overlap` set, when the overlap exceeds max_overlap_ratio of the smaller
// radius (or the centres coincide): a blown-up run, which the caller reports.
// Inlined by force: GCC kept it out of line (it has two callers), and the PairOut then went
// through the stack, with a call per candidate; perf put a third of the range pass on the
// return and on reloading the result (docs/performance.md, session 4).
[[gnu::always_inline]] inline bool disc_pair_force(const DiscArrays& d, const PairPassParams& p, DiscContact& c, PairOut& out,
                            double& overlap) {
    const size_t i = size_t(c.i), j = size_t(c.j);
    const Vec2 dx = d.pos[j] - d.pos[i];
    const double rsum = d.radius[i] + d.radius[j];
    const double dist2 = dx.squaredNorm();
    out.touching = false;
    out.dissipated = 0.0;
    if (dist2 >= rsum * rsum) {
        // PFC deletes a contact that opens: its history starts again at zero. The last
        // dashpot force still acted over the second half of the previous step.
        if (c.damp_n != 0.0f || c.damp_s != 0.0f) {
            const Vec2 vrel = d.vel[j] - d.vel[i];
            const Vec2 nrm = dx / std::sqrt(dist2);
            const double vs = vrel.dot(perp(nrm)) - (d.omega[i] * d.radius[i] + d.omega[j] * d.radius[j]);
            out.dissipated = -0.5 * p.last_dt * (c.damp_n * vrel.dot(nrm) + c.damp_s * vs);
        }
        c.fs = 0.0;
        c.damp_n = c.damp_s = 0.0f;
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
    const PairMaterial& pm = p.materials[size_t(d.material[i]) * p.n_materials + size_t(d.material[j])];
    const LinearContactForce f =
        step_contact({pm.kn, pm.ks, pm.mu, c.cn, c.cs, p.mode, pm.inv_ks}, overlap, vn, vs, p.dt, p.last_dt, c, out.dissipated);
    out.f = f.fn * nrm + f.ft * t;
    // torque = lever x force; both levers give -r * ft (docs/engine.md)
    out.torque_i = -ra * f.ft;
    out.torque_j = -rb * f.ft;
    out.k_tran = pm.k_tran;
    out.k_rot = pm.ks;
    out.touching = true;
    return true;
}

// A batch of pairs' results by field (structure of arrays): what disc_pairs_avx2 leaves for
// the force pass to add into the discs in list order. Only the pairs with something to do
// are there: those touching, and those open with a history to end (a pair open before and
// after the step, with an all-zero history, adds +0 to every sum and writes back the zeros
// it read, so it is left out; in DB-9k half the candidates are such). index[b] is result b's
// contact, counted from the batch's first; the results are in list order. An open pair's
// force, torques and stiffnesses are +0, so the force pass adds every result without a
// branch: x + (+0) is x for every x but -0, and a sum that starts at +0 never becomes -0
// (round to nearest), so the sums are the bits the scalar pass gets by skipping open pairs.
struct PairBatch {
    static constexpr size_t kSize = 64;  // pairs; the batch stays in L1 between kernel and gather
    size_t count = 0;                            // results in the batch
    alignas(32) uint32_t index[kSize + 4];       // result b is contact index[b] of the batch
    alignas(32) double fx[kSize], fy[kSize];     // force on j (B), N/m; i gets the opposite
    alignas(32) double torque_i[kSize], torque_j[kSize];  // N m / m
    alignas(32) double dissipated[kSize];        // J/m, half to each disc
    alignas(32) double k_tran[kSize], k_rot[kSize];  // N/m, the pair's stiffnesses for the step bound
    alignas(32) int32_t touching[kSize];         // 1 or 0
};

// Does this CPU run disc_pairs_avx2? (checked once per World)
bool cpu_has_avx2();

// disc_pair_force for contacts c[0, n) (n <= PairBatch::kSize), four at a time with AVX2, the
// same bits; the results of the pairs with something to do into out (see PairBatch). Returns
// how many contacts it covered, from the first: n less n % 4 (the rest do not fill a group of
// four), or fewer when a group of four of the pairs with something to do holds a blown-up pair:
// then it stops before that group's first pair, and writes nothing from there on, for the
// scalar kernel to report. Only call it when cpu_has_avx2().
size_t disc_pairs_avx2(const DiscArrays& d, const PairPassParams& p, DiscContact* c, size_t n, PairBatch& out);

}  // namespace demlab
