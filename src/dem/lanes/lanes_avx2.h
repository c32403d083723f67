// Lanes of doubles for the wide kernels (the linear law's pair kernel, pair_kernel_wide.h, and
// the integration, integrate_wide.h), four in an AVX2 register; lanes_avx512.h has the same
// names for eight. A kernel is written once over these names, templated on the lane set
// (Avx2 or Avx512 below), and each width's file instantiates it under its own target.
//
// Every helper is one operation of the scalar code, lane by lane, so a kernel keeps the scalar
// loop's bits when it keeps its order of operations: + - * / and sqrt are IEEE's, correctly
// rounded at any width, and nothing here fuses (no FMA: "avx2" does not include it, and the
// AVX-512 files are compiled with -ffp-contract=off). min(a, b) and max(a, b) are the
// instructions' own: the second operand when either is NaN or both are zeros, so
// std::max(a, b) = (a < b) ? b : a is max(b, a) and std::min(a, b) = (b < a) ? b : a is
// min(b, a). A mask is a lane's condition; keep(m, a) gives +0 in the lanes it leaves out.
//
// The types (D: doubles, M: masks, I: 64-bit integers) and the free functions:
//   a + b, a - b, a * b, a / b, -a, sqrt(a), abs(a), min(a, b), max(a, b)
//   cmp<P>(a, b) (a _CMP_ predicate), m & n, m | n, any(m), all(m), bits(m) (lane l: bit l)
//   select(m, a, b) (m ? a : b), keep(m, a) (m ? a : +0)
//   for I: i + j, i & j, keep(m, i), greater(i, j), shift_left<k>(i)
// and the lane set's members, the loads and stores (the layouts are the widths' own):
//   set1, zero, mask(bool), first(n) (lanes 0 .. n-1), set1_int, as_int
//   gather(f) (lane l is f(l)), gather_float(f) (the same from floats, exact)
//   load_n / store_n (n <= kWidth consecutive doubles; the lanes beyond n repeat the last)
//   load_xy_at (Vec2 at the indices k[l]), load_xy_run / store_xy_run (n consecutive Vec2)
//   transpose_records (kWidth records of eight doubles as eight registers of fields)
//   store_rows (four registers as kWidth records of four), store_pairs (two, as records of two),
//   store_flags (a mask as int32 1 or 0), store, store_floats, store_int, four (lanes 4k .. 4k + 3).
#pragma once
#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
#include <immintrin.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>

#define DEMLAB_LANES_AVX2 [[gnu::target("avx2"), gnu::always_inline]] inline

namespace demlab::lanes {

struct D4 {
    __m256d v;
};
struct M4 {  // a lane all ones or all zeros
    __m256d v;
};
struct I4 {
    __m256i v;
};

DEMLAB_LANES_AVX2 D4 operator+(D4 a, D4 b) { return {_mm256_add_pd(a.v, b.v)}; }
DEMLAB_LANES_AVX2 D4 operator-(D4 a, D4 b) { return {_mm256_sub_pd(a.v, b.v)}; }
DEMLAB_LANES_AVX2 D4 operator*(D4 a, D4 b) { return {_mm256_mul_pd(a.v, b.v)}; }
DEMLAB_LANES_AVX2 D4 operator/(D4 a, D4 b) { return {_mm256_div_pd(a.v, b.v)}; }
DEMLAB_LANES_AVX2 D4 operator-(D4 a) { return {_mm256_xor_pd(a.v, _mm256_set1_pd(-0.0))}; }
DEMLAB_LANES_AVX2 D4 sqrt(D4 a) { return {_mm256_sqrt_pd(a.v)}; }
DEMLAB_LANES_AVX2 D4 abs(D4 a) { return {_mm256_andnot_pd(_mm256_set1_pd(-0.0), a.v)}; }
DEMLAB_LANES_AVX2 D4 min(D4 a, D4 b) { return {_mm256_min_pd(a.v, b.v)}; }
DEMLAB_LANES_AVX2 D4 max(D4 a, D4 b) { return {_mm256_max_pd(a.v, b.v)}; }
template <int P>
DEMLAB_LANES_AVX2 M4 cmp(D4 a, D4 b) {
    return {_mm256_cmp_pd(a.v, b.v, P)};
}
DEMLAB_LANES_AVX2 M4 operator&(M4 a, M4 b) { return {_mm256_and_pd(a.v, b.v)}; }
DEMLAB_LANES_AVX2 M4 operator|(M4 a, M4 b) { return {_mm256_or_pd(a.v, b.v)}; }
DEMLAB_LANES_AVX2 unsigned bits(M4 m) { return unsigned(_mm256_movemask_pd(m.v)); }
DEMLAB_LANES_AVX2 bool any(M4 m) { return _mm256_movemask_pd(m.v) != 0; }
DEMLAB_LANES_AVX2 bool all(M4 m) { return _mm256_movemask_pd(m.v) == 15; }
DEMLAB_LANES_AVX2 D4 select(M4 m, D4 a, D4 b) { return {_mm256_blendv_pd(b.v, a.v, m.v)}; }
DEMLAB_LANES_AVX2 D4 keep(M4 m, D4 a) { return {_mm256_and_pd(m.v, a.v)}; }

DEMLAB_LANES_AVX2 I4 operator+(I4 a, I4 b) { return {_mm256_add_epi64(a.v, b.v)}; }
DEMLAB_LANES_AVX2 I4 operator&(I4 a, I4 b) { return {_mm256_and_si256(a.v, b.v)}; }
DEMLAB_LANES_AVX2 I4 keep(M4 m, I4 a) { return {_mm256_and_si256(_mm256_castpd_si256(m.v), a.v)}; }
DEMLAB_LANES_AVX2 M4 greater(I4 a, I4 b) { return {_mm256_castsi256_pd(_mm256_cmpgt_epi64(a.v, b.v))}; }
template <int K>
DEMLAB_LANES_AVX2 I4 shift_left(I4 a) {
    return {_mm256_slli_epi64(a.v, K)};
}

struct Avx2 {
    static constexpr size_t kWidth = 4;
    using D = D4;
    using M = M4;
    using I = I4;

