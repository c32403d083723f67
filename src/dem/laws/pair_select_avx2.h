// The first stages of the disc-disc pass, shared by its AVX2 and AVX-512 kernels
// (pair_kernel_wide.h, compiled by pair_kernel_avx2.cpp and pair_kernel_avx512.cpp): which of
// a batch's candidate pairs have something to do this step, four at a time for both widths.
// Internal to those files; the functions ask for AVX2, which the AVX-512 ones include.
#pragma once
#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
#include <immintrin.h>

#include <cstddef>
#include <cstdint>
#include <cstring>

#include "dem/lanes/lanes_avx2.h"
#include "dem/laws/pair_kernel.h"

namespace demlab {
namespace pair_select {

#define DEMLAB_AVX2 [[gnu::target("avx2"), gnu::always_inline]] static inline

// For each 4-bit mask, its set lanes' numbers packed to the front (the rest: don't care).
alignas(16) const __m128i kPackedLanes[16] = {
    _mm_setr_epi32(0, 0, 0, 0), _mm_setr_epi32(0, 0, 0, 0), _mm_setr_epi32(1, 0, 0, 0), _mm_setr_epi32(0, 1, 0, 0),
    _mm_setr_epi32(2, 0, 0, 0), _mm_setr_epi32(0, 2, 0, 0), _mm_setr_epi32(1, 2, 0, 0), _mm_setr_epi32(0, 1, 2, 0),
    _mm_setr_epi32(3, 0, 0, 0), _mm_setr_epi32(0, 3, 0, 0), _mm_setr_epi32(1, 3, 0, 0), _mm_setr_epi32(0, 1, 3, 0),
    _mm_setr_epi32(2, 3, 0, 0), _mm_setr_epi32(0, 2, 3, 0), _mm_setr_epi32(1, 2, 3, 0), _mm_setr_epi32(0, 1, 2, 3)};

// Stages 0 and 1 of the pass over contacts c[0, n) (n <= PairBatch::kSize): which pairs have
// something to do, listed in out.index in list order (out.count of them), the list padded to
// a multiple of `group` (the law's lanes) with its last pair. Updates the clearances of the
// pairs it looks at (PairSkip). Returns how many contacts it covered, from the first: n less
// n % 4 (the rest do not fill a group of four).
DEMLAB_AVX2 size_t select_pairs(const DiscArrays& d, DiscContact* c, size_t n, PairBatch& out, const PairSkip* skip,
                                size_t group) {
    const double* pos = d.pos->data();
    static_assert(offsetof(DiscContact, damp_s) == offsetof(DiscContact, damp_n) + sizeof(float));
    const size_t covered = n - n % 4;
    // The pairs to do, as a bit per contact: listed in list order at the end.
    static_assert(PairBatch::kSize % 64 == 0);
    constexpr size_t kWords = PairBatch::kSize / 64;
    uint64_t todo_bits[kWords] = {};
    // 0. The clearance test (PairSkip): a negative clearance marks a pair the law found
    // touching in its last step (to do: no need to look); one above the approach, a pair
    // that is still clear (skipped); the others are looked at, by their offsets from c.
    // Without the test, every pair is looked at.
    size_t mc = 0;
    if (skip) {
        const float* const clearance = skip->clearance;
        const __m128 approach_hi = _mm_set1_ps(skip->approach_hi);
        for (size_t g = 0; g < covered; g += 4) {
            const __m128 cl = _mm_loadu_ps(clearance + g);
            const unsigned known = unsigned(_mm_movemask_ps(cl));  // the sign bits
            const unsigned look = unsigned(_mm_movemask_ps(_mm_cmp_ps(cl, approach_hi, _CMP_NGT_UQ))) & ~known;
            todo_bits[g / 64] |= uint64_t(known) << (g % 64);
            _mm_storeu_si128(reinterpret_cast<__m128i*>(out.check + mc),
                             _mm_add_epi32(_mm_set1_epi32(int(g)), _mm_load_si128(&kPackedLanes[look])));
            mc += size_t(__builtin_popcount(look));
        }
        size_t known_count = 0;
        for (uint64_t w : todo_bits) known_count += size_t(__builtin_popcountll(w));
        out.skipped += covered - mc - known_count;
    } else {
        for (size_t g = 0; g < covered; ++g) out.check[g] = uint32_t(g);
        mc = covered;
    }
    // pad the last group of four with its last pair (the same pair again: the same results)
    for (size_t l = mc; l % 4 != 0; ++l) out.check[l] = out.check[mc - 1];

    // 1. Which of those pairs have something to do: touching now, or a history to end (any
    // bit set: a -0 shear force must still become +0, as the scalar kernel writes it). The
    // others are open before and after the step; the scalar kernel would add +0 and write
    // back zeros. Their clearances are updated.
    const __m128 approach_lo = _mm_set1_ps(skip ? skip->approach_lo : 0.0f);
    const __m128 shrink = _mm_set1_ps(1.0f - 0x1p-20f), grow = _mm_set1_ps(1.0f + 0x1p-20f);
    for (size_t g = 0; g < mc; g += 4) {
        const uint32_t at[4] = {out.check[g], out.check[g + 1], out.check[g + 2], out.check[g + 3]};
        const DiscContact* const q[4] = {c + at[0], c + at[1], c + at[2], c + at[3]};
        using L = lanes::Avx2;
        const size_t i[4] = {size_t(q[0]->i), size_t(q[1]->i), size_t(q[2]->i), size_t(q[3]->i)};
        const size_t j[4] = {size_t(q[0]->j), size_t(q[1]->j), size_t(q[2]->j), size_t(q[3]->j)};
        L::D xi, yi, xj, yj;
        L::load_xy_at(pos, i, xi, yi);
        L::load_xy_at(pos, j, xj, yj);
        const L::D ri = L::gather([&](size_t l) { return d.radius[i[l]]; });
        const L::D rj = L::gather([&](size_t l) { return d.radius[j[l]]; });
        const L::D dxx = xj - xi, dxy = yj - yi;
        const __m256d rsum = (ri + rj).v;
        const __m256d dist2 = (dxx * dxx + dxy * dxy).v;
        // the law's test (pair_kernel_wide.h; NaN counts as touching)
        const __m256d touching = _mm256_cmp_pd(dist2, _mm256_mul_pd(rsum, rsum), _CMP_NGE_UQ);
        uint64_t history = 0;  // per lane, a byte: any bit of the history set
        for (unsigned l = 0; l < 4; ++l) {
            uint64_t fs_bits, damp_bits;  // damp_n and damp_s side by side
            std::memcpy(&fs_bits, &q[l]->fs, sizeof fs_bits);
            std::memcpy(&damp_bits, reinterpret_cast<const char*>(q[l]) + offsetof(DiscContact, damp_n), sizeof damp_bits);
            history |= uint64_t((fs_bits | damp_bits) != 0) << (8 * l);
        }
        const __m128i todo_lanes = _mm_or_si128(
            _mm256_castsi256_si128(_mm256_permutevar8x32_epi32(_mm256_castpd_si256(touching), _mm256_setr_epi32(0, 2, 4, 6, 0, 0, 0, 0))),
            _mm_sub_epi32(_mm_setzero_si128(), _mm_cvtepu8_epi32(_mm_cvtsi64_si128(int64_t(history)))));
        if (skip) {
            // A lower bound of the gap |dx| - rsum in floats: float(dist2) and the square
            // root are within 2^-23 of |dx|, float(rsum) within 2^-24 of rsum, so shrinking
            // the one and growing the other by 2^-20 keeps the difference below the gap (and
            // its rounding, 2^-24 of it, is less than what that took off). A gap beyond the
            // float range is clamped: any bound below the gap will do.
            const __m128 dist_f = _mm_sqrt_ps(_mm_min_ps(_mm256_cvtpd_ps(dist2), _mm_set1_ps(1e36f)));
            const __m128 gap = _mm_sub_ps(_mm_mul_ps(dist_f, shrink), _mm_mul_ps(_mm256_cvtpd_ps(rsum), grow));
            // approach_lo + gap <= approach + gap rounds up by at most 2^-24: shrink again
            // (a negative sum only grows towards zero, still below approach_lo: looked at)
            const __m128 cleared = _mm_mul_ps(_mm_add_ps(approach_lo, gap), shrink);
            // a pair with something to do: 0 (the law then marks it, see below). Every lane is
            // stored: a padding lane is its pair again, with the same value.
            alignas(16) float v[4];
            _mm_store_ps(v, _mm_andnot_ps(_mm_castsi128_ps(todo_lanes), cleared));
            for (unsigned l = 0; l < 4; ++l) skip->clearance[at[l]] = v[l];
        }
        const unsigned valid = mc - g >= 4 ? 15u : (1u << (mc - g)) - 1u;
        const unsigned todo = unsigned(_mm_movemask_ps(_mm_castsi128_ps(todo_lanes))) & valid;
        for (unsigned l = 0; l < 4; ++l) todo_bits[at[l] / 64] |= uint64_t(todo >> l & 1u) << (at[l] % 64);
    }
    // the pairs to do in list order
    size_t m = 0;
    for (size_t w = 0; w < kWords; ++w)
        for (uint64_t bits = todo_bits[w]; bits != 0; bits &= bits - 1)
            out.index[m++] = uint32_t(64 * w + size_t(__builtin_ctzll(bits)));
    // pad the law's last group (of `group` lanes) with its last pair: that lane computes what
    // the last lane did and writes the same history back; its results are not counted
    for (size_t l = m; l % group != 0; ++l) out.index[l] = out.index[m - 1];
    out.count = m;
    return covered;
}

#undef DEMLAB_AVX2

}  // namespace pair_select
}  // namespace demlab
#endif
