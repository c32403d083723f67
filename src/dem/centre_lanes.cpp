// centre_lanes.h's formulas compiled three times: for AVX-512 (eight lanes), AVX2 (four) and
// the baseline (two), from the one body. The file is compiled with -ffp-contract=off (no FMA in
// any width, so every width gives the scalar formulas' bits) and -fno-math-errno (the square
// root then vectorises; it is correctly rounded either way and never sees a negative).
#include "dem/centre_lanes.h"

namespace demlab {

namespace {

template <bool kRotationFree, bool kNoTension, bool kNoShearSliding>
struct Width {
    [[gnu::target("avx2,avx512f,avx512dq,avx512vl")]] static void avx512(CentreBlock& b, double dt, double h) {
        centre_lanes<kRotationFree, kNoTension, kNoShearSliding>(b, dt, h);
    }
    [[gnu::target("avx2")]] static void avx2(CentreBlock& b, double dt, double h) {
        centre_lanes<kRotationFree, kNoTension, kNoShearSliding>(b, dt, h);
    }
    static void baseline(CentreBlock& b, double dt, double h) { centre_lanes<kRotationFree, kNoTension, kNoShearSliding>(b, dt, h); }
    static void run(CentreBlock& b, const CentreConsts& k, bool avx2_ok, bool avx512_ok) {
        if (avx512_ok) avx512(b, k.dt, k.half_dt);
        else if (avx2_ok) avx2(b, k.dt, k.half_dt);
        else baseline(b, k.dt, k.half_dt);
    }
};

template <bool kRotationFree, bool kNoTension>
void by_shear(CentreBlock& b, const CentreConsts& k, bool avx2_ok, bool avx512_ok) {
    if (k.no_shear_sliding) Width<kRotationFree, kNoTension, true>::run(b, k, avx2_ok, avx512_ok);
    else Width<kRotationFree, kNoTension, false>::run(b, k, avx2_ok, avx512_ok);
}

template <bool kRotationFree>
void by_tension(CentreBlock& b, const CentreConsts& k, bool avx2_ok, bool avx512_ok) {
    if (k.no_tension) by_shear<kRotationFree, true>(b, k, avx2_ok, avx512_ok);
    else by_shear<kRotationFree, false>(b, k, avx2_ok, avx512_ok);
}

}  // namespace

void centre_block(CentreBlock& b, const CentreConsts& k, bool avx2_ok, bool avx512_ok) {
    if (k.rotation_free) by_tension<true>(b, k, avx2_ok, avx512_ok);
    else by_tension<false>(b, k, avx2_ok, avx512_ok);
}

}  // namespace demlab
