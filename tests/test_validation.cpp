// Bad input is refused with a message that names the parameter and the accepted range.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <sstream>

#include "core/fileio.h"
#include "core/interrupt.h"
#include "core/output_dir.h"
#include "files.h"
#include "run/run.h"
#include "scenario/scenario.h"
#include "setups/db9k.h"
#include "helpers.h"

using namespace demlab;
using namespace demlab::test;

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Tests clean up what they write (issue 48, row 6): after the tests this process ran (ctest runs
// each in a process of its own), nothing named "demlab-...-PID..." is left in the temporary
// directory that was not there before them (a file an earlier process of the same pid left is
// not this one's). A leftover fails the run, naming the file or folder.
class TempLeftoversCheck final : public ::testing::Environment {
public:
    void SetUp() override { before_ = temp_leftovers(); }
    void TearDown() override {
        for (const std::string& name : temp_leftovers())
            if (std::find(before_.begin(), before_.end(), name) == before_.end())
                ADD_FAILURE() << "left in the temporary directory: " << name << " (a test must remove what it writes; tests/files.h: TempFile)";
    }

private:
    std::vector<std::string> before_;
};
[[maybe_unused]] ::testing::Environment* const kTempLeftoversCheck = ::testing::AddGlobalTestEnvironment(new TempLeftoversCheck);
}  // namespace

TEST(Validation, DiscsAndMaterials) {
    World w;
    const int m = w.add_material(material(0.3));
    expect_refused([&] { w.add_disc({Vec2(0, 0), -0.001, Vec2::Zero(), 0, 0, m}); }, {"radius", "must be > 0"});
    expect_refused([&] { w.add_disc({Vec2(0, 0), 0.0, Vec2::Zero(), 0, 0, m}); }, {"radius", "> 0"});
    expect_refused([&] { w.add_disc({Vec2(kNaN, 0), 0.001, Vec2::Zero(), 0, 0, m}); }, {"position", "finite"});
    expect_refused([&] { w.add_disc({Vec2(0, 0), 0.001, Vec2::Zero(), 0, 0, 7}); }, {"material", "no such material"});
    expect_refused([&] { w.add_material(material(0.3, 1e8, 0.0)); }, {"density", "kg/m3", "> 0"});
    expect_refused([&] { w.add_material(material(0.3, -1.0)); }, {"kn", "N/m", "> 0"});
    expect_refused([&] { w.add_material(material(-0.1)); }, {"friction", ">= 0"});
    expect_refused([&] { w.add_material(material(kNaN)); }, {"friction", "finite"});
}

TEST(Validation, Walls) {
    World w;
    expect_refused([&] { w.add_wall(segment(w, Vec2(1, 1), Vec2(1, 1))); }, {"zero-length segment"});
    expect_refused([&] { w.add_wall(arc(w, Vec2(0, 0), 0.0, 0, 90)); }, {"radius", "> 0"});
    expect_refused([&] { w.add_wall(arc(w, Vec2(0, 0), 1.0, 30, 30)); }, {"zero extent", "(0, 360]"});
    // a wall's stiffness and friction are its material's, checked as a disc's
    WallDef bad = segment(Vec2(0, 0), Vec2(1, 0));
    expect_refused([&] { w.add_wall(bad); }, {"material = -1", "no such material"});
    bad.material = 99;
    expect_refused([&] { w.add_wall(bad); }, {"material = 99", "no such material"});
    expect_refused([&] { wall_material(w, 0.3, 0.0); }, {"kn", "> 0"});
    expect_refused([&] { wall_material(w, -0.2); }, {"friction", ">= 0"});
    bad = segment(w, Vec2(0, 0), Vec2(1, kNaN));
    expect_refused([&] { w.add_wall(bad); }, {"p1", "finite"});
}

