// Guards on the physics and the input (issue 54's rows 8-15): no disc crosses a wall between
// two steps, magnitudes are bounded at input and a non-finite ledger ends the run, a wall
// without its points is refused, options that do not apply or disagree are named, a cut CSV
// and an absurd disc count are input errors, and `demo` has the absurd-steps guard.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "core/csv.h"
#include "core/error.h"
#include "calibration/calibration.h"
#include "dem/world.h"
#include "dem3/tin.h"
#include "geometry/esri_grid.h"
#include "geometry/profile.h"
#include "geometry/deposit.h"
#include "files.h"
#include "helpers.h"
#include "run/run.h"
#include "scenario/scenario.h"
#include "setups/lattice_release.h"
#include "setups/release.h"
#include "setups/setup.h"

namespace fs = std::filesystem;
using namespace demlab;
using demlab::test::expect_refused;
using demlab::test::read_file;

namespace {

fs::path temp_dir(const std::string& name) {
    const fs::path d = fs::temp_directory_path() / ("demlab-guards-" + name + "-" + std::to_string(::getpid()));
    fs::remove_all(d);
    return d;
}

// One disc of 1 cm above a floor from x = -1 to 1 m, the rest of the scenario as given.
Scenario one_disc(const std::string& disc, const std::string& rest) {
    Scenario s = parse_scenario("[stop]\nt_max = 1.0\nrest_duration = 0.1\nrest_ke_fraction = 1e-12\n[output]\nsnapshot_interval = 0\n" +
                                    rest + "\n[[discs]]\nradius = 0.01\n" + disc + "\n[[walls]]\nname = \"floor\"\nstart = [-1.0, 0.0]\nend = [1.0, 0.0]\n",
                                "one-disc.toml");
    finish_scenario(s);
    return s;
}

// The executable's exit code, its standard error in `err`; stopped after 60 s (exit 124), so
// that an option accepted by mistake (a flume generated at scale 4, a demo to t = 1e300 s)
// fails the test instead of hanging it.
int run_exe(const std::string& args, std::string& err) {
    const fs::path log = temp_dir("stderr");
    const int status = std::system(("timeout 60 " + std::string(DEMLAB_EXE) + " " + args + " >/dev/null 2>" + log.string()).c_str());
    std::ifstream in(log);
    std::stringstream ss;
    ss << in.rdbuf();
    err = ss.str();
    fs::remove(log);
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

void write_text(const fs::path& p, const std::string& text) {
    std::ofstream(p) << text;
}

// One disc dropped onto a floor for 0.05 s with a snapshot every 0.02 s (dir/drop.toml), run
// by the executable into `run`: a run folder with every kind of file, made in a fraction of a
// second. Its exit code; its standard error in `err`.
int run_drop(const fs::path& dir, const std::string& run, std::string& err) {
    const fs::path sc = dir / "drop.toml";
    write_text(sc, "[stop]\nt_max = 0.05\nrest_duration = 0.01\n[output]\nsnapshot_interval = 0.02\n"
                   "[[discs]]\nposition = [0.0, 0.05]\nradius = 0.01\n[[walls]]\nstart = [-1, 0]\nend = [1, 0]\n");
    return run_exe("run " + sc.string() + " --no-plots --out " + run, err);
}

}  // namespace

// Row 8. A DEBRIS disc falls 2 m at the default ceiling debris.dt_max = 0.01 s (4 cm a step
// at the floor, four radii): the step is cut by speed and radius, and it lands on the floor
// instead of passing through it and being taken out as "lost".
TEST(Guards, DebrisDiscDroppedOntoAFloorDoesNotPassThroughIt) {
    const Scenario s = one_disc("position = [0.0, 2.0]", "[contact]\nlaw = \"debris\"\n[rotation]\nmodel = 1\n");
    ASSERT_EQ(s.world.law_def<DebrisLaw>().dt_max, 0.01);
    ASSERT_EQ(s.world.lost_discs, LostDiscs::Remove);
    const fs::path dir = temp_dir("debris-drop");
    const RunSummary r = run_scenario(s, {dir.string(), false, {}});
    EXPECT_EQ(r.lost_discs, 0) << "the disc went through the floor";
    World w = world_of_scenario(s);
    while (w.time() < 1.0) w.step();
    ASSERT_EQ(w.disc_count(), 1u);
    EXPECT_GT(w.positions()[0].y(), 0.5 * w.radii()[0]) << "the disc is below the floor's top";
    fs::remove_all(dir);
}

// Row 8. A linear-law disc given 3,000 m/s towards the floor with the automatic step: each
// step takes it at most a quarter radius, so the contact sees it, and a floor too soft to
// stop it is an overlap named with the wall (not a disc that left the domain, exit 0).
TEST(Guards, FastDiscIsSeenByTheFloorItHits) {
    const Scenario s = one_disc("position = [0.0, 0.5]\nvelocity = [0.0, -3000.0]", "");
    const fs::path dir = temp_dir("fast");
    try {
        const RunSummary r = run_scenario(s, {dir.string(), false, {}});
        ADD_FAILURE() << "ran to the end with " << r.lost_discs << " lost disc(s)";
    } catch (const RunError& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find("overlap"), std::string::npos) << msg;
        EXPECT_NE(msg.find("floor"), std::string::npos) << msg;
    }
    fs::remove_all(dir);
}

