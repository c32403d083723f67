// Scenario files: every key checked where it is read, errors naming file, line, key and range;
// overrides; the shipped scenarios.
#include <gtest/gtest.h>

#include <filesystem>
#include <functional>

#include "core/error.h"
#include "helpers.h"
#include "setups/release.h"
#include "setups/setup.h"
#include "scenario/scenario.h"

using namespace demlab;
using demlab::test::expect_refused;

TEST(Scenario, UnknownKeyNamesFileLineAndTheNearestKey) {
    expect_refused([] { parse_scenario("[material]\ndensity = 2600\ndensty = 2600\n", "a.toml"); },
                   {"a.toml:3", "material.densty", "unknown key", "did you mean 'material.density'"});
    expect_refused([] { parse_scenario("[materal]\ndensity = 1\n", "b.toml"); }, {"b.toml:2", "unknown key", "material.density"});
}

TEST(Scenario, WrongTypesAndRangesAreRefused) {
    expect_refused([] { parse_scenario("[material]\ndensity = \"heavy\"\n", "c.toml"); },
                   {"c.toml:2", "material.density", "must be a number", "kg/m3"});
    expect_refused([] { parse_scenario("[damping]\nbeta_n = 1.2\n", "d.toml"); },
                   {"d.toml:2", "damping.beta_n", "1.2", "[0.0, 1.0)"});
    expect_refused([] { parse_scenario("[rotation]\nmodel = 4\n", "e.toml"); }, {"rotation.model", "[1, 3]"});
    expect_refused([] { parse_scenario("[release]\nvariant = \"III\"\n", "f.toml"); }, {"release.variant", "\"I\" \"II\""});
    expect_refused([] { parse_scenario("[flume]\nw1_start = [0, \"x\"]\n", "g.toml"); }, {"flume.w1_start", "number"});
    expect_refused([] { parse_scenario("[material\n", "h.toml"); }, {"h.toml:1", "TOML syntax error"});
    expect_refused([] { parse_scenario("[[discs]]\nradius = 0.01\n", "i.toml"); }, {"discs[0]", "missing key 'position'"});
    expect_refused([] { parse_scenario("[[walls]]\ntype = \"segment\"\nstart = [0, 0]\nend = [0, 0]\n", "j.toml"); },
                   {"zero-length segment"});
    expect_refused([] { parse_scenario("[[walls]]\ntype = \"arc\"\ncentre = [0, 0]\nradius = 1\nstart_deg = 10\nend_deg = 10\n", "k.toml"); },
                   {"zero extent"});
}

TEST(Scenario, OverridesSetKeysAndAreChecked) {
    Scenario s = parse_scenario("[material]\nfriction_disc_deg = 15.5\n", "o.toml");
    apply_override(s, "material.friction_disc_deg=16");
    apply_override(s, "release.variant=I");  // a bare word is a string
    apply_override(s, "rotation.model=1");
    EXPECT_EQ(s.disc_friction_deg, 16.0);
    EXPECT_EQ(s.release.variant, "I");
    EXPECT_EQ(s.world.rotation.model, 1);
    expect_refused([&] { apply_override(s, "material.frction_disc_deg=16"); }, {"unknown key", "material.friction_disc_deg"});
    expect_refused([&] { apply_override(s, "damping.beta_n=2"); }, {"damping.beta_n", "[0.0, 1.0)"});
    expect_refused([&] { apply_override(s, "novalue"); }, {"expected key=value"});
}