TEST(Validation, WorldSettings) {
    const auto finalize_with = [](const std::function<void(WorldDef&)>& edit) {
        WorldDef def;
        edit(def);
        World w(def);
        const int m = w.add_material(material(0.3));
        w.add_disc({Vec2(0, 0), 0.001, Vec2::Zero(), 0, 0, m});
        w.finalize();
    };
    expect_refused([&] { finalize_with([](WorldDef& d) { d.damping.beta_n = 1.0; }); }, {"beta_n", "[0, 1)"});
    expect_refused([&] { finalize_with([](WorldDef& d) { d.damping.beta_s = -0.1; }); }, {"beta_s", "[0, 1)"});
    expect_refused([&] { finalize_with([](WorldDef& d) { d.rotation.model = 4; }); }, {"model", "1", "3"});
    expect_refused([&] { finalize_with([](WorldDef& d) { d.rotation.mu_br = 1.5; }); }, {"mu_br", "[0, 1]"});
    expect_refused([&] { finalize_with([](WorldDef& d) { d.timestep.safety = 0.0; }); }, {"safety"});
    expect_refused([&] { finalize_with([](WorldDef& d) { d.gravity = Vec2(0, kNaN); }); }, {"gravity", "finite"});
    // the integrator's lost-disc test relies on a finite domain
    expect_refused([&] { finalize_with([](WorldDef& d) { d.domain_hi = Vec2(INFINITY, 1.0); }); },
                   {"domain_hi", "finite"});
}

// The integrator's one-test check (inside the finite domain) catches a disc that leaves the
// domain and a disc whose state overflows, and tells them apart.
TEST(BlowUp, LostAndNonFiniteDiscsStopTheRun) {
    const auto run_one = [](double gravity_y, double dt, double y0) -> std::string {
        WorldDef def;
        def.gravity = Vec2(0, gravity_y);
        def.timestep.automatic = false;
        def.timestep.fixed = dt;
        def.domain_lo = Vec2(-1, -1);
        def.domain_hi = Vec2(1, 1);
        World w(def);
        const int m = w.add_material(material(0.3));
        w.add_disc({Vec2(0, y0), 0.001, Vec2::Zero(), 0, 0, m});
        w.add_disc({Vec2(0.5, 0.5), 0.001, Vec2::Zero(), 0, 0, m});
        w.finalize();
        try {
            w.run(10);
        } catch (const RunError& e) {
            return e.what();
        }
        return "";
    };
    // (a disc that leaves the domain in one long step is a disc that moved more than half its
    // radius: Guards.FixedStepThatCarriesADiscFartherThanHalfItsRadiusIsRefused)
    const std::string lost = run_one(-100.0, 1e-3, -0.99995);  // 0.1 mm below the domain in the first step
    EXPECT_NE(lost.find("lost disc"), std::string::npos) << lost;
    EXPECT_NE(lost.find("disc 0"), std::string::npos) << lost;
    const std::string overflow = run_one(-1.7e308, 10.0, 0.5);  // v = -inf after one step
    EXPECT_NE(overflow.find("non-finite"), std::string::npos) << overflow;
}

// The force pass integrates its discs block by block as their sums complete, and a range
// stops integrating at its first fault but goes on with its pairs: the diagnosis names the
// first blow-up in list order, the same for any thread count.
TEST(BlowUp, SameDiagnosisOnOneAndTwoThreads) {
    const auto discs = read_xyr(default_db9k_path());
    std::string msg[2];
    for (int threads : {1, 2}) {
        WorldDef def = db9k_world_def();
        def.threads = threads;
        def.timestep.fixed = 2e-5;  // 4 times DB-9k's step: disc 560 (the third block of 256) thrown
                                     // more than half its radius in step 2 (an overlap beyond half a
                                     // radius with disc 559 would stop step 3)
        World w(def);
        build_db9k(w, discs);
        w.finalize();
        try {
            w.run(400);
        } catch (const RunError& e) {
            msg[threads - 1] = e.what();
        }
    }
    EXPECT_NE(msg[0].find("blow-up: disc 560 moved"), std::string::npos) << msg[0];
    EXPECT_EQ(msg[0], msg[1]);
}

TEST(BlowUp, TooLargeATimeStepStopsWithADiagnosis) {
    WorldDef def;
    def.timestep.automatic = false;
    def.timestep.fixed = 5e-4;  // ~40 times the critical step
    World w(def);
    const int m = w.add_material(material(0.3));
    w.add_disc({Vec2(0, 0.0011), 0.001, Vec2(0, -2.0), 0, 0, m});
    w.add_disc({Vec2(0, 0.0035), 0.001, Vec2(0, -2.0), 0, 0, m});
    w.add_wall(segment(w, Vec2(-1, 0), Vec2(1, 0), 0.3, SegmentSolid::Right));
    w.finalize();
    try {
        w.run(1000);
        ADD_FAILURE() << "a run with dt 40x too large did not stop";
    } catch (const RunError& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find("time step"), std::string::npos) << msg;
        EXPECT_NE(msg.find("disc"), std::string::npos) << msg;
        EXPECT_NE(msg.find("step"), std::string::npos) << msg;
    }
}

