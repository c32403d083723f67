// The content hash of a resolved scenario and its files (scenario/fingerprint.h), which reuse
// (sweeps, the calibration) and resume decide with.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "files.h"
#include "scenario/fingerprint.h"
#include "scenario/key_registry.h"
#include "scenario/scenario.h"

using namespace demlab;
namespace fs = std::filesystem;

// The 128-bit FNV-1a check values, and every key that names a file is among the hashed ones:
// a file key added to the registry without its place in scenario_file_keys() fails here
// (free-text keys other than the name and description are file names).
TEST(Fingerprint, CheckValuesAndEveryFileKeyIsHashed) {
    EXPECT_EQ(content_hash(""), "6c62272e07bb014262b821756295c58d");
    EXPECT_EQ(content_hash("a"), "d228cb696f1a8caf78912b704e4a8964");
    EXPECT_EQ(content_hash("foobar"), "343e1662793c64bf6f0d3597ba446f18");
    const std::vector<std::string>& files = scenario_file_keys();
    int text_keys = 0;
    for (const keys::Key& k : keys::registry()) {
        if (k.accepted != "any text" || k.name == "scenario.name" || k.name == "scenario.description") continue;
        ++text_keys;
        EXPECT_NE(std::find(files.begin(), files.end(), k.name), files.end()) << k.name << " names a file that is not hashed";
    }
    EXPECT_EQ(size_t(text_keys), files.size());
}

// The fingerprint follows every key and the bytes of each file the scenario reads, and not the
// comments or the file the scenario text came from.
TEST(Fingerprint, FollowsEveryKeyAndTheContentOfItsFiles) {
    const fs::path dir = test::temp_dir("fingerprint");
    fs::create_directories(dir);
    const fs::path profile = dir / "ground.csv";
    std::ofstream(profile) << "x,y\n0,1\n1,0\n3,0\n";
    const std::string text = "[terrain]\nprofile = \"" + profile.string() +
                             "\"\n[[discs]]\nposition = [0.2, 0.9]\nradius = 0.05\n";
    auto fingerprint = [&](const std::string& t, const std::string& name) {
        Scenario s = parse_scenario(t, name);
        finish_scenario(s);
        return scenario_fingerprint(s);
    };
    const std::string a = fingerprint(text, "a.toml");
    EXPECT_EQ(a.size(), 32u);
    EXPECT_EQ(fingerprint("# a comment\n" + text, "elsewhere/b.toml"), a);
    EXPECT_NE(fingerprint(text + "[material]\ndensity = 2000\n", "a.toml"), a);
    {
        Scenario s = parse_scenario(text, "a.toml");
        apply_override(s, "scenario.seed=2");
        finish_scenario(s);
        EXPECT_NE(scenario_fingerprint(s), a);
        const std::vector<ScenarioInput> in = scenario_inputs(s);
        ASSERT_EQ(in.size(), 1u);
        EXPECT_EQ(in[0].key, "terrain.profile");
        EXPECT_EQ(in[0].path, profile.string());
    }
    // the profile edited (the same points, one more decimal place: the same numbers) is
    // another input: its bytes decide
    std::ofstream(profile) << "x,y\n0,1.0\n1,0\n3,0\n";
    EXPECT_NE(fingerprint(text, "a.toml"), a);
    std::ofstream(profile) << "x,y\n0,1\n1,0\n3,0\n";
    EXPECT_EQ(fingerprint(text, "a.toml"), a);
    fs::remove_all(dir);
}