// Row 8. A fixed step (timestep.fixed) of 0.1 s: the falling disc moves 10 cm in a step, ten radii; the
// run is refused naming the disc and the key instead of letting it through the floor.
TEST(Guards, FixedStepThatCarriesADiscFartherThanHalfItsRadiusIsRefused) {
    const Scenario s = one_disc("position = [0.0, 0.5]", "[timestep]\nautomatic = false\nfixed = 0.1\n");
    const fs::path dir = temp_dir("fixed");
    try {
        const RunSummary r = run_scenario(s, {dir.string(), false, {}});
        ADD_FAILURE() << "ran to the end with " << r.lost_discs << " lost disc(s)";
    } catch (const RunError& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find("disc 0 moved"), std::string::npos) << msg;
        EXPECT_NE(msg.find("timestep.fixed = 0.1 s"), std::string::npos) << msg;
    }
    fs::remove_all(dir);
    // the same world at a sound step falls onto the floor and stays there
    World w = world_of_scenario(one_disc("position = [0.0, 0.5]", "[timestep]\nautomatic = false\nfixed = 1e-5\n"));
    for (int k = 0; k < 50000; ++k) w.step();
    ASSERT_EQ(w.disc_count(), 1u);
    EXPECT_GT(w.positions()[0].y(), 0.5 * w.radii()[0]);
}

// Row 10. Velocities, spins, forces and gravity beyond the bounds are refused with the key;
// the bounds themselves are accepted.
TEST(Guards, MagnitudesAreBoundedAtInput) {
    auto disc = [](const std::string& extra) { one_disc("position = [0.0, 0.5]\n" + extra, ""); };
    expect_refused([&] { disc("velocity = [1e300, 0.0]"); }, {"discs[0].velocity", "at most 10000 m/s"});
    expect_refused([&] { disc("omega = 1e300"); }, {"discs[0].omega", "1e+06"});
    expect_refused([&] { disc("omega = -2e6"); }, {"discs[0].omega"});
    expect_refused([&] { disc("force = [0.0, 1e300]"); }, {"discs[0].force", "N/m"});
    // the rolling penetration against the given discs' smallest radius, with the file's name
    // (the world's own check, after the scenario's, has none)
    expect_refused([&] { one_disc("position = [0.0, 0.5]", "[rotation]\nmodel = 3\nu_rr = 0.006\n"); },
                   {"one-disc.toml: rotation.u_rr = 0.006 m", "smallest disc radius"});
    EXPECT_NO_THROW(one_disc("position = [0.0, 0.5]", "[rotation]\nmodel = 3\nu_rr = 0.0059\n"));
    expect_refused([&] { parse_scenario("[[discs]]\nposition = [0.0, 0.5]\nradius = 1e300\n", "d.toml"); }, {"discs[0].radius"});
    expect_refused([&] { one_disc("position = [0.0, 0.5]", "[world]\ngravity = [0.0, -1e300]\n"); }, {"world.gravity", "1000"});
    expect_refused([&] { one_disc("position = [0.0, 0.5]", "[world]\ngravity = [800.0, -800.0]\n"); }, {"world.gravity"});
    expect_refused([&] { parse_scenario("[[walls]]\nstart = [0.0, 0.0]\nend = [1.0, 0.0]\nvelocity = [2e4, 0.0]\n", "w.toml"); },
                   {"walls[0].velocity"});
    EXPECT_NO_THROW(one_disc("position = [0.0, 0.5]\nvelocity = [1e4, 0.0]\nomega = -1e6\nforce = [0.0, 1e12]", "[world]\ngravity = [0.0, -1e3]\n"));
}

// Row 10. A ledger that is not finite (a spin far beyond the input bound, put in behind the
// scenario's back) ends the run with a RunError; no energy.csv row of inf or nan is written
// and the run does not finish.
TEST(Guards, NonFiniteLedgerEndsTheRun) {
    Scenario s = one_disc("position = [0.0, 0.5]", "");
    s.discs[0].omega = 1e300;  // 0.5 I omega^2 overflows
    const fs::path dir = temp_dir("nonfinite");
    try {
        run_scenario(s, {dir.string(), false, {}});
        ADD_FAILURE() << "ran to the end";
    } catch (const RunError& e) {
        EXPECT_NE(std::string(e.what()).find("energy ledger is not finite"), std::string::npos) << e.what();
    }
    EXPECT_FALSE(fs::exists(dir / "summary.json"));
    fs::remove_all(dir);
}