// Input files are refused before they are read when they are not regular files or are too
// large: /dev/zero as a scenario read 23 GB before the kernel stopped it.
TEST(Validation, UnboundedOrOddInputFilesAreRefused) {
    expect_refused([] { load_scenario("/dev/zero"); }, {"/dev/zero", "not a regular file"});
    expect_refused([] { load_scenario("/tmp"); }, {"not a regular file"});
    expect_refused([] { load_scenario("/nonexistent/scenario.toml"); }, {"no such file"});
    const std::string big = (std::filesystem::temp_directory_path() / ("demlab-big-" + std::to_string(::getpid()) + ".toml")).string();
    {
        std::ofstream(big) << "# a comment\n";
        std::filesystem::resize_file(big, (uint64_t(16) << 20) + 1);  // sparse: 16 MiB and a byte
    }
    expect_refused([&] { load_scenario(big); }, {"more than the 16 MiB"});
    std::filesystem::remove(big);
}

// A run that ends at t_max on a sample time writes its last row once (it was written twice).
TEST(Validation, TheLastSeriesRowIsWrittenOnce) {
    Scenario s = parse_scenario("[[discs]]\nposition = [0, 1]\nradius = 0.01\n[[walls]]\nstart = [-1, 0]\nend = [1, 0]\n"
                                "[stop]\nt_max = 0.1\nrest_duration = 0.05\n[output]\nseries_interval = 0.01\nsnapshot_interval = 0\ntrack = [0]\n",
                                "last-row.toml");
    s.world.timestep.automatic = false;
    s.world.timestep.fixed = 1e-4;
    finish_scenario(s);
    const auto dir = std::filesystem::temp_directory_path() / ("demlab-last-row-" + std::to_string(::getpid()));
    std::filesystem::remove_all(dir);
    run_scenario(s, {dir.string(), false, {}});
    for (const char* f : {"energy.csv", "forces.csv", "track.csv"}) {
        const std::vector<double> t = demlab::test::csv_column(dir / f, "t_s");
        ASSERT_GE(t.size(), 2u) << f;
        EXPECT_NE(t[t.size() - 2], t.back()) << f << ": the last time is written twice";
    }
    std::filesystem::remove_all(dir);
}

// A release mass that did not settle is refused with the ratio and the key to change; with
// release.accept_unsettled it runs, and summary.json records the ratio it reached.
TEST(Validation, UnsettledReleaseIsRefusedUnlessAccepted) {
    Scenario s = load_scenario(std::string(DEMLAB_SOURCE_DIR) + "/scenarios/geometry-A.toml");
    apply_override(s, "release.scale=20");
    apply_override(s, "release.settle_max_time=0.02");
    apply_override(s, "stop.t_max=0.05");
    apply_override(s, "stop.rest_duration=0.01");
    apply_override(s, "output.snapshot_interval=0");
    finish_scenario(s);
    const auto dir = std::filesystem::temp_directory_path() / ("demlab-unsettled-" + std::to_string(::getpid()));
    std::filesystem::remove_all(dir);
    try {
        run_scenario(s, {dir.string(), false, {}});
        ADD_FAILURE() << "an unsettled mass was run";
    } catch (const RunError& e) {
        const std::string m = e.what();
        EXPECT_NE(m.find("did not settle"), std::string::npos) << m;
        EXPECT_NE(m.find("release.accept_unsettled"), std::string::npos) << m;
    }
    std::filesystem::remove_all(dir);
    apply_override(s, "release.accept_unsettled=true");
    run_scenario(s, {dir.string(), false, {}});
    const std::string summary = read_file(dir / "summary.json");
    EXPECT_EQ(summary.find("\"release_settle_ratio\": null"), std::string::npos) << summary;
    EXPECT_NE(summary.find("\"release_settle_ratio\": "), std::string::npos);
    std::filesystem::remove_all(dir);
}