    DEMLAB_LANES_AVX2 static D set1(double x) { return {_mm256_set1_pd(x)}; }
    DEMLAB_LANES_AVX2 static D zero() { return {_mm256_setzero_pd()}; }
    DEMLAB_LANES_AVX2 static M mask(bool b) {
        return {b ? _mm256_castsi256_pd(_mm256_set1_epi64x(-1)) : _mm256_setzero_pd()};
    }
    DEMLAB_LANES_AVX2 static M first(size_t n) {
        return {_mm256_castsi256_pd(_mm256_cmpgt_epi64(_mm256_set1_epi64x(int64_t(n)), _mm256_setr_epi64x(0, 1, 2, 3)))};
    }
    DEMLAB_LANES_AVX2 static I set1_int(int64_t x) { return {_mm256_set1_epi64x(x)}; }
    DEMLAB_LANES_AVX2 static I zero_int() { return {_mm256_setzero_si256()}; }
    DEMLAB_LANES_AVX2 static I as_int(D a) { return {_mm256_castpd_si256(a.v)}; }

    template <typename F>
    DEMLAB_LANES_AVX2 static D gather(F f) {
        return {_mm256_set_pd(f(3), f(2), f(1), f(0))};
    }
    template <typename F>
    DEMLAB_LANES_AVX2 static D gather_float(F f) {
        return {_mm256_cvtps_pd(_mm_set_ps(f(3), f(2), f(1), f(0)))};
    }

    DEMLAB_LANES_AVX2 static D load_n(const double* a, size_t n) {
        if (n == 4) return {_mm256_loadu_pd(a)};
        return gather([&](size_t l) { return a[std::min(l, n - 1)]; });
    }
    DEMLAB_LANES_AVX2 static void store_n(double* a, size_t n, D v) {
        if (n == 4) {
            _mm256_storeu_pd(a, v.v);
            return;
        }
        alignas(32) double t[4];
        _mm256_store_pd(t, v.v);
        for (size_t l = 0; l < n; ++l) a[l] = t[l];
    }
    DEMLAB_LANES_AVX2 static void store(double* a, D v) { _mm256_store_pd(a, v.v); }  // aligned
    DEMLAB_LANES_AVX2 static void store_floats(float* a, D v) { _mm_store_ps(a, _mm256_cvtpd_ps(v.v)); }  // aligned
    DEMLAB_LANES_AVX2 static void store_int(int64_t* a, I v) { _mm256_store_si256(reinterpret_cast<__m256i*>(a), v.v); }

