// Lanes of doubles, eight in an AVX-512 register (F, DQ, VL): the names of lanes_avx2.h (which
// says what each does) for the lane set Avx512. Masks are mask registers, and keep(m, a) is a
// zeroing move: +0 in the lanes left out, as the AVX2 form's and with an all-zero lane.
//
// Why eight lanes when the arithmetic per lane is the same: the AVX2 kernels ran at about four
// instructions per cycle, bound by the number of instructions, and in the law a fifth of those
// were stack spills and reloads (16 vector registers for more live values than that). Eight
// lanes halve the arithmetic instructions per lane, and 32 registers hold the law's values.
// AVX-512's gathers and scatters ran no faster than scalar loads on Zen 4 (about one element a
// cycle, measured), so gather and load_xy_at load lane by lane, as the AVX2 forms do.
//
// AVX-512F includes FMA: the files that use these are compiled with -ffp-contract=off
// (CMakeLists.txt), so that a * b + c stays two roundings, and no helper here fuses.
#pragma once
#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
#include <immintrin.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>

#include "dem/lanes/lanes_avx2.h"

// GCC 12's AVX-512 intrinsics pass an _mm512_undefined_pd() operand to their masked builtins,
// and -Wmaybe-uninitialized reports it wherever they are inlined (GCC bug 105593): a false
// positive of the compiler's own headers, silenced for the files that use these.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif

#define DEMLAB_LANES_AVX512 [[gnu::target("avx2,avx512f,avx512dq,avx512vl"), gnu::always_inline]] inline

namespace demlab::lanes {

struct D8 {
    __m512d v;
};
struct M8 {
    __mmask8 m;
};
struct I8 {
    __m512i v;
};

DEMLAB_LANES_AVX512 D8 operator+(D8 a, D8 b) { return {_mm512_add_pd(a.v, b.v)}; }
DEMLAB_LANES_AVX512 D8 operator-(D8 a, D8 b) { return {_mm512_sub_pd(a.v, b.v)}; }
DEMLAB_LANES_AVX512 D8 operator*(D8 a, D8 b) { return {_mm512_mul_pd(a.v, b.v)}; }
DEMLAB_LANES_AVX512 D8 operator/(D8 a, D8 b) { return {_mm512_div_pd(a.v, b.v)}; }
DEMLAB_LANES_AVX512 D8 operator-(D8 a) { return {_mm512_xor_pd(a.v, _mm512_set1_pd(-0.0))}; }
DEMLAB_LANES_AVX512 D8 sqrt(D8 a) { return {_mm512_sqrt_pd(a.v)}; }
DEMLAB_LANES_AVX512 D8 abs(D8 a) { return {_mm512_andnot_pd(_mm512_set1_pd(-0.0), a.v)}; }
DEMLAB_LANES_AVX512 D8 min(D8 a, D8 b) { return {_mm512_min_pd(a.v, b.v)}; }
DEMLAB_LANES_AVX512 D8 max(D8 a, D8 b) { return {_mm512_max_pd(a.v, b.v)}; }
template <int P>
DEMLAB_LANES_AVX512 M8 cmp(D8 a, D8 b) {
    return {_mm512_cmp_pd_mask(a.v, b.v, P)};
}
DEMLAB_LANES_AVX512 M8 operator&(M8 a, M8 b) { return {__mmask8(a.m & b.m)}; }
DEMLAB_LANES_AVX512 M8 operator|(M8 a, M8 b) { return {__mmask8(a.m | b.m)}; }
DEMLAB_LANES_AVX512 unsigned bits(M8 m) { return unsigned(m.m); }
DEMLAB_LANES_AVX512 bool any(M8 m) { return m.m != 0; }
DEMLAB_LANES_AVX512 bool all(M8 m) { return m.m == 0xFF; }
DEMLAB_LANES_AVX512 D8 select(M8 m, D8 a, D8 b) { return {_mm512_mask_blend_pd(m.m, b.v, a.v)}; }
DEMLAB_LANES_AVX512 D8 keep(M8 m, D8 a) { return {_mm512_maskz_mov_pd(m.m, a.v)}; }

DEMLAB_LANES_AVX512 I8 operator+(I8 a, I8 b) { return {_mm512_add_epi64(a.v, b.v)}; }
DEMLAB_LANES_AVX512 I8 operator&(I8 a, I8 b) { return {_mm512_and_si512(a.v, b.v)}; }
DEMLAB_LANES_AVX512 I8 keep(M8 m, I8 a) { return {_mm512_maskz_mov_epi64(m.m, a.v)}; }
DEMLAB_LANES_AVX512 M8 greater(I8 a, I8 b) { return {_mm512_cmpgt_epi64_mask(a.v, b.v)}; }
template <int K>
DEMLAB_LANES_AVX512 I8 shift_left(I8 a) {
    return {_mm512_slli_epi64(a.v, K)};
}

struct Avx512 {
    static constexpr size_t kWidth = 8;
    using D = D8;
    using M = M8;
    using I = I8;