// Row 11. A wall without one of its points is refused naming the wall and the key, as a disc
// without its position is.
TEST(Guards, WallWithoutItsPointsIsRefused) {
    expect_refused([] { parse_scenario("[[walls]]\nend = [1.0, 0.0]\n", "w.toml"); }, {"walls[0]", "missing key 'start'"});
    expect_refused([] { parse_scenario("[[walls]]\nstart = [1.0, 0.0]\n", "w.toml"); }, {"walls[0]", "missing key 'end'"});
    expect_refused([] { parse_scenario("[[walls]]\ntype = \"arc\"\nradius = 1.0\nstart_deg = 0\nend_deg = 90\n", "w.toml"); },
                   {"walls[0]", "missing key 'centre'"});
    expect_refused([] { parse_scenario("[[walls]]\ntype = \"arc\"\ncentre = [0.0, 1.0]\nstart_deg = 0\nend_deg = 90\n", "w.toml"); },
                   {"walls[0]", "missing key 'radius'"});
    // an arc sweeps at most a full circle
    expect_refused([] { parse_scenario("[[walls]]\ntype = \"arc\"\ncentre = [0.0, 1.0]\nradius = 1.0\nstart_deg = 0\nend_deg = 720\n", "w.toml"); },
                   {"walls[0]", "sweeps 720 deg", "(0, 360]"});
    EXPECT_NO_THROW(parse_scenario("[[walls]]\ntype = \"arc\"\ncentre = [0.0, 1.0]\nradius = 1.0\nstart_deg = 0\nend_deg = 360\n", "w.toml"));
    EXPECT_NO_THROW(parse_scenario("[[walls]]\nstart = [0.0, 0.0]\nend = [1.0, 0.0]\n", "w.toml"));
}

// Row 12. A release mass file or bonds given where they do not apply are refused with the key.
TEST(Guards, KeysThatDoNotApplyAreRefused) {
    expect_refused([] {
        Scenario s = parse_scenario("[release]\nfrom_file = \"mass.csv\"\n[[discs]]\nposition = [0.0, 0.5]\nradius = 0.01\n", "d.toml");
        finish_scenario(s);
    }, {"release.from_file", "does not apply"});
    expect_refused([] {
        Scenario s = parse_scenario("[cohesion]\nbonds = [[0, 1]]\n[[discs]]\nposition = [0.0, 0.5]\nradius = 0.01\n"
                                    "[[discs]]\nposition = [0.02, 0.5]\nradius = 0.01\n", "d.toml");
        finish_scenario(s);
    }, {"cohesion.bonds", "cohesion.enabled"});
}

// Row 12. Command-line options that do not apply to the scenario, or that a --set of the
// same key contradicts, are refused (exit 2) naming them.
TEST(Guards, RunOptionsThatDoNotApplyOrDisagreeAreRefused) {
    const fs::path dir = temp_dir("opts");
    fs::create_directories(dir);
    const fs::path sc = dir / "two.toml";
    write_text(sc, "[[discs]]\nposition = [0.0, 0.5]\nradius = 0.01\n[[walls]]\nstart = [-1.0, 0.0]\nend = [1.0, 0.0]\n");
    const std::string out = " --no-plots --out " + (dir / "run").string();
    std::string err;
    EXPECT_EQ(run_exe("run " + sc.string() + " --scale 4" + out, err), 2);
    EXPECT_NE(err.find("--scale does not apply"), std::string::npos) << err;
    EXPECT_EQ(run_exe("run " + sc.string() + " --variant II" + out, err), 2);
    EXPECT_NE(err.find("--variant does not apply"), std::string::npos) << err;
    EXPECT_EQ(run_exe("run " + sc.string() + " --release-from " + sc.string() + out, err), 2);
    EXPECT_NE(err.find("release.from_file (--release-from)"), std::string::npos) << err;
    const std::string geometry_a = std::string(DEMLAB_SOURCE_DIR) + "/scenarios/geometry-A.toml";
    EXPECT_EQ(run_exe("run " + geometry_a + " --scale 20 --set release.scale=4" + out, err), 2);
    EXPECT_NE(err.find("--scale and --set release.scale=4 both set release.scale"), std::string::npos) << err;
    EXPECT_EQ(run_exe("run " + geometry_a + " --model 2 --set ' rotation.model = 3'" + out, err), 2);
    EXPECT_NE(err.find("--model and --set"), std::string::npos) << err;
    EXPECT_FALSE(fs::exists(dir / "run"));
    fs::remove_all(dir);
}

