// Regression: a short flume run's measurements equal stored references, so a change meant to
// make demlab faster (or tidier) cannot move the flume results unnoticed.
//
// The comparison is exact (the CSV text, 10 significant digits). A tolerance would not help:
// a granular flow is chaotic, and one changed bit in a force grows to a visibly different
// flow within a few thousand steps, so results either agree to the last digit or differ
// plainly. Exactness holds for the same compiler, flags and libm (Debian 12, GCC 12, x86-64,
// no -march=native: DEMLAB_NATIVE changes the bits through FMA contraction), and for any
// thread count. A change that alters the arithmetic on purpose (a new summation order, a
// different law) must regenerate the references with
//     DEMLAB_UPDATE_REFERENCES=1 ./build/demlab_tests --gtest_filter='Regression.*'
// and say so in its commit.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "files.h"
#include "run/run.h"
#include "scenario/scenario.h"

using namespace demlab;
using demlab::test::read_file;
using demlab::test::temp_dir;
namespace fs = std::filesystem;

namespace {
// the first line where two texts differ, for the message
std::string first_difference(const std::string& a, const std::string& b) {
    std::istringstream ia(a), ib(b);
    std::string la, lb;
    for (int line = 1;; ++line) {
        const bool ea = !std::getline(ia, la), eb = !std::getline(ib, lb);
        if (ea && eb) return "none";
        if (ea != eb || la != lb)
            return "line " + std::to_string(line) + ":\n  reference: " + (ea ? "<end>" : la) + "\n  now:       " + (eb ? "<end>" : lb);
    }
}

// Runs geometry A at scale 20 (Model 3, Variant II; generation, gate lift, impact on the
// barrier, to t = 1.2 s) with the overrides, and compares forces.csv and front.csv with
// tests/data/geometry-A-s20-<name>forces.csv and ...front.csv (or writes them).
void expect_references(const std::string& name, const std::vector<std::string>& overrides) {
    Scenario s = load_scenario(std::string(DEMLAB_SOURCE_DIR) + "/scenarios/geometry-A.toml");
    for (const char* a : {"release.scale=20", "stop.t_max=1.2", "output.snapshot_interval=0"}) apply_override(s, a);
    for (const std::string& a : overrides) apply_override(s, a);
    finish_scenario(s);
    const fs::path dir = temp_dir("regression-" + name);
    run_scenario(s, {dir.string(), false, {}});
    const fs::path refs = fs::path(DEMLAB_SOURCE_DIR) / "tests" / "data";
    const bool update = std::getenv("DEMLAB_UPDATE_REFERENCES") != nullptr;
    for (const char* f : {"forces.csv", "front.csv"}) {
        const fs::path ref = refs / ("geometry-A-s20-" + name + f);
        const std::string now = read_file(dir / f);
        if (update) {
            std::ofstream(ref, std::ios::binary) << now;
            continue;
        }
        ASSERT_TRUE(fs::exists(ref)) << ref << " is missing (DEMLAB_UPDATE_REFERENCES=1 writes it)";
        const std::string expected = read_file(ref);
        EXPECT_GT(expected.size(), 1000u);
        EXPECT_TRUE(now == expected) << f << " differs from " << ref << " at " << first_difference(expected, now);
    }
    fs::remove_all(dir);
}
}  // namespace

// (The front arrives at 0.89 s. Thread-count independence is Determinism's test: 364 discs are
// below the thread pool's parallel threshold.)
TEST(Regression, FlumeForcesAndFrontEqualReferences) { expect_references("", {}); }

// The release settled by the earlier scheme (frictionless at the real stiffness with local
// damping 0.7, then friction on the dashpots alone, the dashpots as the run's) is the four
// keys below: with them the run gives the references of the builds before the soft settling
// (written by the build of f6fa954), so results measured from earlier masses stay reproducible.
TEST(Regression, TheEarlierReleaseKeysGiveTheEarlierBuildsResults) {
    expect_references("earlier-release-", {"release.settle_stiffness_factor=1", "release.settle_alpha=0.7",
                                           "release.settle_friction_alpha=0", "release.settle_dashpots=\"centred\""});
}
