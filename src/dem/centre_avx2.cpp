// centre_wide.h four pairs at a time in AVX2 registers; the caller asks cpu_has_avx2() first.
#include "dem/centre_lanes.h"

#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
#define DEMLAB_WIDE_TARGET "avx2"
#include "dem/lanes/lanes_avx2.h"
#include "dem/centre_wide.h"

namespace demlab {
[[gnu::target("avx2")]] bool centre_touching_avx2(const CentrePairArrays& a, const uint32_t* list, size_t n, CentreBlock& b,
                                                  const CentreConsts& k) {
    return centre_wide::touching_any<lanes::Avx2>(a, list, n, b, k);
}
}  // namespace demlab
#else
namespace demlab {
bool centre_touching_avx2(const CentrePairArrays&, const uint32_t*, size_t, CentreBlock& b, const CentreConsts&) {
    b.count = 0;
    return false;
}
}  // namespace demlab
#endif
