// Slow validation (label "slow", not in CI): the release mass at the thesis' scale 4.
#include <gtest/gtest.h>

#include "setups/release.h"
#include "scenario/scenario.h"

using namespace demlab;

TEST(ReleaseScale4, HoldsTheThesisCountAndPorosity) {
    Scenario s = load_scenario(std::string(DEMLAB_SOURCE_DIR) + "/scenarios/geometry-A.toml");
    finish_scenario(s);
    const ReleaseMass m = generate_release(s);
    // 9,099 discs within 3 %
    EXPECT_NEAR(double(m.pos.size()), 9099.0, 0.03 * 9099.0);
    // generated at the target (PFC's count rule uses the mean radius, so the disc area is
    // (1 - n) (1 + var/mean^2) of the box), then 3 % smaller radii: 6 % less disc area
    EXPECT_NEAR(m.porosity_generated, 1.0 - (1.0 - 0.166) * 7.0 / 6.75, 0.005);
    EXPECT_NEAR(m.porosity_settled, 1.0 - (1.0 - m.porosity_generated) * 0.97 * 0.97, 0.002);
    EXPECT_TRUE(m.settled);
    // every disc stays in the release box
    for (size_t i = 0; i < m.pos.size(); ++i) {
        EXPECT_GE(m.pos[i].x(), 0.0);
        EXPECT_LE(m.pos[i].x(), 0.5276);
    }
}
