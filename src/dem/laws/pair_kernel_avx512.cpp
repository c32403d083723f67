// The disc-disc law of pair_kernel.h eight pairs at a time, in AVX-512 registers, for the CPUs
// that have AVX-512 (F, DQ, VL); the others use pair_kernel_avx2.cpp. The selection stages are
// the AVX2 kernel's (pair_select_avx2.h), and the results go into the same PairBatch.
//
// Why a wider law when the arithmetic per pair is the same: the AVX2 law ran at about four
// instructions per cycle, bound by the number of instructions, and a fifth of those were
// stack spills and reloads (16 vector registers for a law with more live values than that).
// Eight lanes halve the arithmetic instructions per pair, and 32 registers hold the law's
// values. The loads and stores cost what they did per pair: AVX-512's gathers and scatters
// ran no faster than scalar loads on Zen 4 (about one element a cycle, measured), so the
// discs' state and the contacts' histories are loaded and stored as in the AVX2 kernel.
//
// Same bits as disc_pair_force, for the AVX2 kernel's reasons (pair_kernel_avx2.cpp): every
// lane does the scalar kernel's operations in its order; no FMA (AVX-512F includes FMA, so this
// file is compiled with -ffp-contract=off, CMakeLists.txt, and no intrinsic here fuses);
// min/max with std::min/std::max's operand order (_mm512_max_pd(b, a) is (a < b) ? b : a); the
// selects become masked blends on the same conditions. Masked zeroing gives +0, as the AVX2
// kernel's and with an all-zero mask does.
#include <immintrin.h>

#include <cstddef>
#include <cstring>

#include "dem/laws/pair_kernel.h"
#include "dem/laws/pair_select_avx2.h"

// GCC 12's AVX-512 intrinsics pass an _mm512_undefined_pd() operand to their masked builtins,
// and -Wmaybe-uninitialized reports it wherever they are inlined (GCC bug 105593): a false
// positive of the compiler's own headers, silenced for this file only.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif

namespace demlab {

bool cpu_has_avx512() {
#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
    return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") &&
           __builtin_cpu_supports("avx512vl");
#else
    return false;
#endif
}

#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
#define DEMLAB_AVX512 [[gnu::target("avx2,avx512f,avx512dq,avx512vl"), gnu::always_inline]] static inline

namespace {

// (lo, hi) as one register
DEMLAB_AVX512 __m512d join(__m256d lo, __m256d hi) { return _mm512_insertf64x4(_mm512_castpd256_pd512(lo), hi, 1); }

// Eight (x, y) pairs from an array of Vec2 (two doubles each), as an x and a y register.
DEMLAB_AVX512 __m512d xy4(const double* a, size_t i0, size_t i1, size_t i2, size_t i3) {
    const __m256d a01 = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(a + 2 * i0)), _mm_loadu_pd(a + 2 * i1), 1);
    const __m256d a23 = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(a + 2 * i2)), _mm_loadu_pd(a + 2 * i3), 1);
    return join(a01, a23);  // x0 y0 x1 y1 x2 y2 x3 y3
}
DEMLAB_AVX512 void load_xy8(const double* a, const size_t* k, __m512d& x, __m512d& y) {
    const __m512d lo = xy4(a, k[0], k[1], k[2], k[3]), hi = xy4(a, k[4], k[5], k[6], k[7]);
    x = _mm512_permutex2var_pd(lo, _mm512_setr_epi64(0, 2, 4, 6, 8, 10, 12, 14), hi);
    y = _mm512_permutex2var_pd(lo, _mm512_setr_epi64(1, 3, 5, 7, 9, 11, 13, 15), hi);
}

DEMLAB_AVX512 __m512d load8(const double* a, const size_t* k) {
    const __m256d lo = _mm256_set_pd(a[k[3]], a[k[2]], a[k[1]], a[k[0]]);
    const __m256d hi = _mm256_set_pd(a[k[7]], a[k[6]], a[k[5]], a[k[4]]);
    return join(lo, hi);
}

