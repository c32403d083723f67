// The disc-disc kernel over two candidate pairs at once, in SSE2 (part of every x86-64, so
// there is nothing to detect at run time). It computes what disc_pair_force (pair_kernel.h)
// computes, operation for operation, so it gives the same bits:
//   - every operation is a single IEEE operation in both (add, sub, mul, div, sqrt), and no
//     product is fused into an add (SSE2 has no FMA; scalar x86-64 code without -march has
//     none either);
//   - min/max take maxpd's operand order that reproduces std::max(a, b) = (a < b) ? b : a,
//     signed zeros and NaNs included (max_std, min_std below);
//   - a pair that does not touch is computed too, and its lane then takes the values the
//     scalar path's early return gives (select, without a branch).
// Why: in a flow about 40 % of the candidates do not touch, in no order a branch predictor
// can learn, and the scalar path's "touching?" branch was mispredicted on half of them
// (cachegrind, docs/performance.md). Two lanes also share the latency of the square root and
// the division, which sit in every touching pair's chain.
// Test: Kernel.TwoLanesGiveTheScalarBits (tests/test_contact_law.cpp) over random pairs in
// every dashpot mode; the flume regression and the DB-9k checksum are unchanged.
#pragma once
#include <emmintrin.h>

#include "pair_kernel.h"

