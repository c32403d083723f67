// centre_wide.h eight pairs at a time in AVX-512 registers (F, DQ, VL); the caller asks
// cpu_has_avx512() first. Compiled with -ffp-contract=off (AVX-512F includes FMA).
#include "dem/centre_lanes.h"

#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
#define DEMLAB_WIDE_TARGET "avx2,avx512f,avx512dq,avx512vl"
#include "dem/lanes/lanes_avx512.h"
#include "dem/centre_wide.h"

namespace demlab {
[[gnu::target("avx2,avx512f,avx512dq,avx512vl")]] bool centre_touching_avx512(const CentrePairArrays& a, const uint32_t* list,
                                                                              size_t n, CentreBlock& b, const CentreConsts& k) {
    return centre_wide::touching_any<lanes::Avx512>(a, list, n, b, k);
}
}  // namespace demlab
#else
namespace demlab {
bool centre_touching_avx512(const CentrePairArrays&, const uint32_t*, size_t, CentreBlock& b, const CentreConsts&) {
    b.count = 0;
    return false;
}
}  // namespace demlab
#endif