// Names that would write outside runs/ or hold a control character, discs that overlap at t = 0 and an empty output folder
// are input errors, refused before any output.
TEST(Validation, PathNamesOverlapsAndEmptyFoldersAreRefused) {
    for (const char* name : {"../x", "a/b", ".hidden", ""}) {
        expect_refused([&] {
            Scenario s = parse_scenario(std::string("[scenario]\nname = \"") + name + "\"\n[[discs]]\nposition = [0, 0]\nradius = 0.01\n", "n.toml");
            finish_scenario(s);
        }, {"scenario.name", "plain name"});
    }
    // nor a control character: "x\0y" made the folder runs/x and left it behind
    for (const char* name : {"x\\u0000y", "two\\nlines", "tab\\there", "del\\u007f"}) {
        expect_refused([&] {
            Scenario s = parse_scenario(std::string("[scenario]\nname = \"") + name + "\"\n[[discs]]\nposition = [0, 0]\nradius = 0.01\n", "n.toml");
            finish_scenario(s);
        }, {"scenario.name", "control character"});
    }
    expect_refused([] {
        Scenario s = parse_scenario("[[discs]]\nposition = [0, 0]\nradius = 0.01\n[[discs]]\nposition = [0.5, 0]\nradius = 0.01\n"
                                    "[[discs]]\nposition = [0.004, 0]\nradius = 0.01\n", "o.toml");
        finish_scenario(s);
    }, {"discs[0] and discs[2] overlap", "world.max_overlap_ratio"});
    // touching (or slightly overlapping) discs are fine
    Scenario ok = parse_scenario("[[discs]]\nposition = [0, 0]\nradius = 0.01\n[[discs]]\nposition = [0.0199, 0]\nradius = 0.01\n", "ok.toml");
    EXPECT_NO_THROW(finish_scenario(ok));
    expect_refused([] { prepare_output_dir("", false); }, {"needs a name"});
}

// Two undamped discs dropped 3 cm onto a floor with a fixed step just above the critical one
// create energy (a disc thrown from 4 to 28 cm): the watch names it an energy growth at every
// step size, before a disc is lost (its scale is the energy put in, which created energy does
// not inflate), and not at half of it; with the automatic step the same drop runs to t_max and
// the ledger's closure is reported against the energy put in, not as 0 for want of dissipation.
TEST(BlowUp, EnergyWatchCatchesStepsJustAboveTheCriticalOne) {
    const double m = 2672.0 * M_PI * 0.01 * 0.01, k = 0.5e8;  // disc and wall stiffness in series
    const double dt_critical = 2.0 * std::sqrt(m / k);
    auto scenario = [](const std::string& timestep) {
        Scenario s = parse_scenario("[rotation]\nmodel = 1\n[damping]\nbeta_n = 0.0\nbeta_s = 0.0\n[timestep]\n" + timestep +
                                        "\n[stop]\nt_max = 2.0\nrest_duration = 0.1\nrest_ke_fraction = 1e-12\n[output]\nsnapshot_interval = 0\n"
                                        "[[discs]]\nposition = [0.0, 0.04]\nradius = 0.01\n[[discs]]\nposition = [0.1, 0.04]\nradius = 0.01\n"
                                        "[[walls]]\nstart = [-1.0, 0.0]\nend = [1.0, 0.0]\n",
                                    "two-discs.toml");
        finish_scenario(s);
        return s;
    };
    const auto dir = std::filesystem::temp_directory_path() / ("demlab-energy-watch-" + std::to_string(::getpid()));
    for (const double factor : {1.02, 1.05, 1.10, 1.16, 1.30, 1.60}) {
        std::filesystem::remove_all(dir);
        try {
            run_scenario(scenario("automatic = false\nfixed = " + std::to_string(factor * dt_critical)), {dir.string(), false, {}});
            ADD_FAILURE() << factor << " times the critical step ran to the end";
        } catch (const RunError& e) {
            EXPECT_NE(std::string(e.what()).find("energy growth"), std::string::npos) << factor << ": " << e.what();
        }
    }
    std::filesystem::remove_all(dir);
    EXPECT_EQ(run_scenario(scenario("automatic = false\nfixed = " + std::to_string(0.5 * dt_critical)), {dir.string(), false, {}}).stop_reason,
              "t_max");
    std::filesystem::remove_all(dir);
    const RunSummary r = run_scenario(scenario("automatic = true"), {dir.string(), false, {}});
    EXPECT_EQ(r.stop_reason, "t_max");
    // the automatic step takes the free discs' step into each impact, beyond the contact's
    // critical one, and the undamped bounces lose energy the ledger cannot book: now reported
    // (91 % of the energy put in after 2 s), where "0.00 %" was printed for want of dissipation
    EXPECT_GT(r.energy_balance_error, 0.5);
    std::filesystem::remove_all(dir);
}