// Row 14. A CSV whose last row is cut (a full disk, a killed writer) is an input error naming
// the file and the line, not an out-of-range access in `demlab plot`.
TEST(Guards, CutCsvIsAnInputErrorNamingFileAndLine) {
    const fs::path dir = temp_dir("csv");
    fs::create_directories(dir);
    const fs::path f = dir / "forces.csv";
    write_text(f, "t_s,fx_N_per_m,fy_N_per_m\n0,1,2\n0.1,1.5\n");
    expect_refused([&] { read_csv_table(f.string()); }, {"forces.csv:3", "2 cells, the header has 3"});
    write_text(f, "t_s,fx_N_per_m,fy_N_per_m\n0,1,2\n0.1,1.5,2.");
    expect_refused([&] { read_csv_table(f.string()); }, {"forces.csv:3", "no line end"});
    write_text(f, "t_s,fx_N_per_m,fy_N_per_m\n0,1,2\n0.1,1.5,2.5\n");
    EXPECT_EQ(read_csv_table(f.string()).rows.size(), 2u);
    // the executable: plot on a run folder with a cut series
    fs::create_directories(dir / "run");
    write_text(dir / "run" / "scenario.toml", "[[discs]]\nposition = [0.0, 0.5]\nradius = 0.01\n");
    write_text(dir / "run" / "forces.csv", "t_s,fx_slope_N_per_m\n0,1\n0.1");
    std::string err;
    const int code = run_exe("plot " + (dir / "run").string(), err);
    if (err.find("gnuplot") == std::string::npos) {  // (without gnuplot, plot stops before reading)
        EXPECT_EQ(code, 2) << err;
        EXPECT_EQ(err.find("_M_range_check"), std::string::npos) << err;
    }
    // every series plot and compare read is checked whole, and summary.json too: a damaged
    // run folder is refused naming the file, not drawn short or read as "not measured"
    const fs::path real = dir / "real";
    const std::string geometry_a = std::string(DEMLAB_SOURCE_DIR) + "/scenarios/geometry-A.toml";
    ASSERT_EQ(run_exe("run " + geometry_a + " --scale 20 --threads 1 --no-plots --set stop.t_max=0.05 --set stop.rest_duration=0.01 --out " + real.string(), err), 0) << err;
    for (const char* series : {"front.csv", "energy.csv", "forces.csv", "summary.json"}) {
        const fs::path cut = dir / (std::string("cut-") + series);
        fs::copy(real, cut, fs::copy_options::recursive);
        const std::string whole = read_file(cut / series);
        write_text(cut / series, whole.substr(0, whole.size() * 2 / 3));
        if (std::string(series) != "summary.json") {
            const int plot = run_exe("plot " + cut.string(), err);
            if (err.find("gnuplot is not installed") == std::string::npos) {
                EXPECT_EQ(plot, 2) << series << ": " << err;
                EXPECT_NE(err.find(series), std::string::npos) << err;
            }
        }
        if (std::string(series) == "energy.csv") continue;  // (compare does not read it)
        EXPECT_EQ(run_exe("compare " + real.string() + " " + cut.string() + " --out " + (dir / "cmp").string(), err), 2)
            << series << ": " << err;
        EXPECT_NE(err.find(series), std::string::npos) << err;
        EXPECT_FALSE(fs::exists(dir / "cmp"));
    }
    fs::remove_all(dir);
}

// Row 14. A release of micrometre discs is refused from the area and the radii before any
// disc is allocated (it ended in std::bad_alloc), naming the keys; the lattice too.
TEST(Guards, AbsurdDiscCountsAreRefusedBeforeAllocation) {
    Scenario s = load_scenario(std::string(DEMLAB_SOURCE_DIR) + "/scenarios/geometry-A.toml");
    apply_override(s, "release.r_min=1e-5");
    apply_override(s, "release.r_max=2e-5");
    apply_override(s, "rotation.u_rr=1e-6");
    finish_scenario(s);
    expect_refused([&] { generate_release(s); }, {"release.r_min", "release.r_max", "more than 2e+07"});
    Scenario l = parse_scenario("[lattice_release]\nregion = [[0.0, 0.0], [100.0, 0.0], [100.0, 100.0], [0.0, 100.0]]\n"
                                "origin = [0.0, 0.0]\nr_min = 1e-5\n[rotation]\nu_rr = 1e-6\n", "lattice.toml");
    finish_scenario(l);
    expect_refused([&] { lattice_mass(l, {}); }, {"lattice_release", "spacing", "more than 2e+07"});
}

// Row 15 and the seed. `demo --t-end 1e300` is refused before its folder is made (it ran
// until killed), and a negative seed is refused instead of wrapping to 2^64 - 1.
TEST(Guards, DemoRefusesAbsurdRunsAndNegativeSeeds) {
    const fs::path dir = temp_dir("demo");
    std::string err;
    EXPECT_EQ(run_exe("demo --t-end 1e300 --out " + dir.string(), err), 2);
    EXPECT_NE(err.find("demo --t-end"), std::string::npos) << err;
    EXPECT_FALSE(fs::exists(dir));
    EXPECT_EQ(run_exe("demo --seed -1 --out " + dir.string(), err), 2);
    EXPECT_NE(err.find("--seed -1"), std::string::npos) << err;
    // one past 2^64: refused, not taken as 2^63 - 1
    EXPECT_EQ(run_exe("demo --seed 99999999999999999999 --out " + dir.string(), err), 2);
    EXPECT_NE(err.find("--seed 99999999999999999999"), std::string::npos) << err;
    EXPECT_FALSE(fs::exists(dir));
}

