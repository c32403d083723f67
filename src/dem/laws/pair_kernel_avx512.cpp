// The disc-disc law of pair_kernel.h eight pairs at a time in AVX-512 registers, for the CPUs
// that have AVX-512 (F, DQ, VL); the others use pair_kernel_avx2.cpp. The law is
// pair_kernel_wide.h (the same source as the AVX2 one, and why it gives the scalar kernel's
// bits) over lanes::Avx512 (why eight lanes pay: lanes_avx512.h); the selection stages are the
// AVX2 ones (pair_select_avx2.h), and the results go into the same PairBatch. AVX-512F
// includes FMA: this file is compiled with -ffp-contract=off (CMakeLists.txt).
#include <immintrin.h>

#include <cstddef>
#include <cstring>

#include "dem/laws/pair_kernel.h"

#define DEMLAB_WIDE_TARGET "avx2,avx512f,avx512dq,avx512vl"
#include "dem/lanes/lanes_avx512.h"
#include "dem/laws/pair_kernel_wide.h"

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
[[gnu::target("avx2,avx512f,avx512dq,avx512vl")]] size_t disc_pairs_avx512(const DiscArrays& d, const PairPassParams& p,
                                                                             DiscContact* c, size_t n, PairBatch& out,
                                                                             const PairSkip* skip) {
    return pair_wide::disc_pairs_any<lanes::Avx512>(d, p, c, n, out, skip);
}

[[gnu::target("avx2,avx512f,avx512dq,avx512vl")]] size_t pair_law_avx512(const DiscArrays& d, const PairPassParams& p,
                                                                           DiscContact* c, PairBatch& out) {
    return pair_wide::pair_law<lanes::Avx512>(d, p, c, out);
}
#else
size_t pair_law_avx512(const DiscArrays&, const PairPassParams&, DiscContact*, PairBatch&) { return 0; }
size_t disc_pairs_avx512(const DiscArrays&, const PairPassParams&, DiscContact*, size_t, PairBatch&, const PairSkip*) {
    return 0;
}
#endif

}  // namespace demlab