// A damper that makes energy is an instability even when the ledger closes (issue 48, row 5):
// a pair pressed together by constant forces, one spinning, free rotation, with the lagged
// dashpots at PFC's step rule as printed (timestep.damping_correction = false): the dashpots booked -70 J/m of
// "dissipation" and the run ended as if sound. The watch names the account, the time and the
// likely cause; with the correction the same pair runs without a word, its accounts growing.
TEST(BlowUp, FallingDissipationAccountIsAnInstability) {
    auto scenario = [](const char* correction) {
        Scenario s = parse_scenario(std::string("[world]\ngravity = [0.0, 0.0]\n[rotation]\nmodel = 2\n[timestep]\ndashpots = \"lagged\"\ndamping_correction = ") +
                                        correction + "\n[stop]\nt_max = 0.5\n[output]\nsnapshot_interval = 0\n"
                                        "[[discs]]\nposition = [0.0, 0.0]\nradius = 0.01\nomega = 10.0\nforce = [1000.0, 0.0]\n"
                                        "[[discs]]\nposition = [0.0199, 0.0]\nradius = 0.01\nforce = [-1000.0, 0.0]\n",
                                    "pressed-pair.toml");
        finish_scenario(s);
        return s;
    };
    const auto dir = temp_dir("dissipation-watch");
    try {
        run_scenario(scenario("false"), {dir.string(), false, {}});
        ADD_FAILURE() << "a damper made energy and the run ended without a word";
    } catch (const RunError& e) {
        const std::string msg = e.what();
        for (const char* fragment : {"dissipated_contacts", "fell by", "t = 0.03", "Likely cause", "timestep.damping_correction"})
            EXPECT_NE(msg.find(fragment), std::string::npos) << fragment << ": " << msg;
    }
    EXPECT_FALSE(std::filesystem::exists(dir / "summary.json"));
    std::filesystem::remove_all(dir);
    EXPECT_NO_THROW(run_scenario(scenario("true"), {dir.string(), false, {}}));
    const std::vector<double> booked = csv_column(dir / "energy.csv", "dissipated_contacts_J_per_m");
    ASSERT_GT(booked.size(), 2u);
    for (size_t k = 1; k < booked.size(); ++k) EXPECT_GE(booked[k], booked[k - 1]) << "row " << k;
    std::filesystem::remove_all(dir);
}

// What is found wrong only once the release mass exists (a tracer id past its discs) is
// refused before the run folder is made, so the corrected retry is not blocked by it.
TEST(Validation, LateFindingsLeaveNoRunFolder) {
    Scenario s = load_scenario(std::string(DEMLAB_SOURCE_DIR) + "/scenarios/geometry-A.toml");
    apply_override(s, "release.scale=20");
    apply_override(s, "output.track=[100000]");
    finish_scenario(s);
    const auto dir = std::filesystem::temp_directory_path() / ("demlab-late-" + std::to_string(::getpid()));
    std::filesystem::remove_all(dir);
    expect_refused([&] { run_scenario(s, {dir.string(), false, {}}); }, {"output.track", "100000"});
    EXPECT_FALSE(std::filesystem::exists(dir));
}

// A saved mass of another scale is refused (the resolved scenario would describe discs that
// are not the ones used), before any folder is made; the same scale is taken.
TEST(Validation, ReleaseFromAnotherScaleIsRefused) {
    Scenario s = short_geometry_a();
    const auto tmp = std::filesystem::temp_directory_path();
    const auto first = tmp / ("demlab-mass-" + std::to_string(::getpid())), second = tmp / ("demlab-mass2-" + std::to_string(::getpid()));
    std::filesystem::remove_all(first);
    std::filesystem::remove_all(second);
    run_scenario(s, {first.string(), false, {}});
    Scenario other = load_scenario(std::string(DEMLAB_SOURCE_DIR) + "/scenarios/geometry-A.toml");
    apply_override(other, "release.scale=10");
    other.release.from_file = (first / "release.csv").string();
    finish_scenario(other);
    expect_refused([&] { run_scenario(other, {second.string(), false, {}}); }, {"release.csv", "release.scale = 10"});
    EXPECT_FALSE(std::filesystem::exists(second));
    s.release.from_file = (first / "release.csv").string();
    EXPECT_NO_THROW(run_scenario(s, {second.string(), false, {}}));
    std::filesystem::remove_all(first);
    std::filesystem::remove_all(second);
}