// The demo writes a run folder like any run (issue 55, row 8): its resolved scenario, series,
// snapshots and summary, which `render` takes (it was refused: "was output.snapshot_interval
// 0?"), and `run` of its scenario.toml gives the same series.
TEST(Guards, DemoWritesARunFolder) {
    const fs::path dir = temp_dir("demo-folder"), again = temp_dir("demo-again"), frames = temp_dir("demo-frames");
    std::string err;
    ASSERT_EQ(run_exe("demo --t-end 0.04 --no-plots --out " + dir.string(), err), 0) << err;
    for (const char* f : {"scenario.toml", "summary.json", "forces.csv", "energy.csv", "envelope.csv", "release.csv",
                          "snapshots/discs.pvd"})
        EXPECT_TRUE(fs::exists(dir / f)) << f;
    EXPECT_EQ(run_exe("render " + dir.string() + " --out " + frames.string(), err), 0) << err;
    EXPECT_TRUE(fs::exists(frames / "frame_00000.png"));
    ASSERT_EQ(run_exe("run " + (dir / "scenario.toml").string() + " --no-plots --out " + again.string(), err), 0) << err;
    for (const char* f : {"forces.csv", "energy.csv", "envelope.csv"}) EXPECT_EQ(read_file(dir / f), read_file(again / f)) << f;
    for (const fs::path& d : {dir, again, frames}) fs::remove_all(d);
}

// Discs of a --release-from file that overlap beyond world.max_overlap_ratio are named with
// the file (exit 2) instead of stopping the first step as a blow-up (exit 3).
TEST(Guards, OverlappingDiscsInAReleaseFileAreNamed) {
    Scenario s = test::short_geometry_a();
    ReleaseMass m = generate_release(s);
    for (const WallDef& wd : make_setup(s)->release_box().walls) m.box_walls.push_back({wd.p0, wd.p1});
    ASSERT_GT(m.pos.size(), 10u);
    m.pos[7] = m.pos[3] + Vec2(0.1 * m.radius[3], 0.0);  // almost on top of disc 3
    const fs::path dir = temp_dir("overlap");
    fs::create_directories(dir);
    const fs::path file = dir / "release.csv";
    save_release(m, file.string());
    s.release.from_file = file.string();
    expect_refused([&] { run_scenario(s, {(dir / "run").string(), false, {}}); }, {"release.csv", "discs 3 and 7", "overlap"});
    EXPECT_FALSE(fs::exists(dir / "run"));
    fs::remove_all(dir);
}

// A mistyped option or command gets a "did you mean", as a mistyped key does (issue 55, row
// 10), and the usage exit code; no folder is made.
TEST(Guards, MistypedOptionsAndCommandsAreNamedWithTheNearest) {
    const std::string scenario = std::string(DEMLAB_SOURCE_DIR) + "/scenarios/geometry-A.toml";
    const fs::path out = temp_dir("mistyped");
    std::string err;
    EXPECT_EQ(run_exe("run " + scenario + " --scal 20 --out " + out.string(), err), 1);
    EXPECT_NE(err.find("no option '--scal'; did you mean '--scale'?"), std::string::npos) << err;
    EXPECT_EQ(run_exe("run " + scenario + " --thread=2 --out " + out.string(), err), 1);
    EXPECT_NE(err.find("no option '--thread'; did you mean '--threads'?"), std::string::npos) << err;
    EXPECT_EQ(run_exe("rnu " + scenario, err), 1);
    EXPECT_NE(err.find("no command 'rnu'; did you mean 'run'?"), std::string::npos) << err;
    // an option spelt right is not named
    EXPECT_EQ(run_exe("run " + scenario + " --scale 20 --bogus-flag-xyz --out " + out.string(), err), 1);
    EXPECT_EQ(err.find("'--scale'"), std::string::npos) << err;
    EXPECT_FALSE(fs::exists(out));
}

