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
}  // namespace

// Geometry A (Model 3, Variant II) at scale 20: generation, gate lift, impact on the barrier
// (the front arrives at 0.89 s), to t = 1.2 s. (Thread-count independence is Determinism's test:
// 364 discs are below the thread pool's parallel threshold.)
TEST(Regression, FlumeForcesAndFrontEqualReferences) {
    Scenario s = load_scenario(std::string(DEMLAB_SOURCE_DIR) + "/scenarios/geometry-A.toml");
    for (const char* a : {"release.scale=20", "stop.t_max=1.2", "output.snapshot_interval=0"}) apply_override(s, a);
    finish_scenario(s);
    const fs::path dir = temp_dir("regression");
    run_scenario(s, {dir.string(), false, {}});
    const fs::path refs = fs::path(DEMLAB_SOURCE_DIR) / "tests" / "data";
    const bool update = std::getenv("DEMLAB_UPDATE_REFERENCES") != nullptr;
    for (const char* f : {"forces.csv", "front.csv"}) {
        const fs::path ref = refs / (std::string("geometry-A-s20-") + f);
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
