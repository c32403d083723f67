// integrate_kernel.h: World::integrate_discs' loop eight discs at a time in AVX-512 registers,
// for the CPUs that have AVX-512 (F, DQ, VL): the loop of integrate_wide.h over lanes::Avx512.
// Why: the AVX2 loop ran at about four instructions a cycle (perf: its samples spread over its
// instructions), so halving its vector instructions is what can make it faster. Same bits as
// the scalar loop and the AVX2 one (integrate_wide.h); AVX-512F includes FMA, so this file is
// compiled with -ffp-contract=off (CMakeLists.txt).
#include <cmath>
#include <cstdint>

#include "dem/integrate_kernel.h"

#define DEMLAB_WIDE_TARGET "avx2,avx512f,avx512dq,avx512vl"
#include "dem/lanes/lanes_avx512.h"
#include "dem/integrate_wide.h"

namespace demlab {

#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
[[gnu::target("avx2,avx512f,avx512dq,avx512vl")]] IntegrateOut integrate_avx512(const IntegrateArrays& a,
                                                                              const IntegrateParams& p, size_t begin,
                                                                              size_t end, LedgerBlock* blocks,
                                                                              size_t block_size) {
    return integrate_wide::integrate<lanes::Avx512>(a, p, begin, end, blocks, block_size);
}
#else
IntegrateOut integrate_avx512(const IntegrateArrays&, const IntegrateParams&, size_t, size_t, LedgerBlock*, size_t) {
    return {INFINITY, SIZE_MAX, false, 0.0, 0.0, 0};
}
#endif

}  // namespace demlab