// A saved mass cut at a line's end, edited off the box, or with tags or figures that are no
// numbers is refused before the run folder is made, naming the file.
TEST(Validation, ReleaseFromACutOrEditedFileIsRefused) {
    Scenario s = short_geometry_a();
    namespace fs = std::filesystem;
    const auto tmp = fs::temp_directory_path();
    const auto first = tmp / ("demlab-cut-" + std::to_string(::getpid())), second = tmp / ("demlab-cut2-" + std::to_string(::getpid()));
    const std::string edited = (tmp / ("demlab-cut-" + std::to_string(::getpid()) + ".csv")).string();
    fs::remove_all(first);
    fs::remove_all(second);
    run_scenario(s, {first.string(), false, {}});
    std::vector<std::string> lines;
    {
        std::ifstream in(first / "release.csv");
        for (std::string l; std::getline(in, l);) lines.push_back(l);
    }
    size_t row0 = 0;  // the first disc row
    while (row0 < lines.size() && (lines[row0].empty() || lines[row0][0] == '#' || lines[row0][0] == 'i')) ++row0;
    ASSERT_LT(row0 + 2, lines.size());
    auto refused = [&](std::vector<std::string> text, const std::vector<std::string>& words) {
        std::string all;
        for (const std::string& l : text) all += l + "\n";
        write_file_atomic(edited, all);
        Scenario t = s;
        t.release.from_file = edited;
        expect_refused([&] { run_scenario(t, {second.string(), false, {}}); }, words);
        EXPECT_FALSE(fs::exists(second));
    };
    auto with_cell = [&](size_t row, int column, const std::string& value) {
        std::vector<std::string> text = lines;
        std::vector<std::string> cells;
        std::istringstream in(text[row]);
        for (std::string c; std::getline(in, c, ',');) cells.push_back(c);
        cells[size_t(column)] = value;
        text[row].clear();
        for (size_t c = 0; c < cells.size(); ++c) text[row] += (c ? "," : "") + cells[c];
        return text;
    };
    std::vector<std::string> cut(lines.begin(), lines.end() - 1);
    refused(cut, {edited, "disc rows", "'# n'"});
    refused(with_cell(row0 + 1, 2, "5.0"), {edited, "outside", "row 1"});
    refused(with_cell(row0 + 1, 2, "100000"), {edited, "outside"});
    refused(with_cell(row0, 4, "nan"), {edited, "layer"});
    refused(with_cell(row0, 5, "1e30"), {edited, "grid"});
    refused(with_cell(row0, 4, "-3"), {edited, "layer"});
    std::vector<std::string> header = lines;
    for (std::string& l : header)
        if (l.rfind("# porosity_generated ", 0) == 0) l = "# porosity_generated nan";
    refused(header, {edited, "porosity_generated"});
    fs::remove(edited);
    fs::remove_all(first);
}

// --force replaces a folder's content: a shorter run over a longer one leaves none of the old
// snapshots; the old folder is kept aside until the new run is complete, so a forced run that
// fails loses nothing.
TEST(Validation, ForceReplacesTheFolderAndAFailedRunLosesNothing) {
    auto drop = [](double t_max, const std::string& extra) {
        Scenario s = parse_scenario("[stop]\nt_max = " + std::to_string(t_max) + "\nrest_duration = 0.01\nrest_ke_fraction = 1e-12\n"
                                    "[output]\nseries_interval = 0.005\nsnapshot_interval = 0.02\n" + extra +
                                    "[[discs]]\nposition = [0.0, 0.05]\nradius = 0.01\n[[walls]]\nstart = [-1, 0]\nend = [1, 0]\n",
                                    "drop.toml");
        finish_scenario(s);
        return s;
    };
    const auto dir = std::filesystem::temp_directory_path() / ("demlab-force-" + std::to_string(::getpid()));
    std::filesystem::remove_all(dir);
    run_scenario(drop(0.12, ""), {dir.string(), false, {}});
    EXPECT_TRUE(std::filesystem::exists(dir / "snapshots/discs_00006.vtp"));
    run_scenario(drop(0.04, ""), {dir.string(), true, {}});
    EXPECT_FALSE(std::filesystem::exists(dir / "snapshots/discs_00006.vtp"));  // none of the old run's
    EXPECT_TRUE(std::filesystem::exists(dir / "snapshots/discs_00002.vtp"));
    EXPECT_FALSE(std::filesystem::exists(replaced_output_dir(dir.string())));
    // a forced run that blows up: the old folder is still there, aside
    EXPECT_THROW(run_scenario(drop(0.12, "[timestep]\nautomatic = false\nfixed = 0.01\n"), {dir.string(), true, {}}), RunError);
    EXPECT_TRUE(std::filesystem::exists(replaced_output_dir(dir.string()) + "/snapshots/discs_00002.vtp"));
    std::filesystem::remove_all(dir);
    std::filesystem::remove_all(replaced_output_dir(dir.string()));
}