// A bin of output.deposit_bin so small that the bed path would get billions of bins (deposit.csv,
// peaks.csv, surface.csv) is an input error naming the file, the key and the smallest bin
// allowed, for the discs and for DAN, before the run folder exists (it ended in an allocation
// failure after release.csv and scenario.toml were written).
TEST(Guards, DepositBinsThatWouldExhaustTheMemoryAreRefusedBeforeTheRun) {
    const fs::path dir = temp_dir("deposit-bins");
    fs::create_directories(dir);
    const std::string geometry_a = std::string(DEMLAB_SOURCE_DIR) + "/scenarios/geometry-A.toml";
    const std::string out = " --no-plots --out " + (dir / "run").string();
    for (const char* solver : {"dem", "dan"}) {
        std::string err;
        const std::string scale = std::string(solver) == "dem" ? " --scale 20" : "";  // (DAN refuses --scale)
        EXPECT_EQ(run_exe("run " + geometry_a + " --solver " + solver + scale + " --set output.deposit_bin=1e-12" + out, err), 2)
            << solver;
        for (const char* part : {"geometry-A.toml: output.deposit_bin = 1e-12 m", "2.823 m long", "more than 1e+07",
                                 "at least 2.823e-07 m"})
            EXPECT_NE(err.find(part), std::string::npos) << solver << ": " << err;
        EXPECT_FALSE(fs::exists(dir / "run")) << solver;
    }
    fs::remove_all(dir);
}

// Row 15. Options that were accepted though wrong: --size with trailing characters, an empty
// --strip, a strip whose folder does not exist (found only after every frame was rendered),
// --scale and --variant with DAN (silently unused), resume's --checkpoint-every nan. Each is
// refused before anything is written.
// The files that render and calibrate read back from a run folder are checked as the series
// are: a snapshot index whose time is not a number, or whose file points out of the folder; a
// DAN blocks.csv or an envelope.csv with a cell that is not a number; calibrate's --angles
// with trailing text. Each is an input error naming the file (and line), exit 2.
TEST(Guards, DamagedIndexesAndNumbersInRunFilesAreInputErrors) {
    const fs::path dir = temp_dir("indexes");
    fs::create_directories(dir);
    const std::string run = (dir / "run").string();
    std::string err;
    ASSERT_EQ(run_drop(dir, run, err), 0) << err;
    const fs::path pvd = dir / "run/snapshots/discs.pvd";
    const std::string index = read_file(pvd);
    ASSERT_NE(index.find("timestep=\"0\" file=\"discs_00000.vtp\""), std::string::npos) << index;
    auto damaged = [&](const std::string& from, const std::string& to, const std::string& says) {
        std::string bad = index;
        bad.replace(bad.find(from), from.size(), to);
        write_text(pvd, bad);
        EXPECT_EQ(run_exe("render " + run + " --size 64x48 --out " + (dir / "f").string(), err), 2) << to;
        EXPECT_NE(err.find("discs.pvd:"), std::string::npos) << err;
        EXPECT_NE(err.find(says), std::string::npos) << err;
        EXPECT_FALSE(fs::exists(dir / "f")) << to;
    };
    damaged("timestep=\"0\"", "timestep=\"nan\"", "finite");
    damaged("timestep=\"0\"", "timestep=\"0x\"", "'0x' is not a number");
    damaged("file=\"discs_00000.vtp\"", "file=\"../../run/snapshots/discs_00000.vtp\"", "not a snapshot file of this folder");
    write_text(pvd, index);
    EXPECT_EQ(run_exe("render " + run + " --size 64x48 --out " + (dir / "f").string(), err), 0) << err;

    // DAN's blocks, drawn by render
    const std::string dan = (dir / "dan").string();
    const std::string geometry_a = std::string(DEMLAB_SOURCE_DIR) + "/scenarios/geometry-A.toml";
    ASSERT_EQ(run_exe("run " + geometry_a + " --solver dan --no-plots --set stop.t_max=0.3 --set stop.rest_duration=0.1 "
                      "--set output.snapshot_interval=0.1 --out " + dan, err), 0) << err;
    const fs::path blocks = dir / "dan/blocks.csv";
    std::string rows = read_file(blocks);
    const size_t second = rows.find('\n') + 1;
    rows.replace(second, rows.find(',', second) - second, "0.0zz");
    write_text(blocks, rows);
    EXPECT_EQ(run_exe("render " + dan + " --size 64x48 --out " + (dir / "g").string(), err), 2);
    EXPECT_NE(err.find("blocks.csv:2: '0.0zz' is not a number"), std::string::npos) << err;

    // an envelope, read back by the calibration
    const fs::path envelope = dir / "envelope.csv";
    write_text(envelope, "x_m,surface_m\n0.1,0.02\n1e12,0.01\n");
    EXPECT_THROW(read_envelope_csv(envelope.string()), InputError);
    write_text(envelope, "x_m,surface_m\n0.1,0.02x\n");
    EXPECT_THROW(read_envelope_csv(envelope.string()), InputError);
    write_text(envelope, "x_m,surface_m\n0.1,0.02\n0.2,0.01\n");
    EXPECT_EQ(read_envelope_csv(envelope.string()).y.size(), 201u);
    EXPECT_EQ(run_exe("calibrate " + std::string(DEMLAB_SOURCE_DIR) + "/calibration/dam-break.toml --angles 15x --out " +
                          (dir / "c").string(), err), 2);
    EXPECT_NE(err.find("--angles '15x'"), std::string::npos) << err;
    fs::remove_all(dir);
}

