// The disc-disc kernel of pair_kernel.h four pairs at a time in AVX2 registers: the law of
// pair_kernel_wide.h (which says why it gives the scalar kernel's bits) over lanes::Avx2, and
// the sums of a batch into the discs, which both widths use.
//
// Only this file's functions use AVX2; the caller asks cpu_has_avx2() first.
#include <immintrin.h>

#include <cstddef>
#include <cstring>

#include "dem/laws/pair_kernel.h"

#define DEMLAB_WIDE_TARGET "avx2"
#include "dem/lanes/lanes_avx2.h"
#include "dem/laws/pair_kernel_wide.h"

namespace demlab {

bool cpu_has_avx2() {
#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
    return __builtin_cpu_supports("avx2");
#else
    return false;
#endif
}

#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
// The sums of the scalar pass (add_to_i, add_to_j in force_pass.cpp) for a record at a time: the
// same additions, lane by lane, in the same order of pairs.
[[gnu::target("avx2")]] void add_pair_batch_avx2(const PairBatch& batch, const DiscContact* c, DiscLoad* load) {
    static_assert(offsetof(DiscLoad, force) == 0 && offsetof(DiscLoad, torque) == 16 && offsetof(DiscLoad, k_tran) == 24 &&
                  offsetof(DiscLoad, k_rot) == 32 && offsetof(DiscLoad, dissipated) == 40);
    for (size_t b = 0, n = batch.count; b < n; ++b) {
        // everything read from the batch and the contact first: the stores into the loads
        // may alias them as far as the compiler knows, and it reloaded i, j and the touching
        // flag after each (a third of the loop's instructions)
        const DiscContact& cb = c[batch.index[b]];
        const size_t i = size_t(cb.i), j = size_t(cb.j);
        const int32_t touching = batch.touching[b];
        const __m128d both = _mm_load_pd(batch.to_both[b]);
        const __m256d to_i = _mm256_load_pd(batch.to_i[b]), to_j = _mm256_load_pd(batch.to_j[b]);
        double* const li = reinterpret_cast<double*>(load + i);
        _mm256_store_pd(li, _mm256_add_pd(_mm256_load_pd(li), to_i));
        _mm_store_pd(li + 4, _mm_add_pd(_mm_load_pd(li + 4), both));
        load[i].n_disc += touching;
        double* const lj = reinterpret_cast<double*>(load + j);
        _mm256_store_pd(lj, _mm256_add_pd(_mm256_load_pd(lj), to_j));
        _mm_store_pd(lj + 4, _mm_add_pd(_mm_load_pd(lj + 4), both));
        load[j].n_disc += touching;
    }
}

[[gnu::target("avx2")]] size_t disc_pairs_avx2(const DiscArrays& d, const PairPassParams& p, DiscContact* c, size_t n,
                                               PairBatch& out, const PairSkip* skip) {
    return pair_wide::disc_pairs_any<lanes::Avx2>(d, p, c, n, out, skip);
}

[[gnu::target("avx2")]] size_t pair_law_avx2(const DiscArrays& d, const PairPassParams& p, DiscContact* c, PairBatch& out) {
    return pair_wide::pair_law<lanes::Avx2>(d, p, c, out);
}
#else
size_t pair_law_avx2(const DiscArrays&, const PairPassParams&, DiscContact*, PairBatch&) { return 0; }
size_t disc_pairs_avx2(const DiscArrays&, const PairPassParams&, DiscContact*, size_t, PairBatch&, const PairSkip*) {
    return 0;
}
void add_pair_batch_avx2(const PairBatch&, const DiscContact*, DiscLoad*) {}
#endif

}  // namespace demlab