    // (x, y) pairs a + 2 k[l], as an x and a y register
    DEMLAB_LANES_AVX2 static void load_xy_at(const double* a, const size_t* k, D& x, D& y) {
        const __m256d a02 = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(a + 2 * k[0])), _mm_loadu_pd(a + 2 * k[2]), 1);
        const __m256d a13 = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(a + 2 * k[1])), _mm_loadu_pd(a + 2 * k[3]), 1);
        x = {_mm256_unpacklo_pd(a02, a13)};  // x0 x1 x2 x3
        y = {_mm256_unpackhi_pd(a02, a13)};  // y0 y1 y2 y3
    }

    // n consecutive (x, y) pairs from a (lanes beyond n: the last again)
    DEMLAB_LANES_AVX2 static void load_xy_run(const double* a, size_t n, D& x, D& y) {
        if (n == 4) {
            const __m256d a01 = _mm256_loadu_pd(a), a23 = _mm256_loadu_pd(a + 4);
            x = {_mm256_permute4x64_pd(_mm256_unpacklo_pd(a01, a23), 0xD8)};  // x0 x2 x1 x3 -> x0 x1 x2 x3
            y = {_mm256_permute4x64_pd(_mm256_unpackhi_pd(a01, a23), 0xD8)};
            return;
        }
        x = gather([&](size_t l) { return a[2 * std::min(l, n - 1)]; });
        y = gather([&](size_t l) { return a[2 * std::min(l, n - 1) + 1]; });
    }
    DEMLAB_LANES_AVX2 static void store_xy_run(double* a, size_t n, D x, D y) {
        const __m256d t02 = _mm256_unpacklo_pd(x.v, y.v), t13 = _mm256_unpackhi_pd(x.v, y.v);  // x0 y0 x2 y2, x1 y1 x3 y3
        const __m256d a01 = _mm256_permute2f128_pd(t02, t13, 0x20), a23 = _mm256_permute2f128_pd(t02, t13, 0x31);
        if (n == 4) {
            _mm256_storeu_pd(a, a01);
            _mm256_storeu_pd(a + 4, a23);
            return;
        }
        alignas(32) double t[8];
        _mm256_store_pd(t, a01);
        _mm256_store_pd(t + 4, a23);
        for (size_t l = 0; l < 2 * n; ++l) a[l] = t[l];
    }

    // Four records of eight doubles (rows[l], 32-byte aligned: lane l) as eight registers of
    // fields, by two 4x4 transposes.
    DEMLAB_LANES_AVX2 static void transpose4(__m256d r0, __m256d r1, __m256d r2, __m256d r3, D* f) {
        const __m256d t0 = _mm256_unpacklo_pd(r0, r1), t1 = _mm256_unpackhi_pd(r0, r1);  // r0[0] r1[0] r0[2] r1[2], ...
        const __m256d t2 = _mm256_unpacklo_pd(r2, r3), t3 = _mm256_unpackhi_pd(r2, r3);
        f[0] = {_mm256_permute2f128_pd(t0, t2, 0x20)};
        f[1] = {_mm256_permute2f128_pd(t1, t3, 0x20)};
        f[2] = {_mm256_permute2f128_pd(t0, t2, 0x31)};
        f[3] = {_mm256_permute2f128_pd(t1, t3, 0x31)};
    }
    DEMLAB_LANES_AVX2 static void transpose_records(const double* const rows[4], D f[8]) {
        transpose4(_mm256_load_pd(rows[0]), _mm256_load_pd(rows[1]), _mm256_load_pd(rows[2]), _mm256_load_pd(rows[3]), f);
        transpose4(_mm256_load_pd(rows[0] + 4), _mm256_load_pd(rows[1] + 4), _mm256_load_pd(rows[2] + 4),
                   _mm256_load_pd(rows[3] + 4), f + 4);
    }

    // Four registers whose lanes are pairs, as four records (rows[l] = lane l of a, b, c, d).
    DEMLAB_LANES_AVX2 static void store_rows(double (*rows)[4], D a, D b, D c, D d) {
        const __m256d ab02 = _mm256_unpacklo_pd(a.v, b.v), ab13 = _mm256_unpackhi_pd(a.v, b.v);
        const __m256d cd02 = _mm256_unpacklo_pd(c.v, d.v), cd13 = _mm256_unpackhi_pd(c.v, d.v);
        _mm256_store_pd(rows[0], _mm256_permute2f128_pd(ab02, cd02, 0x20));
        _mm256_store_pd(rows[1], _mm256_permute2f128_pd(ab13, cd13, 0x20));
        _mm256_store_pd(rows[2], _mm256_permute2f128_pd(ab02, cd02, 0x31));
        _mm256_store_pd(rows[3], _mm256_permute2f128_pd(ab13, cd13, 0x31));
    }
    // Two registers as four records of two (rows[l] = lane l of a, b).
    DEMLAB_LANES_AVX2 static void store_pairs(double (*rows)[2], D a, D b) {
        const __m256d lo = _mm256_unpacklo_pd(a.v, b.v);  // lanes 0 and 2
        const __m256d hi = _mm256_unpackhi_pd(a.v, b.v);  // lanes 1 and 3
        _mm_store_pd(rows[0], _mm256_castpd256_pd128(lo));
        _mm_store_pd(rows[1], _mm256_castpd256_pd128(hi));
        _mm_store_pd(rows[2], _mm256_extractf128_pd(lo, 1));
        _mm_store_pd(rows[3], _mm256_extractf128_pd(hi, 1));
    }
    // The mask as 32-bit integers 1 or 0 (16-byte aligned): its lanes (all ones) negated.
    DEMLAB_LANES_AVX2 static void store_flags(int32_t* a, M m) {
        _mm_store_si128(reinterpret_cast<__m128i*>(a),
                        _mm_sub_epi32(_mm_setzero_si128(), _mm256_castsi256_si128(_mm256_permutevar8x32_epi32(
                                                               _mm256_castpd_si256(m.v), _mm256_setr_epi32(0, 2, 4, 6, 0, 0, 0, 0)))));
    }

    // lanes 4k .. 4k + 3 of v (k = 0), for sums kept in four lanes (value l in lane l % 4)
    DEMLAB_LANES_AVX2 static D4 four(D v, size_t) { return v; }
};

}  // namespace demlab::lanes

#undef DEMLAB_LANES_AVX2
#endif