// The input files a scenario names, damaged as a review found them accepted: a number with
// text after it, a header keyword given twice, a header asking for more cells than the file
// holds, coordinates beyond 1e9 m (elevations 1e7 m), a profile's first row taken for a header, a column named
// twice, counts that are not whole, rasters of billions of cells. Each is an input error naming
// the file (and line) before any output.
TEST(Guards, DamagedInputFilesAreRefusedNamingFileAndLine) {
    const fs::path dir = temp_dir("inputs");
    fs::create_directories(dir);
    const std::string f = (dir / "f").string();
    auto refused = [&](const std::string& text, const std::function<void()>& read, const std::vector<std::string>& says) {
        write_text(f, text);
        std::vector<std::string> all = {f};
        all.insert(all.end(), says.begin(), says.end());
        expect_refused(read, all);
    };
    // a release mass: the cell whole
    refused("id,x_m,y_m,r_m,layer,grid\n0,0.1x,0.2,0.01,0,0\n", [&] { load_release(f); }, {":2:", "'0.1x' is not a number"});
    refused("# wall 0 1.115 1.4485 0.312zz\nid,x_m,y_m,r_m,layer,grid\n0,0.1,0.2,0.01,0,0\n", [&] { load_release(f); },
            {":1:", "# wall"});
    write_text(f, "id,x_m,y_m,r_m,layer,grid\r\n0,0.1,0.2,0.01,0,0\r\n");  // Windows line ends
    EXPECT_EQ(load_release(f).pos.size(), 1u);
    // a column named twice
    EXPECT_THROW(CsvHeader("t_s,s_front_m,t_s", "front.csv").column("t_s"), InputError);
    EXPECT_EQ(CsvHeader("t_s,s_front_m", "front.csv").column("s_front_m"), 1u);
    // an ESRI grid
    const std::string grid = "ncols 2\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2\n3 4\n";
    write_text(f, grid);
    EXPECT_EQ(read_esri_grid(f).z.size(), 4u);
    refused("ncols 2\nnrows 2\nxllcorner 0\nxllcenter 5\nyllcorner 0\ncellsize 1\n1 2\n3 4\n", [&] { read_esri_grid(f); },
            {":4:", "given again (line 3"});
    refused("ncols 1000000\nnrows 50\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2\n", [&] { read_esri_grid(f); },
            {"1000000 x 50 cells", "bytes at least"});
    refused("ncols 2\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1e200\n1 2\n3 4\n", [&] { read_esri_grid(f); }, {":5:", "cellsize"});
    refused("ncols 2\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2\n3 1e308\n", [&] { read_esri_grid(f); }, {":7:", "1e7"});
    // GIS tools' float32 nodata value, a cell holding it, and a corner with a UTM zone prefix
    write_text(f, "ncols 2\nnrows 2\nxllcorner 32500000\nyllcorner 5000000\ncellsize 1\n"
                  "NODATA_value -3.4028234663852886e+38\n1 -3.4028234663852886e+38\n3 4\n");
    EXPECT_EQ(read_esri_grid(f).z.size(), 4u);
    // a profile: a first row that is not a header, an empty cell, an elevation beyond 1e7 m
    write_text(f, "x_m,y_m\n0,1\n1,0.5\n");
    EXPECT_EQ(read_profile_csv(f).size(), 2u);
    write_text(f, "0 1\n1 0.5\n");
    EXPECT_EQ(read_profile_csv(f).size(), 2u);
    write_text(f, "x_m,y_m,\n0,1,\n1,0.5,\n");  // a spreadsheet's trailing commas
    EXPECT_EQ(read_profile_csv(f).size(), 2u);
    refused("-0.5;1.4887\n0,1\n1,0.5\n", [&] { read_profile_csv(f); }, {":1:"});
    refused("O.00,1.4\n1,0.5\n2,0.4\n", [&] { read_profile_csv(f); }, {":1:"});
    refused("x,y\n0,1\n1.55,,0.3250\n2,0.4\n", [&] { read_profile_csv(f); }, {":3:"});
    refused("x,y\n0,1\n1.5x,0.5\n", [&] { read_profile_csv(f); }, {":3:"});
    refused("x,y\n0,1\n1,1e308\n", [&] { read_profile_csv(f); }, {":3:", "1e7"});
    // a point terrain
    refused("0 0 0\n1 0 1e308\n0 1 0\n", [&] { read_xyz_points(f); }, {":2:", "1e7"});
    // a calibration: whole counts
    const std::string scenario = std::string(DEMLAB_SOURCE_DIR) + "/scenarios/dam-break.toml";
    refused("[calibration]\nscenario = \"" + scenario + "\"\nseeds = 1.5\n", [&] { load_calibration(f); }, {"calibration.seeds", "whole"});
    refused("[calibration]\nscenario = \"" + scenario + "\"\nsections = [3.9, 4]\n", [&] { load_calibration(f); }, {"whole"});
    // a calibration whose scenario does not exist: refused before its folder is made
    write_text(f, "[calibration]\nscenario = \"no-such.toml\"\nangles = [15]\n");
    std::string err;
    EXPECT_EQ(run_exe("calibrate " + f + " --no-refine --jobs 1 --out " + (dir / "c").string(), err), 2);
    EXPECT_NE(err.find("no-such.toml"), std::string::npos) << err;
    EXPECT_FALSE(fs::exists(dir / "c"));
    // and one whose scenario is not a dam break
    write_text(f, "[calibration]\nscenario = \"" + std::string(DEMLAB_SOURCE_DIR) + "/scenarios/geometry-A.toml\"\nangles = [15]\n");
    EXPECT_EQ(run_exe("calibrate " + f + " --no-refine --jobs 1 --out " + (dir / "c").string(), err), 2);
    EXPECT_NE(err.find("not a [dam_break] scenario"), std::string::npos) << err;
    EXPECT_FALSE(fs::exists(dir / "c"));
    // a 3-D run whose peak rasters would have billions of cells
    const std::string snow3 = std::string(DEMLAB_SOURCE_DIR) + "/scenarios/snow-slide-3d.toml";
    EXPECT_EQ(run_exe("run " + snow3 + " --no-plots --set dem3.raster_cell=0.0001 --out " + (dir / "r").string(), err), 2);
    EXPECT_NE(err.find("dem3.raster_cell"), std::string::npos) << err;
    EXPECT_FALSE(fs::exists(dir / "r"));
    // a grid named .Asc is a grid (it was read as x y z points: "2 values")
    fs::copy_file(std::string(DEMLAB_SOURCE_DIR) + "/data/snow-slope-3d/bed.asc", dir / "bed.Asc");
    EXPECT_EQ(run_exe("run " + snow3 + " --no-plots --set 'dem3.terrain=\"" + (dir / "bed.Asc").string() +
                          "\"' --set stop.t_max=0.02 --set stop.rest_duration=0.01 --out " + (dir / "asc").string(), err), 0) << err;
    // DAN's reference front: the cell whole
    write_text(f, "t_s,s_front_m\n0,0.5\n0.2,0.8\n0.4,1.2x\n");
    const std::string geometry_a = std::string(DEMLAB_SOURCE_DIR) + "/scenarios/geometry-A.toml";
    EXPECT_EQ(run_exe("run " + geometry_a + " --solver dan --no-plots --set 'dan.sync_front=\"" + f + "\"' --out " +
                          (dir / "d").string(), err), 2);
    EXPECT_NE(err.find(f + ":4: '1.2x' is not a number"), std::string::npos) << err;
    EXPECT_FALSE(fs::exists(dir / "d"));
    fs::remove_all(dir);
}