// --force replaces demlab's own files only: a completed run lists them in its marker, and a
// folder the user has put notes or an analysis into is refused (exit 2) with both kept.
TEST(Validation, ForceKeepsOffTheUsersOwnFilesInARunFolder) {
    Scenario s = parse_scenario("[stop]\nt_max = 0.04\nrest_duration = 0.01\nrest_ke_fraction = 1e-12\n"
                                "[output]\nseries_interval = 0.005\nsnapshot_interval = 0.02\n"
                                "[[discs]]\nposition = [0.0, 0.05]\nradius = 0.01\n[[walls]]\nstart = [-1, 0]\nend = [1, 0]\n",
                                "drop.toml");
    finish_scenario(s);
    namespace fs = std::filesystem;
    const auto dir = fs::temp_directory_path() / ("demlab-force-own-" + std::to_string(::getpid()));
    fs::remove_all(dir);
    run_scenario(s, {dir.string(), false, {}});
    run_scenario(s, {dir.string(), true, {}});  // demlab's files only: replaced
    write_file_atomic((dir / "notes.txt").string(), "my notes\n");
    fs::create_directories(dir / "snapshots/mine");
    write_file_atomic((dir / "snapshots/mine/fig.txt").string(), "x\n");
    // and inside a folder with its own marker (as plots/ and frames/ are)
    fs::create_directories(dir / "plots");
    mark_output_dir((dir / "plots").string());
    write_file_atomic((dir / "plots/a.png").string(), "png\n");
    record_output_files((dir / "plots").string());
    write_file_atomic((dir / "plots/b.txt").string(), "mine\n");
    const std::string what = expect_refused([&] { run_scenario(s, {dir.string(), true, {}}); },
                                            {"'notes.txt'", "'snapshots/mine'", "'plots/b.txt'", "4 entries"});
    EXPECT_EQ(what.find("a.png"), std::string::npos) << what;  // demlab's own, listed
    EXPECT_TRUE(fs::exists(dir / "notes.txt"));
    EXPECT_TRUE(fs::exists(dir / "snapshots/mine/fig.txt"));
    EXPECT_TRUE(fs::exists(dir / "plots/b.txt"));
    EXPECT_TRUE(fs::exists(dir / "summary.json"));
    fs::remove(dir / "notes.txt");
    fs::remove(dir / "plots/b.txt");
    fs::remove_all(dir / "snapshots/mine");
    run_scenario(s, {dir.string(), true, {}});
    EXPECT_TRUE(fs::exists(dir / "summary.json"));
    EXPECT_FALSE(fs::exists(replaced_output_dir(dir.string())));
    fs::remove_all(dir);
}

// A series file cut short behind the checkpoint's back is an input error on resume (exit 2),
// naming the file, not a failed run.
TEST(Validation, TruncatedSeriesOnResumeIsAnInputError) {
    Scenario s = parse_scenario("[stop]\nt_max = 0.12\nrest_duration = 0.01\nrest_ke_fraction = 1e-12\n"
                                "[output]\nseries_interval = 0.005\nsnapshot_interval = 0.02\n"
                                "[[discs]]\nposition = [0.0, 0.05]\nradius = 0.01\n[[walls]]\nstart = [-1, 0]\nend = [1, 0]\n",
                                "drop.toml");
    finish_scenario(s);
    const auto dir = std::filesystem::temp_directory_path() / ("demlab-truncated-" + std::to_string(::getpid()));
    std::filesystem::remove_all(dir);
    RunOptions ro{dir.string(), false, [](const std::string&, const std::string&, int index) {
                      if (index == 3) request_interrupt(SIGTERM);
                  }};
    ro.handle_signals = true;
    EXPECT_THROW(run_scenario(s, ro), Interrupted);
    std::filesystem::resize_file(dir / "energy.csv.part", 10);
    Scenario again = load_scenario((dir / "scenario.toml").string());
    finish_scenario(again);
    RunOptions rr{dir.string(), false, {}};
    rr.resume = true;
    expect_refused([&] { run_scenario(again, rr); }, {"energy.csv.part", "shorter than at the checkpoint"});
    std::filesystem::remove_all(dir);
}