// a double field of eight contacts
template <typename F>
DEMLAB_AVX512 __m512d field8(DiscContact* const* q, F f) {
    const __m256d lo = _mm256_set_pd(f(*q[3]), f(*q[2]), f(*q[1]), f(*q[0]));
    const __m256d hi = _mm256_set_pd(f(*q[7]), f(*q[6]), f(*q[5]), f(*q[4]));
    return join(lo, hi);
}
// a float field of eight contacts, as doubles (exact)
template <typename F>
DEMLAB_AVX512 __m512d float_field8(DiscContact* const* q, F f) {
    return _mm512_cvtps_pd(_mm256_set_ps(f(*q[7]), f(*q[6]), f(*q[5]), f(*q[4]), f(*q[3]), f(*q[2]), f(*q[1]), f(*q[0])));
}

DEMLAB_AVX512 __m512d neg(__m512d a) { return _mm512_xor_pd(a, _mm512_set1_pd(-0.0)); }

// c ? a : b, lane by lane
DEMLAB_AVX512 __m512d blend(__mmask8 c, __m512d a, __m512d b) { return _mm512_mask_blend_pd(c, b, a); }

// c ? a : +0
DEMLAB_AVX512 __m512d keep(__mmask8 c, __m512d a) { return _mm512_maskz_mov_pd(c, a); }

// Four registers whose lanes are pairs, as eight records rows[l] = {a[l], b[l], c[l], d[l]}.
DEMLAB_AVX512 void store_rows8(double (*rows)[4], __m512d a, __m512d b, __m512d c, __m512d d) {
    const __m512d ab0 = _mm512_unpacklo_pd(a, b), ab1 = _mm512_unpackhi_pd(a, b);  // a0 b0 a2 b2 .., a1 b1 a3 b3 ..
    const __m512d cd0 = _mm512_unpacklo_pd(c, d), cd1 = _mm512_unpackhi_pd(c, d);
    // 128-bit lanes: ab0 = (p0, p2, p4, p6), ab1 = (p1, p3, p5, p7) of (a, b); the same of (c, d)
    const __m512d x0 = _mm512_shuffle_f64x2(ab0, cd0, 0x44);  // ab p0, ab p2, cd p0, cd p2
    const __m512d x1 = _mm512_shuffle_f64x2(ab1, cd1, 0x44);  // ab p1, ab p3, cd p1, cd p3
    const __m512d x2 = _mm512_shuffle_f64x2(ab0, cd0, 0xEE);  // ab p4, ab p6, cd p4, cd p6
    const __m512d x3 = _mm512_shuffle_f64x2(ab1, cd1, 0xEE);  // ab p5, ab p7, cd p5, cd p7
    // rows p, p+1 side by side: (ab p, cd p, ab p+1, cd p+1)
    _mm512_store_pd(rows[0], _mm512_shuffle_f64x2(x0, x1, 0x88));  // x0 lanes 0, 2; x1 lanes 0, 2
    _mm512_store_pd(rows[2], _mm512_shuffle_f64x2(x0, x1, 0xDD));  // x0 lanes 1, 3; x1 lanes 1, 3
    _mm512_store_pd(rows[4], _mm512_shuffle_f64x2(x2, x3, 0x88));
    _mm512_store_pd(rows[6], _mm512_shuffle_f64x2(x2, x3, 0xDD));
}

struct PairLanes8 {
    __m512d kn, ks, mu, inv_ks, k_tran;
};

DEMLAB_AVX512 PairLanes8 broadcast_lanes8(const PairMaterial& m) {
    return {_mm512_set1_pd(m.kn), _mm512_set1_pd(m.ks), _mm512_set1_pd(m.mu), _mm512_set1_pd(m.inv_ks),
            _mm512_set1_pd(m.k_tran)};
}

DEMLAB_AVX512 PairLanes8 pair_lanes8(const PairPassParams& p, const DiscArrays& d, const size_t* i, const size_t* j) {
    alignas(64) double kn[8], ks[8], mu[8], inv_ks[8], k_tran[8];
    for (int l = 0; l < 8; ++l) {
        const PairMaterial& pm = p.materials[size_t(d.material[i[l]]) * p.n_materials + size_t(d.material[j[l]])];
        kn[l] = pm.kn;
        ks[l] = pm.ks;
        mu[l] = pm.mu;
        inv_ks[l] = pm.inv_ks;
        k_tran[l] = pm.k_tran;
    }
    return {_mm512_load_pd(kn), _mm512_load_pd(ks), _mm512_load_pd(mu), _mm512_load_pd(inv_ks), _mm512_load_pd(k_tran)};
}