    DEMLAB_LANES_AVX512 static D set1(double x) { return {_mm512_set1_pd(x)}; }
    DEMLAB_LANES_AVX512 static D zero() { return {_mm512_setzero_pd()}; }
    DEMLAB_LANES_AVX512 static M mask(bool b) { return {__mmask8(b ? 0xFF : 0)}; }
    DEMLAB_LANES_AVX512 static M first(size_t n) { return {__mmask8((1u << n) - 1u)}; }
    DEMLAB_LANES_AVX512 static I set1_int(int64_t x) { return {_mm512_set1_epi64(x)}; }
    DEMLAB_LANES_AVX512 static I zero_int() { return {_mm512_setzero_si512()}; }
    DEMLAB_LANES_AVX512 static I as_int(D a) { return {_mm512_castpd_si512(a.v)}; }

    // (lo, hi) as one register
    DEMLAB_LANES_AVX512 static __m512d join(__m256d lo, __m256d hi) {
        return _mm512_insertf64x4(_mm512_castpd256_pd512(lo), hi, 1);
    }
    template <typename F>
    DEMLAB_LANES_AVX512 static D gather(F f) {
        return {join(_mm256_set_pd(f(3), f(2), f(1), f(0)), _mm256_set_pd(f(7), f(6), f(5), f(4)))};
    }
    template <typename F>
    DEMLAB_LANES_AVX512 static D gather_float(F f) {
        return {_mm512_cvtps_pd(_mm256_set_ps(f(7), f(6), f(5), f(4), f(3), f(2), f(1), f(0)))};
    }

    DEMLAB_LANES_AVX512 static D load_n(const double* a, size_t n) {
        if (n == 8) return {_mm512_loadu_pd(a)};
        return gather([&](size_t l) { return a[std::min(l, n - 1)]; });
    }
    DEMLAB_LANES_AVX512 static void store_n(double* a, size_t n, D v) {
        if (n == 8)
            _mm512_storeu_pd(a, v.v);
        else
            _mm512_mask_storeu_pd(a, first(n).m, v.v);
    }
    DEMLAB_LANES_AVX512 static void store(double* a, D v) { _mm512_store_pd(a, v.v); }  // aligned
    DEMLAB_LANES_AVX512 static void store_floats(float* a, D v) { _mm256_store_ps(a, _mm512_cvtpd_ps(v.v)); }  // aligned
    DEMLAB_LANES_AVX512 static void store_int(int64_t* a, I v) { _mm512_store_si512(a, v.v); }