// The friction angles become coefficients once, when the scenario is read, into its materials;
// the set-up's walls and the [[walls]] entries name their material by index.
TEST(Scenario, WallsCarryMaterialsByIndex) {
    Scenario s = parse_scenario("[material]\nfriction_disc_deg = 16\nfriction_wall_deg = 25\nwall_kn = 5e7\nwall_ks = 4e7\n"
                                "[dam_break]\n"
                                "[[walls]]\nstart = [0, 0]\nend = [1, 0]\nkn = 3e7\nks = 2e7\nfriction_deg = 30\n"
                                "[[walls]]\nstart = [0, 1]\nend = [1, 1]\n",
                                "m.toml");
    finish_scenario(s);
    const std::vector<MaterialDef> m = scenario_materials(s);
    ASSERT_EQ(m.size(), 4u);
    EXPECT_EQ(m[kDiscMaterial].friction, std::tan(deg_to_rad(16.0)));
    EXPECT_EQ(m[kWallMaterial].friction, std::tan(deg_to_rad(25.0)));
    EXPECT_EQ(m[kWallMaterial].kn, 5e7);
    EXPECT_EQ(m[kWallMaterial].ks, 4e7);
    ASSERT_EQ(s.walls.size(), 2u);
    EXPECT_EQ(s.walls[0].material, kFirstWallEntryMaterial);
    EXPECT_EQ(s.walls[1].material, kFirstWallEntryMaterial + 1);
    const MaterialDef& w0 = m[size_t(s.walls[0].material)];
    EXPECT_EQ(w0.kn, 3e7);
    EXPECT_EQ(w0.ks, 2e7);
    EXPECT_EQ(w0.friction, std::tan(deg_to_rad(30.0)));
    // an entry without its own keys: a wall's defaults, not the set-up's wall material
    const MaterialDef& w1 = m[size_t(s.walls[1].material)];
    EXPECT_EQ(w1.kn, 1e8);
    EXPECT_EQ(w1.friction, std::tan(deg_to_rad(21.7)));
    for (const WallDef& w : make_setup(s)->walls()) EXPECT_EQ(w.material, kWallMaterial);
    for (const WallDef& w : make_setup(s)->release_box().walls) EXPECT_EQ(w.material, kWallMaterial);
    // the resolved scenario gives the entries' angles back
    const std::string text = resolved_toml(s);
    EXPECT_NE(text.find("kn = 3e+07\nks = 2e+07\nfriction_deg = 29.999999999999996\n"), std::string::npos) << text;
}

TEST(Scenario, ReleaseBoxMustClose) {
    Scenario s = parse_scenario("[flume]\ngate_start = [0.5276, 0.9]\n", "box.toml");
    expect_refused([&] { finish_scenario(s); }, {"gate_start", "must lie on W1", "does not close"});
    Scenario big = parse_scenario("[flume]\n[release]\nscale = 80\n", "big.toml");
    expect_refused([&] { finish_scenario(big); }, {"release.r_max", "too large"});
}

TEST(Scenario, EveryShippedScenarioLoadsAndResolves) {
    int count = 0;
    for (const auto& e : std::filesystem::directory_iterator(std::string(DEMLAB_SOURCE_DIR) + "/scenarios")) {
        if (e.path().extension() != ".toml") continue;
        Scenario s = load_scenario(e.path().string());
        EXPECT_NO_THROW(finish_scenario(s)) << e.path();
        EXPECT_TRUE(has_release(s) || s.lattice_release.enabled || (s.solver == "dem3" && !s.dem3.terrain.empty())) << e.path();
        // the resolved scenario parses back to the same values
        Scenario again = parse_scenario(resolved_toml(s), "resolved");
        finish_scenario(again);
        EXPECT_EQ(resolved_toml(again).substr(resolved_toml(again).find('\n', 80)),
                  resolved_toml(s).substr(resolved_toml(s).find('\n', 80)));
        ++count;
    }
    EXPECT_EQ(count, 21);  // 8 rows of Table 2, the presets A, B, C, the dam break, the terrain profile, the snow slide, its dam, its disordered variant, Attabad on a profile, on a grid, in 3-D and literally in 3-D, and the snow slab in 3-D
}

TEST(Release, CountFollowsPfcsRuleForTheThesisScales) {
    // Table 14: scale 2 -> 36,403, scale 4 -> 9,099, scale 20 -> 364 discs (within 3 %)
    const double area = 0.5 * 0.5276 * (1.1150 - 0.8226);
    const std::pair<int, long> expected[] = {{2, 36403}, {4, 9099}, {20, 364}};
    for (auto [scale, n] : expected) {
        const long got = release_count(area, 0.166, scale_r_min(scale), scale_r_max(scale));
        EXPECT_NEAR(double(got), double(n), 0.03 * double(n)) << "scale " << scale;
    }
}
