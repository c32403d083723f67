// integrate_kernel.h: World::integrate_discs' loop four discs at a time in AVX2 registers, the
// loop of integrate_wide.h over lanes::Avx2. Same bits as the scalar loop (integrate_wide.h).
#include <cmath>
#include <cstdint>

#include "dem/integrate_kernel.h"

#define DEMLAB_WIDE_TARGET "avx2"
#include "dem/lanes/lanes_avx2.h"
#include "dem/integrate_wide.h"

namespace demlab {

#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
[[gnu::target("avx2")]] IntegrateOut integrate_avx2(const IntegrateArrays& a, const IntegrateParams& p, size_t begin,
                                                    size_t end, LedgerBlock* blocks, size_t block_size) {
    return integrate_wide::integrate<lanes::Avx2>(a, p, begin, end, blocks, block_size);
}
#else
IntegrateOut integrate_avx2(const IntegrateArrays&, const IntegrateParams&, size_t, size_t, LedgerBlock*, size_t) {
    return {INFINITY, SIZE_MAX, false, 0.0, 0.0, 0};
}
#endif

}  // namespace demlab