// stop.max_steps ends a run after that many steps, with its outputs complete (DEM and DAN).
TEST(Validation, MaxStepsEndsTheRunWithItsOutputs) {
    Scenario s = parse_scenario("[[discs]]\nposition = [0, 1]\nradius = 0.01\n[[walls]]\nstart = [-1, 0]\nend = [1, 0]\n"
                                "[stop]\nt_max = 10\nmax_steps = 50\n[output]\nsnapshot_interval = 0\n",
                                "max-steps.toml");
    finish_scenario(s);
    const auto dir = std::filesystem::temp_directory_path() / ("demlab-max-steps-" + std::to_string(::getpid()));
    std::filesystem::remove_all(dir);
    const RunSummary r = run_scenario(s, {dir.string(), false, {}});
    EXPECT_EQ(r.steps, 50);
    EXPECT_EQ(r.stop_reason, "max_steps");
    EXPECT_TRUE(std::filesystem::exists(dir / "summary.json"));
    std::filesystem::remove_all(dir);
    Scenario d = load_scenario(std::string(DEMLAB_SOURCE_DIR) + "/scenarios/geometry-A.toml");
    apply_override(d, "scenario.solver=\"dan\"");
    apply_override(d, "stop.max_steps=30");
    finish_scenario(d);
    const RunSummary rd = run_scenario(d, {dir.string(), false, {}});
    EXPECT_EQ(rd.steps, 30);
    EXPECT_EQ(rd.stop_reason, "max_steps");
    std::filesystem::remove_all(dir);
    expect_refused([] { parse_scenario("[stop]\nmax_steps = -1\n", "bad.toml"); }, {"stop.max_steps", "-1"});
}

// release.from_file is the scenario file's neighbour, as terrain.profile and the other files a
// scenario names: resolved absolute, the run folder's copy and a resume from any working
// directory read the same mass.
TEST(Validation, ReleaseFromFileIsTheScenarioFilesNeighbour) {
    namespace fs = std::filesystem;
    const fs::path work = temp_dir("from-file");
    std::string text = read_file(fs::path(DEMLAB_SOURCE_DIR) / "scenarios/geometry-A.toml");
    const size_t at = text.find("[release]\n");
    ASSERT_NE(at, std::string::npos);
    text.insert(at + 10, "from_file = \"../masses/release.csv\"\n");
    fs::create_directories(work / "project");
    write_file_atomic((work / "project/a.toml").string(), text);
    Scenario s = load_scenario((work / "project/a.toml").string());
    finish_scenario(s);
    EXPECT_EQ(fs::path(s.release.from_file), (fs::absolute(work) / "masses/release.csv").lexically_normal());
    fs::remove_all(work);
}

// A release mass settled without gravity (world.gravity = [0, 0], a valid value) puts no load on
// its lid: release.csv holds 0 there, not 0 / 0 written as inf, and reads back as a start.
TEST(Validation, AReleaseWithoutGravityWritesAFiniteLidLoadAndReadsBack) {
    namespace fs = std::filesystem;
    const fs::path work = temp_dir("no-gravity");
    Scenario s = load_scenario(std::string(DEMLAB_SOURCE_DIR) + "/scenarios/geometry-A.toml");
    for (const char* o : {"release.scale=20", "world.gravity=[0, 0]", "stop.t_max=0.002", "stop.rest_duration=0.001"})
        apply_override(s, o);
    finish_scenario(s);
    run_scenario(s, {(work / "a").string(), false, {}});
    const std::string release = read_file(work / "a/release.csv");
    EXPECT_NE(release.find("# lid_load_fraction 0\n"), std::string::npos);
    Scenario again = s;
    again.release.from_file = (work / "a/release.csv").string();
    EXPECT_NO_THROW(run_scenario(again, {(work / "b").string(), false, {}}));
    fs::remove_all(work);
}