// The law for the contacts c + out.index[b], b < out.count (padded to a multiple of eight),
// as pair_kernel_avx2.cpp's law: returns how many it did.
template <bool kOneMaterial>
DEMLAB_AVX512 size_t law8(const DiscArrays& d, const PairPassParams& p, DiscContact* c, PairBatch& out, const PairSkip* skip) {
    const PairLanes8 one = kOneMaterial ? broadcast_lanes8(p.materials[0]) : PairLanes8{};
    const double* pos = d.pos->data();
    const double* vel = d.vel->data();
    const bool no_tension = p.mode == DashpotMode::NoTension || p.mode == DashpotMode::NoTensionNoShearWhileSliding;
    const bool no_shear_sliding =
        p.mode == DashpotMode::NoShearWhileSliding || p.mode == DashpotMode::NoTensionNoShearWhileSliding;
    const __mmask8 no_tension_m = no_tension ? 0xFF : 0, no_shear_sliding_m = no_shear_sliding ? 0xFF : 0;
    const __m512d zero = _mm512_setzero_pd();
    const __m512d half = _mm512_set1_pd(0.5);
    const __m512d dt = _mm512_set1_pd(p.dt), last_dt = _mm512_set1_pd(p.last_dt);
    const __m512d minus_half_last_dt = _mm512_set1_pd(-0.5 * p.last_dt);
    const __m512d ratio = _mm512_set1_pd(p.max_overlap_ratio);
    const size_t m = out.count;

    // The law, eight of the selected pairs at a time (pair_kernel_avx2.cpp has the same
    // operations on four; the comments there).
    for (size_t g = 0; g < m; g += 8) {
        DiscContact* q[8];
        size_t i[8], j[8];
        for (int l = 0; l < 8; ++l) {
            q[l] = c + out.index[g + size_t(l)];
            i[l] = size_t(q[l]->i);
            j[l] = size_t(q[l]->j);
        }
        __m512d xi, yi, xj, yj;
        load_xy8(pos, i, xi, yi);
        load_xy8(pos, j, xj, yj);
        const __m512d ri = load8(d.radius, i), rj = load8(d.radius, j);
        const __m512d dxx = _mm512_sub_pd(xj, xi), dxy = _mm512_sub_pd(yj, yi);
        const __m512d rsum = _mm512_add_pd(ri, rj);
        const __m512d dist2 = _mm512_add_pd(_mm512_mul_pd(dxx, dxx), _mm512_mul_pd(dxy, dxy));
        const __mmask8 touching = _mm512_cmp_pd_mask(dist2, _mm512_mul_pd(rsum, rsum), _CMP_NGE_UQ);
        const __m512d dist = _mm512_sqrt_pd(dist2);
        const __m512d overlap = _mm512_sub_pd(rsum, dist);
        const __mmask8 fault =
            touching & (_mm512_cmp_pd_mask(overlap, _mm512_mul_pd(ratio, _mm512_min_pd(rj, ri)), _CMP_NLE_UQ) |
                        _mm512_cmp_pd_mask(dist, zero, _CMP_EQ_OQ));
        // a blown-up pair: leave this group untouched, stop before its first pair
        if (fault != 0) {
            out.count = g;
            return g;
        }

        const __m512d nx = _mm512_div_pd(dxx, dist), ny = _mm512_div_pd(dxy, dist);
        const __m512d tx = neg(ny);
        __m512d vxi, vyi, vxj, vyj;
        load_xy8(vel, i, vxi, vyi);
        load_xy8(vel, j, vxj, vyj);
        const __m512d vrx = _mm512_sub_pd(vxj, vxi), vry = _mm512_sub_pd(vyj, vyi);
        const __m512d wi = load8(d.omega, i), wj = load8(d.omega, j);
        const __m512d vn = _mm512_add_pd(_mm512_mul_pd(vrx, nx), _mm512_mul_pd(vry, ny));
        const __m512d vt = _mm512_add_pd(_mm512_mul_pd(vrx, tx), _mm512_mul_pd(vry, nx));
        const __m512d half_overlap = _mm512_mul_pd(half, overlap);
        const __m512d ra = _mm512_sub_pd(ri, half_overlap), rb = _mm512_sub_pd(rj, half_overlap);
        const __m512d vs = _mm512_sub_pd(vt, _mm512_add_pd(_mm512_mul_pd(wi, ra), _mm512_mul_pd(wj, rb)));

        const PairLanes8 pl = kOneMaterial ? one : pair_lanes8(p, d, i, j);
        const __m512d kn = pl.kn, ks = pl.ks, mu = pl.mu, inv_ks = pl.inv_ks;
        const __m512d cn = field8(q, [](const DiscContact& x) { return x.cn; });
        const __m512d cs = field8(q, [](const DiscContact& x) { return x.cs; });
        const __m512d fs_old = field8(q, [](const DiscContact& x) { return x.fs; });
        const __m512d damp_n_old = float_field8(q, [](const DiscContact& x) { return x.damp_n; });
        const __m512d damp_s_old = float_field8(q, [](const DiscContact& x) { return x.damp_s; });

        // linear_contact (contact_law.h), operation for operation
        const __m512d fn_spring = _mm512_mul_pd(kn, overlap);
        const __m512d damp_n_free = _mm512_mul_pd(neg(cn), vn);
        const __m512d fn_free = _mm512_add_pd(fn_spring, damp_n_free);
        const __mmask8 cut_tension = no_tension_m & _mm512_cmp_pd_mask(fn_free, zero, _CMP_LT_OQ);
        const __m512d fn = blend(cut_tension, zero, fn_free);
        const __m512d fn_damp = blend(cut_tension, neg(fn_spring), damp_n_free);
        const __m512d fs_trial = _mm512_sub_pd(fs_old, _mm512_mul_pd(_mm512_mul_pd(ks, vs), dt));
        const __m512d fs_max = _mm512_mul_pd(mu, fn_spring);
        const __m512d excess = _mm512_sub_pd(_mm512_andnot_pd(_mm512_set1_pd(-0.0), fs_trial), fs_max);
        const __mmask8 sliding = _mm512_cmp_pd_mask(excess, zero, _CMP_GT_OQ);
        const __m512d fs = _mm512_min_pd(fs_max, _mm512_max_pd(neg(fs_max), fs_trial));
        const __m512d slip_work = _mm512_mul_pd(_mm512_mul_pd(fs_max, _mm512_max_pd(zero, excess)), inv_ks);
        const __m512d fs_damp = blend(sliding & no_shear_sliding_m, zero, _mm512_mul_pd(neg(cs), vs));
        const __m512d ft = _mm512_add_pd(fs, fs_damp);
        // LinearLaw::step: the dashpots' work centred on v(t - dt/2)
        const __m512d work_n = _mm512_mul_pd(_mm512_add_pd(_mm512_mul_pd(fn_damp, dt), _mm512_mul_pd(damp_n_old, last_dt)), vn);
        const __m512d work_s = _mm512_mul_pd(_mm512_add_pd(_mm512_mul_pd(fs_damp, dt), _mm512_mul_pd(damp_s_old, last_dt)), vs);
        const __m512d diss_touching = _mm512_sub_pd(slip_work, _mm512_mul_pd(half, _mm512_add_pd(work_n, work_s)));

        // an open pair: the last dashpot forces' second half, with the radii as lever arms
        const __m512d vs_open = _mm512_sub_pd(vt, _mm512_add_pd(_mm512_mul_pd(wi, ri), _mm512_mul_pd(wj, rj)));
        const __mmask8 had_dashpots =
            _mm512_cmp_pd_mask(damp_n_old, zero, _CMP_NEQ_UQ) | _mm512_cmp_pd_mask(damp_s_old, zero, _CMP_NEQ_UQ);
        const __m512d diss_open = keep(
            had_dashpots,
            _mm512_mul_pd(minus_half_last_dt, _mm512_add_pd(_mm512_mul_pd(damp_n_old, vn), _mm512_mul_pd(damp_s_old, vs_open))));

        // results: force on j = fn n + ft t; torques -r ft; +0 for an open pair (PairBatch)
        const __m512d fx = keep(touching, _mm512_add_pd(_mm512_mul_pd(fn, nx), _mm512_mul_pd(ft, tx)));
        const __m512d fy = keep(touching, _mm512_add_pd(_mm512_mul_pd(fn, ny), _mm512_mul_pd(ft, nx)));
        const __m512d torque_i = keep(touching, _mm512_mul_pd(neg(ra), ft));
        const __m512d torque_j = keep(touching, _mm512_mul_pd(neg(rb), ft));
        const __m512d k_tran_t = keep(touching, pl.k_tran);
        store_rows8(out.to_i + g, neg(fx), neg(fy), torque_i, k_tran_t);
        store_rows8(out.to_j + g, fx, fy, torque_j, k_tran_t);
        const __m512d k_rot = keep(touching, ks);
        const __m512d half_dissipated = _mm512_mul_pd(half, blend(touching, diss_touching, diss_open));
        // (k_rot, half_dissipated) per pair: 128-bit lanes p0 p2 p4 p6 and p1 p3 p5 p7
        const __m512d lo = _mm512_unpacklo_pd(k_rot, half_dissipated), hi = _mm512_unpackhi_pd(k_rot, half_dissipated);
        const __m512d both_lo = _mm512_shuffle_f64x2(lo, hi, 0x44);  // p0 p2 p1 p3
        const __m512d both_hi = _mm512_shuffle_f64x2(lo, hi, 0xEE);  // p4 p6 p5 p7
        _mm512_store_pd(out.to_both[g], _mm512_shuffle_f64x2(both_lo, both_lo, 0xD8));      // p0 p1 p2 p3
        _mm512_store_pd(out.to_both[g + 4], _mm512_shuffle_f64x2(both_hi, both_hi, 0xD8));  // p4 p5 p6 p7
        _mm256_store_si256(reinterpret_cast<__m256i*>(out.touching + g), _mm256_maskz_set1_epi32(touching, 1));
        // the histories: an open pair starts again from zero (PFC deletes it)
        alignas(64) double fs_new[8];
        alignas(32) float dn_new[8], ds_new[8];
        _mm512_store_pd(fs_new, keep(touching, fs));
        _mm256_store_ps(dn_new, _mm512_cvtpd_ps(keep(touching, fn_damp)));
        _mm256_store_ps(ds_new, _mm512_cvtpd_ps(keep(touching, fs_damp)));
        for (int l = 0; l < 8; ++l) {
            q[l]->fs = fs_new[l];
            q[l]->damp_n = dn_new[l];
            q[l]->damp_s = ds_new[l];
        }
        // the clearance test: a touching pair is to do next step without a look (-1); an open
        // one, with the zero history just written, is looked at (0)
        if (skip) {
            alignas(32) float v[8];
            _mm256_store_ps(v, _mm256_maskz_mov_ps(touching, _mm256_set1_ps(-1.0f)));
            for (int l = 0; l < 8; ++l) skip->clearance[out.index[g + size_t(l)]] = v[l];
        }
    }
    return m;
}