TEST(Guards, OptionsOnceAcceptedByMistakeAreRefused) {
    const fs::path dir = temp_dir("options");
    fs::create_directories(dir);
    const std::string run = (dir / "run").string();
    std::string err;
    ASSERT_EQ(run_drop(dir, run, err), 0) << err;
    EXPECT_EQ(run_exe("render " + run + " --size 640x480junk --out " + (dir / "f1").string(), err), 2);
    EXPECT_NE(err.find("--size '640x480junk'"), std::string::npos) << err;
    EXPECT_EQ(run_exe("render " + run + " --size 64x48x3 --out " + (dir / "f1").string(), err), 2);
    EXPECT_EQ(run_exe("render " + run + " --strip ''", err), 1);
    EXPECT_NE(err.find("empty file name"), std::string::npos) << err;
    EXPECT_EQ(run_exe("render " + run + " --size 64x48 --strip " + (dir / "nodir/x.png").string(), err), 2);
    EXPECT_NE(err.find("does not exist"), std::string::npos) << err;
    EXPECT_FALSE(fs::exists(dir / "f1"));
    EXPECT_FALSE(fs::exists(dir / "run/frames"));
    const std::string geometry_a = std::string(DEMLAB_SOURCE_DIR) + "/scenarios/geometry-A.toml";
    EXPECT_EQ(run_exe("run " + geometry_a + " --solver dan --scale 20 --out " + (dir / "d").string(), err), 2);
    EXPECT_NE(err.find("--scale"), std::string::npos) << err;
    EXPECT_EQ(run_exe("run " + geometry_a + " --solver dan --variant I --out " + (dir / "d").string(), err), 2);
    EXPECT_NE(err.find("--variant"), std::string::npos) << err;
    EXPECT_FALSE(fs::exists(dir / "d"));
    EXPECT_EQ(run_exe("resume " + run + " --checkpoint-every nan", err), 2);
    EXPECT_NE(err.find("nan"), std::string::npos) << err;
    fs::remove_all(dir);
}