namespace demlab {

namespace sse2 {

// Two doubles, lane 0 and lane 1.
struct D2 {
    __m128d v;
};
inline D2 operator+(D2 a, D2 b) { return {_mm_add_pd(a.v, b.v)}; }
inline D2 operator-(D2 a, D2 b) { return {_mm_sub_pd(a.v, b.v)}; }
inline D2 operator*(D2 a, D2 b) { return {_mm_mul_pd(a.v, b.v)}; }
inline D2 operator/(D2 a, D2 b) { return {_mm_div_pd(a.v, b.v)}; }
inline D2 neg(D2 a) { return {_mm_xor_pd(a.v, _mm_set1_pd(-0.0))}; }  // -a: flips the sign bit, as scalar negation
inline D2 abs(D2 a) { return {_mm_andnot_pd(_mm_set1_pd(-0.0), a.v)}; }  // std::abs: clears it
inline D2 sqrt(D2 a) { return {_mm_sqrt_pd(a.v)}; }
inline D2 lanes(double l0, double l1) { return {_mm_set_pd(l1, l0)}; }
inline D2 splat(double x) { return {_mm_set1_pd(x)}; }
inline double lane0(D2 a) { return _mm_cvtsd_f64(a.v); }
inline double lane1(D2 a) { return _mm_cvtsd_f64(_mm_unpackhi_pd(a.v, a.v)); }
// std::max(a, b) is (a < b) ? b : a; maxpd(x, y) is x > y ? x : y, else y (also for NaN and
// for two zeros): maxpd(b, a) is the same choice in every case. Likewise for min.
inline D2 max_std(D2 a, D2 b) { return {_mm_max_pd(b.v, a.v)}; }
inline D2 min_std(D2 a, D2 b) { return {_mm_min_pd(b.v, a.v)}; }

// A lane mask: all ones or all zeros per lane.
struct M2 {
    __m128d m;
};
inline M2 operator&(M2 a, M2 b) { return {_mm_and_pd(a.m, b.m)}; }
inline M2 operator|(M2 a, M2 b) { return {_mm_or_pd(a.m, b.m)}; }
inline M2 all_lanes(bool c) { return {c ? _mm_castsi128_pd(_mm_set1_epi32(-1)) : _mm_setzero_pd()}; }
inline M2 less(D2 a, D2 b) { return {_mm_cmplt_pd(a.v, b.v)}; }
inline M2 greater(D2 a, D2 b) { return {_mm_cmpgt_pd(a.v, b.v)}; }
inline M2 not_greater_equal(D2 a, D2 b) { return {_mm_cmpnge_pd(a.v, b.v)}; }  // true for NaN
inline M2 not_less_equal(D2 a, D2 b) { return {_mm_cmpnle_pd(a.v, b.v)}; }     // true for NaN
inline M2 equal(D2 a, D2 b) { return {_mm_cmpeq_pd(a.v, b.v)}; }
inline M2 not_equal(D2 a, D2 b) { return {_mm_cmpneq_pd(a.v, b.v)}; }
// c ? a : b per lane, the exact bits of one side (as select() in contact_law.h)
inline D2 select(M2 c, D2 a, D2 b) { return {_mm_or_pd(_mm_and_pd(c.m, a.v), _mm_andnot_pd(c.m, b.v))}; }
inline int bits(M2 c) { return _mm_movemask_pd(c.m); }  // bit l: lane l

inline D2 load_x(const Vec2& a, const Vec2& b) { return lanes(a.x(), b.x()); }
inline D2 load_y(const Vec2& a, const Vec2& b) { return lanes(a.y(), b.y()); }

}  // namespace sse2

// disc_pair_force for contacts c0 (lane 0) and c1 (lane 1). Writes o0, o1 and the two
// histories like the scalar kernel, with one difference the callers rely on: a pair that does
// not touch gets zero force, torques and stiffnesses (the scalar kernel's add_to_* skip them;
// the range pass adds them, which changes no bit: see World::compute_forces). Returns a bit
// per lane that faulted (overlap beyond max_overlap_ratio of the smaller radius, or
// coincident centres), with its overlap in overlap[l]; a faulted lane's history is left
// alone, as the scalar kernel's, and its output is not to be used.
[[gnu::always_inline]] inline int disc_pair_force_x2(const DiscArrays& d, const PairPassParams& p, DiscContact& c0,
                                                      DiscContact& c1, PairOut& o0, PairOut& o1, double overlap[2]) {
    using namespace sse2;
    const size_t i0 = size_t(c0.i), j0 = size_t(c0.j), i1 = size_t(c1.i), j1 = size_t(c1.j);
    // dx = pos[j] - pos[i], per component as Eigen does it
    const D2 dxx = load_x(d.pos[j0], d.pos[j1]) - load_x(d.pos[i0], d.pos[i1]);
    const D2 dxy = load_y(d.pos[j0], d.pos[j1]) - load_y(d.pos[i0], d.pos[i1]);
    const D2 ri = lanes(d.radius[i0], d.radius[i1]), rj = lanes(d.radius[j0], d.radius[j1]);
    const D2 rsum = ri + rj;
    const D2 dist2 = dxx * dxx + dxy * dxy;
    // the scalar path leaves when dist2 >= rsum^2; everything else (NaN too) goes on
    const M2 touch = not_greater_equal(dist2, rsum * rsum);
    const D2 dist = sqrt(dist2);
    const D2 ov = rsum - dist;
    const M2 fault = touch & (not_less_equal(ov, splat(p.max_overlap_ratio) * min_std(ri, rj)) | equal(dist, splat(0.0)));
    const D2 nx = dxx / dist, ny = dxy / dist;
    const D2 tx = neg(ny), ty = nx;  // t = perp(n)
    const D2 half_ov = splat(0.5) * ov;
    const D2 ra = ri - half_ov, rb = rj - half_ov;
    const D2 vx = load_x(d.vel[j0], d.vel[j1]) - load_x(d.vel[i0], d.vel[i1]);
    const D2 vy = load_y(d.vel[j0], d.vel[j1]) - load_y(d.vel[i0], d.vel[i1]);
    const D2 vn = vx * nx + vy * ny;
    const D2 vt = vx * tx + vy * ty;
    const D2 wi = lanes(d.omega[i0], d.omega[i1]), wj = lanes(d.omega[j0], d.omega[j1]);
    const D2 vs = vt - (wi * ra + wj * rb);  // eq. 2.46, lever arms to PFC's contact point

    const PairMaterial& m0 = p.materials[size_t(d.material[i0]) * p.n_materials + size_t(d.material[j0])];
    const PairMaterial& m1 = p.materials[size_t(d.material[i1]) * p.n_materials + size_t(d.material[j1])];
    const D2 kn = lanes(m0.kn, m1.kn), ks = lanes(m0.ks, m1.ks), mu = lanes(m0.mu, m1.mu);
    const D2 cn = lanes(c0.cn, c1.cn), cs = lanes(c0.cs, c1.cs);
    const D2 dt = splat(p.dt), last_dt = splat(p.last_dt), zero = splat(0.0);
    const D2 old_damp_n = lanes(double(c0.damp_n), double(c1.damp_n));
    const D2 old_damp_s = lanes(double(c0.damp_s), double(c1.damp_s));

    // linear_contact (contact_law.h), line for line
    const D2 fn_spring = kn * ov;
    const D2 damp_n_free = neg(cn) * vn;
    const D2 fn_free = fn_spring + damp_n_free;
    const bool no_tension = p.mode == DashpotMode::NoTension || p.mode == DashpotMode::NoTensionNoShearWhileSliding;
    const M2 cut_tension = all_lanes(no_tension) & less(fn_free, zero);
    const D2 fn = select(cut_tension, zero, fn_free);
    const D2 damp_n = select(cut_tension, neg(fn_spring), damp_n_free);
    const D2 fs_trial = lanes(c0.fs, c1.fs) - ks * vs * dt;
    const D2 fs_max = mu * fn_spring;
    const D2 excess = abs(fs_trial) - fs_max;
    const M2 sliding = greater(excess, zero);
    const D2 fs = min_std(max_std(fs_trial, neg(fs_max)), fs_max);
    const D2 slip_work = fs_max * max_std(excess, zero) * lanes(m0.inv_ks, m1.inv_ks);
    const bool no_shear_sliding =
        p.mode == DashpotMode::NoShearWhileSliding || p.mode == DashpotMode::NoTensionNoShearWhileSliding;
    const D2 damp_s = select(sliding & all_lanes(no_shear_sliding), zero, neg(cs) * vs);
    const D2 ft = fs + damp_s;
    // step_contact: the dashpots' work centred on v(t - dt/2)
    const D2 diss_touch =
        slip_work - splat(0.5) * ((damp_n * dt + old_damp_n * last_dt) * vn + (damp_s * dt + old_damp_s * last_dt) * vs);
    // a contact that opened: the last dashpot force's second half, along the current normal and
    // with the full radii as lever arms; exactly 0.0 when it had none
    const D2 vs_open = vt - (wi * ri + wj * rj);
    const D2 diss_open = splat(-0.5 * p.last_dt) * (old_damp_n * vn + old_damp_s * vs_open);
    const M2 had_damp = not_equal(old_damp_n, zero) | not_equal(old_damp_s, zero);
    const D2 dissipated = select(touch, diss_touch, select(had_damp, diss_open, zero));

    // the new history: the spring and dashpot forces of a touching pair, zero for an open one
    const D2 fs_hist = select(touch, fs, zero);
    const __m128 damp_f = _mm_movelh_ps(_mm_cvtpd_ps(select(touch, damp_n, zero).v), _mm_cvtpd_ps(select(touch, damp_s, zero).v));
    alignas(16) float damp[4];  // n0, n1, s0, s1
    _mm_store_ps(damp, damp_f);

    const D2 fx = select(touch, fn * nx + ft * tx, zero);
    const D2 fy = select(touch, fn * ny + ft * ty, zero);
    const D2 tq_i = select(touch, neg(ra) * ft, zero);  // torque = lever x force: -r ft (docs/engine.md)
    const D2 tq_j = select(touch, neg(rb) * ft, zero);
    const D2 k_tran = select(touch, lanes(m0.k_tran, m1.k_tran), zero);
    const D2 k_rot = select(touch, ks, zero);
    const int touching = bits(touch);
    const int faulted = bits(fault);
    overlap[0] = lane0(ov);
    overlap[1] = lane1(ov);
    o0.f = Vec2(lane0(fx), lane0(fy));
    o0.torque_i = lane0(tq_i);
    o0.torque_j = lane0(tq_j);
    o0.dissipated = lane0(dissipated);
    o0.k_tran = lane0(k_tran);
    o0.k_rot = lane0(k_rot);
    o0.touching = (touching & 1) != 0;
    o1.f = Vec2(lane1(fx), lane1(fy));
    o1.torque_i = lane1(tq_i);
    o1.torque_j = lane1(tq_j);
    o1.dissipated = lane1(dissipated);
    o1.k_tran = lane1(k_tran);
    o1.k_rot = lane1(k_rot);
    o1.touching = (touching & 2) != 0;
    if (!(faulted & 1)) {
        c0.fs = lane0(fs_hist);
        c0.damp_n = damp[0];
        c0.damp_s = damp[2];
    }
    if (!(faulted & 2)) {
        c1.fs = lane1(fs_hist);
        c1.damp_n = damp[1];
        c1.damp_s = damp[3];
    }
    return faulted;
}

}  // namespace demlab