template <bool kOneMaterial>
DEMLAB_AVX512 size_t disc_pairs8(const DiscArrays& d, const PairPassParams& p, DiscContact* c, size_t n, PairBatch& out,
                                 const PairSkip* skip) {
    const size_t covered = pair_select::select_pairs(d, c, n, out, skip, 8);
    const size_t m = out.count;
    const size_t done = law8<kOneMaterial>(d, p, c, out, skip);
    return done < m ? out.index[done] : covered;
}

}  // namespace

[[gnu::target("avx2,avx512f,avx512dq,avx512vl")]] size_t disc_pairs_avx512(const DiscArrays& d, const PairPassParams& p,
                                                                             DiscContact* c, size_t n, PairBatch& out,
                                                                             const PairSkip* skip) {
    return p.n_materials == 1 ? disc_pairs8<true>(d, p, c, n, out, skip) : disc_pairs8<false>(d, p, c, n, out, skip);
}

[[gnu::target("avx2,avx512f,avx512dq,avx512vl")]] size_t pair_law_avx512(const DiscArrays& d, const PairPassParams& p,
                                                                           DiscContact* c, PairBatch& out) {
    const size_t m = out.count;
    if (m == 0) return 0;
    for (size_t l = m; l % 8 != 0; ++l) out.index[l] = out.index[m - 1];  // padding: the last pair again
    return p.n_materials == 1 ? law8<true>(d, p, c, out, nullptr) : law8<false>(d, p, c, out, nullptr);
}
#else
size_t pair_law_avx512(const DiscArrays&, const PairPassParams&, DiscContact*, PairBatch&) { return 0; }
size_t disc_pairs_avx512(const DiscArrays&, const PairPassParams&, DiscContact*, size_t, PairBatch&, const PairSkip*) {
    return 0;
}
#endif

}  // namespace demlab
