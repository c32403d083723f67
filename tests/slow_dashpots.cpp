// Slow validation (label "slow", not in CI): the pack of 2,000 discs at PFC's step rule as
// printed for 1e6 steps (about 13 s of settling and lying still) with the centred dashpots,
// and the lagged dashpots' failure on it.
#include <gtest/gtest.h>

#include <cstdio>

#include "dashpot_stability.h"

using namespace demlab;
using namespace demlab::test;

TEST(DashpotStability, SettledPackMillionStepsAtPfcRule) {
    const DashpotWatch pack = settling_pack(DashpotScheme::Centred, 1000000);
    std::printf("centred: %d discs, %ld steps, energy %.6g -> %.6g J/m, largest rise %.3g, dissipation drop %.3g\n",
                pack.discs, pack.steps, pack.energy_start, pack.energy_end, pack.energy_rise, pack.dissipation_drop);
    ASSERT_GE(pack.discs, 2000);
    EXPECT_FALSE(pack.threw);
    EXPECT_LE(pack.energy_rise, 1e-9 * std::abs(pack.energy_start));
    EXPECT_LE(pack.dissipation_drop, 1e-9 * std::abs(pack.energy_start));
}

TEST(DashpotStability, LaggedDashpotsFailOnThePackAtPfcRule) {
    const DashpotWatch pack = settling_pack(DashpotScheme::Lagged, 1000000);
    std::printf("lagged: threw %d, %ld steps, largest rise %.3g J/m, dissipation drop %.3g\n", int(pack.threw),
                pack.steps, pack.energy_rise, pack.dissipation_drop);
    EXPECT_TRUE(pack.threw || pack.energy_rise > 1e-9 * std::abs(pack.energy_start) ||
                pack.dissipation_drop > 1e-9 * std::abs(pack.energy_start));
}