    // (x, y) pairs a + 2 k[l], as an x and a y register
    DEMLAB_LANES_AVX512 static __m512d xy4(const double* a, size_t i0, size_t i1, size_t i2, size_t i3) {
        const __m256d a01 = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(a + 2 * i0)), _mm_loadu_pd(a + 2 * i1), 1);
        const __m256d a23 = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(a + 2 * i2)), _mm_loadu_pd(a + 2 * i3), 1);
        return join(a01, a23);  // x0 y0 x1 y1 x2 y2 x3 y3
    }
    DEMLAB_LANES_AVX512 static void load_xy_at(const double* a, const size_t* k, D& x, D& y) {
        const __m512d lo = xy4(a, k[0], k[1], k[2], k[3]), hi = xy4(a, k[4], k[5], k[6], k[7]);
        x = {_mm512_permutex2var_pd(lo, _mm512_setr_epi64(0, 2, 4, 6, 8, 10, 12, 14), hi)};
        y = {_mm512_permutex2var_pd(lo, _mm512_setr_epi64(1, 3, 5, 7, 9, 11, 13, 15), hi)};
    }

    // n consecutive (x, y) pairs from a (lanes beyond n: the last again)
    DEMLAB_LANES_AVX512 static void load_xy_run(const double* a, size_t n, D& x, D& y) {
        if (n == 8) {
            const __m512d a03 = _mm512_loadu_pd(a), a47 = _mm512_loadu_pd(a + 8);  // x0 y0 x1 y1 ..
            x = {_mm512_permutex2var_pd(a03, _mm512_setr_epi64(0, 2, 4, 6, 8, 10, 12, 14), a47)};
            y = {_mm512_permutex2var_pd(a03, _mm512_setr_epi64(1, 3, 5, 7, 9, 11, 13, 15), a47)};
            return;
        }
        x = gather([&](size_t l) { return a[2 * std::min(l, n - 1)]; });
        y = gather([&](size_t l) { return a[2 * std::min(l, n - 1) + 1]; });
    }
    DEMLAB_LANES_AVX512 static void store_xy_run(double* a, size_t n, D x, D y) {
        const __m512d a03 = _mm512_permutex2var_pd(x.v, _mm512_setr_epi64(0, 8, 1, 9, 2, 10, 3, 11), y.v);    // x0 y0 .. x3 y3
        const __m512d a47 = _mm512_permutex2var_pd(x.v, _mm512_setr_epi64(4, 12, 5, 13, 6, 14, 7, 15), y.v);  // x4 y4 .. x7 y7
        if (n == 8) {
            _mm512_storeu_pd(a, a03);
            _mm512_storeu_pd(a + 8, a47);
            return;
        }
        _mm512_mask_storeu_pd(a, first(2 * std::min<size_t>(n, 4)).m, a03);
        if (n > 4) _mm512_mask_storeu_pd(a + 8, first(2 * (n - 4)).m, a47);
    }

    // Eight records of eight doubles (rows[l], 64-byte aligned: lane l) as eight registers of
    // fields, by an 8x8 transpose.
    DEMLAB_LANES_AVX512 static void transpose_records(const double* const rows[8], D f[8]) {
        __m512d r[8];
        for (int l = 0; l < 8; ++l) r[l] = _mm512_load_pd(rows[l]);
        // pairs of rows: lo (fields 0 2 4 6 of rows 2k, 2k+1 side by side), hi (fields 1 3 5 7)
        const __m512d t0 = _mm512_unpacklo_pd(r[0], r[1]), t1 = _mm512_unpackhi_pd(r[0], r[1]);
        const __m512d t2 = _mm512_unpacklo_pd(r[2], r[3]), t3 = _mm512_unpackhi_pd(r[2], r[3]);
        const __m512d t4 = _mm512_unpacklo_pd(r[4], r[5]), t5 = _mm512_unpackhi_pd(r[4], r[5]);
        const __m512d t6 = _mm512_unpacklo_pd(r[6], r[7]), t7 = _mm512_unpackhi_pd(r[6], r[7]);
        // 128-bit lanes: t0 = (f0 of rows 0 1, f2 of 0 1, f4 of 0 1, f6 of 0 1); 0x88 takes lanes
        // 0 and 2 of each operand, 0xDD lanes 1 and 3
        const __m512d u04 = _mm512_shuffle_f64x2(t0, t2, 0x88), u26 = _mm512_shuffle_f64x2(t0, t2, 0xDD);  // rows 0-3
        const __m512d v04 = _mm512_shuffle_f64x2(t4, t6, 0x88), v26 = _mm512_shuffle_f64x2(t4, t6, 0xDD);  // rows 4-7
        const __m512d u15 = _mm512_shuffle_f64x2(t1, t3, 0x88), u37 = _mm512_shuffle_f64x2(t1, t3, 0xDD);
        const __m512d v15 = _mm512_shuffle_f64x2(t5, t7, 0x88), v37 = _mm512_shuffle_f64x2(t5, t7, 0xDD);
        f[0] = {_mm512_shuffle_f64x2(u04, v04, 0x88)};
        f[4] = {_mm512_shuffle_f64x2(u04, v04, 0xDD)};
        f[2] = {_mm512_shuffle_f64x2(u26, v26, 0x88)};
        f[6] = {_mm512_shuffle_f64x2(u26, v26, 0xDD)};
        f[1] = {_mm512_shuffle_f64x2(u15, v15, 0x88)};
        f[5] = {_mm512_shuffle_f64x2(u15, v15, 0xDD)};
        f[3] = {_mm512_shuffle_f64x2(u37, v37, 0x88)};
        f[7] = {_mm512_shuffle_f64x2(u37, v37, 0xDD)};
    }

    // Four registers whose lanes are pairs, as eight records rows[l] = {a[l], b[l], c[l], d[l]}
    // (64-byte aligned).
    DEMLAB_LANES_AVX512 static void store_rows(double (*rows)[4], D a, D b, D c, D d) {
        const __m512d ab0 = _mm512_unpacklo_pd(a.v, b.v), ab1 = _mm512_unpackhi_pd(a.v, b.v);  // a0 b0 a2 b2 .., a1 b1 a3 b3 ..
        const __m512d cd0 = _mm512_unpacklo_pd(c.v, d.v), cd1 = _mm512_unpackhi_pd(c.v, d.v);
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
    // Two registers as eight records of two (rows[l] = lane l of a, b; 64-byte aligned).
    DEMLAB_LANES_AVX512 static void store_pairs(double (*rows)[2], D a, D b) {
        // 128-bit lanes p0 p2 p4 p6 and p1 p3 p5 p7
        const __m512d lo = _mm512_unpacklo_pd(a.v, b.v), hi = _mm512_unpackhi_pd(a.v, b.v);
        const __m512d both_lo = _mm512_shuffle_f64x2(lo, hi, 0x44);  // p0 p2 p1 p3
        const __m512d both_hi = _mm512_shuffle_f64x2(lo, hi, 0xEE);  // p4 p6 p5 p7
        _mm512_store_pd(rows[0], _mm512_shuffle_f64x2(both_lo, both_lo, 0xD8));  // p0 p1 p2 p3
        _mm512_store_pd(rows[4], _mm512_shuffle_f64x2(both_hi, both_hi, 0xD8));  // p4 p5 p6 p7
    }
    // The mask as 32-bit integers 1 or 0 (32-byte aligned).
    DEMLAB_LANES_AVX512 static void store_flags(int32_t* a, M m) {
        _mm256_store_si256(reinterpret_cast<__m256i*>(a), _mm256_maskz_set1_epi32(m.m, 1));
    }

    // lanes 4k .. 4k + 3 of v (k = 0 or 1), for sums kept in four lanes (value l in lane l % 4)
    DEMLAB_LANES_AVX512 static D4 four(D v, size_t k) {
        return {k == 0 ? _mm512_castpd512_pd256(v.v) : _mm512_extractf64x4_pd(v.v, 1)};
    }
};

}  // namespace demlab::lanes

#undef DEMLAB_LANES_AVX512
#endif
