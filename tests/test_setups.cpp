// Set-ups as parts (setups/setup.h): the bed path against closed forms, the terrain profile
// from a CSV polyline end to end, and its refusals.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <tuple>

#include "core/error.h"
#include "files.h"
#include "core/csv.h"
#include "geometry/bed_path.h"
#include "geometry/esri_grid.h"
#include "geometry/packing.h"
#include "geometry/profile.h"
#include "helpers.h"
#include "run/run.h"
#include "scenario/scenario.h"
#include "setups/db9k.h"
#include "setups/flume.h"
#include "setups/release.h"
#include "setups/setup.h"
#include "dem/world.h"

using namespace demlab;
using demlab::test::expect_refused;
using demlab::test::csv_column;
using demlab::test::read_file;
using demlab::test::temp_dir;
namespace fs = std::filesystem;

namespace {
WallGeom seg(Vec2 a, Vec2 b) { return make_geom(test::segment(a, b, SegmentSolid::Right)); }

// removed when the test's variable goes out of scope
test::TempFile write_temp(const std::string& name, const std::string& text) { return test::TempFile(name, text); }
}  // namespace

// A chain of a 3-4-5 segment and a horizontal one: s adds up along the parts, h is the
// distance above the bed; the first part reaches back and the last forward without end.
TEST(BedPath, ProjectsOntoAChainOfSegments) {
    const BedPath path({seg({0, 4}, {3, 0}), seg({3, 0}, {7, 0})});
    EXPECT_DOUBLE_EQ(path.part_start(1), 5.0);
    EXPECT_DOUBLE_EQ(path.length(), 9.0);
    double s, h;
    path.project({5, 1}, s, h);  // above the flat, 2 m along it
    EXPECT_DOUBLE_EQ(s, 7.0);
    EXPECT_DOUBLE_EQ(h, 1.0);
    path.project({10, 0.5}, s, h);  // beyond the end
    EXPECT_DOUBLE_EQ(s, 12.0);
    EXPECT_DOUBLE_EQ(h, 0.5);
    // on the slope's normal through its middle (1.5, 2), 1 m out: (1.5, 2) + (0.8, 0.6)
    path.project({2.3, 2.6}, s, h);
    EXPECT_NEAR(s, 2.5, 1e-12);
    EXPECT_NEAR(h, 1.0, 1e-12);
    Vec2 p, n;
    path.at(7.0, p, n);
    EXPECT_NEAR((p - Vec2(5, 0)).norm(), 0.0, 1e-12);
    EXPECT_NEAR((n - Vec2(0, 1)).norm(), 0.0, 1e-12);
}

// An arc's s is its radius times the angle from its start; h is measured inwards.
TEST(BedPath, ArcPartsCountTheirAngle) {
    WallDef a = test::arc({0, 1}, 1.0, 180.0, 270.0);  // from (-1, 1) down to (0, 0)
    const BedPath path({seg({-1, 3}, {-1, 1}), make_geom(a), seg({0, 0}, {2, 0})});
    EXPECT_NEAR(path.part_start(2), 2.0 + 0.5 * kPi, 1e-12);
    double s, h;
    const Vec2 q = Vec2(0, 1) + 0.5 * Vec2(std::cos(1.25 * kPi), std::sin(1.25 * kPi));  // halfway, 0.5 m in
    path.project(q, s, h);
    EXPECT_NEAR(s, 2.0 + 0.25 * kPi, 1e-12);
    EXPECT_NEAR(h, 0.5, 1e-12);
}

TEST(TerrainProfile, CsvIsReadWithHeaderAndComments) {
    const auto p = read_profile_csv(write_temp("profile-ok.csv", "# ground\nx,y\n0,1\n1.5,0.5\n\n2,0.5\n").path());
    ASSERT_EQ(p.size(), 3u);
    EXPECT_DOUBLE_EQ(p[1].x(), 1.5);
    EXPECT_DOUBLE_EQ(p[2].y(), 0.5);
}

TEST(TerrainProfile, BadCsvIsRefusedWithFileAndLine) {
    const test::TempFile back = write_temp("profile-back.csv", "x,y\n0,1\n1,0.5\n0.5,0.4\n");
    expect_refused([&] { read_profile_csv(back.path()); }, {":4:", "must exceed the previous row's x"});
    const test::TempFile text = write_temp("profile-text.csv", "x,y\n0,1\n1,abc\n");
    expect_refused([&] { read_profile_csv(text.path()); }, {":3:", "two numbers"});
    const test::TempFile one = write_temp("profile-one.csv", "0,1\n");
    expect_refused([&] { read_profile_csv(one.path()); }, {"at least 2 points"});
    expect_refused([] { read_profile_csv("/nonexistent/profile.csv"); }, {"cannot open", "no such file"});
}

TEST(TerrainProfile, ScenarioRefusesWhatCannotRun) {
    const test::TempFile prof = write_temp("profile-s.csv", "0,1\n1,0\n2,0\n");
    auto load = [&](const std::string& extra) {
        Scenario s = parse_scenario("[terrain]\nprofile = \"" + prof.path() + "\"\n" + extra, "t.toml");
        finish_scenario(s);
        return s;
    };
    expect_refused([&] { load("release = [[0.1, 1.0], [0.3, 1.0]]\n"); }, {"terrain.release", "at least 3"});
    expect_refused([&] { load("release = [[0, 1], [0.4, 1], [0.2, 1.1], [0.4, 1.3], [0, 1.3]]\n"); }, {"non-convex"});
    expect_refused([&] { load(""); }, {"no discs"});
    expect_refused([] {
        Scenario s = parse_scenario("[terrain]\nrelease = [[0, 1], [1, 1], [1, 2]]\n", "t.toml");
        finish_scenario(s);
    }, {"terrain.profile"});
    expect_refused([&] { load("[flume]\n"); }, {"not several"});
    const Scenario s = load("release = [[0.1, 1.0], [0.4, 1.0], [0.4, 1.3], [0.1, 1.3]]\n");
    EXPECT_EQ(make_setup(s)->kind(), "terrain");
    EXPECT_EQ(make_setup(s)->walls().size(), 2u);
    // the resolved scenario keeps the table, and reads back to the same set-up
    const Scenario back = parse_scenario(resolved_toml(s), "resolved.toml");
    EXPECT_EQ(make_setup(back)->kind(), "terrain");
    EXPECT_EQ(back.terrain.release.size(), 4u);
}

// A release polygon must lie above the ground (issue 48, rows 1 and 2): the shipped slope-dam
// profile (x from 0 to 2.9 m) with the polygon over no ground, partly under the slope, or with
// a ridge of the ground through it, is refused naming terrain.release and the corner or the
// ground's point; demlab run exits 2 and makes no folder. The shipped polygon still loads.
TEST(TerrainProfile, ReleaseMustLieAboveTheGround) {
    const std::string scenario = std::string(DEMLAB_SOURCE_DIR) + "/scenarios/terrain-slope-dam.toml";
    auto load = [&](const std::string& release) {
        Scenario s = load_scenario(scenario);
        apply_override(s, "terrain.release=" + release);
        finish_scenario(s);
        return s;
    };
    expect_refused([&] { load("[[10, 10], [11, 10], [11, 11], [10, 11]]"); },
                   {"terrain.release", "corner 0 [10, 10]", "beyond the terrain's profile", "x from 0 to 2.9 m"});
    expect_refused([&] { load("[[-1, 1.5], [0.2, 1.5], [0.2, 2], [-1, 2]]"); }, {"terrain.release", "corner 0 [-1, 1.5]", "beyond"});
    // the ground at x = 0.5 is at 0.911 m and at x = 1 at 0.623 m: the lower corners are in it
    expect_refused([&] { load("[[0.5, 0.5], [1, 0.5], [1, 1.2], [0.5, 1.2]]"); },
                   {"terrain.release", "corner 0 [0.5, 0.5]", "under the ground"});
    expect_refused([&] { load("[[0.5, 0], [1, 0], [1, 0.3], [0.5, 0.3]]"); }, {"terrain.release", "corner 0", "under the ground"});
    expect_refused([&] { load("[[0.5, 1.2], [0.5, 0.5], [1, 0.5], [1, 1.2]]"); }, {"terrain.release", "corner 1 [0.5, 0.5]", "under the ground"});
    EXPECT_EQ(load("[[0.06, 1.17], [0.45, 0.95], [0.45, 1.20], [0.06, 1.20]]").terrain.release.size(), 4u);
    // a corner on the ground is on or above it
    EXPECT_NO_THROW(load("[[0.5, 0.9113214286], [1, 0.6226428571], [1, 1.2], [0.5, 1.2]]"));

    // a ridge of the ground through the polygon, its corners above the ground: the ridge's top
    // inside the polygon, or above it (its flanks cross the edges)
    for (const auto& [profile, fragment] :
         {std::pair<const char*, const char*>{"x,y\n0,1\n1,0\n1.2,1\n1.4,0\n3,0\n", "[1.2, 1] (point 3 of the profile) lies inside"},
          {"x,y\n0,1\n1,0\n1.2,2\n1.4,0\n3,0\n", "crosses the polygon's edge"}}) {
        const test::TempFile ridge = write_temp("ridge.csv", profile);
        expect_refused([&] {
            Scenario s = parse_scenario("[terrain]\nprofile = \"" + ridge.path() + "\"\nrelease = [[0.9, 0.5], [1.6, 0.5], [1.6, 1.5], [0.9, 1.5]]\n", "t.toml");
            finish_scenario(s);
        }, {"terrain.release", fragment});
    }

    // the command: exit 2, no output folder (a coarse, short run should it be accepted)
    const fs::path out = temp_dir("release-nowhere");
    const int status = std::system((std::string(DEMLAB_EXE) + " run " + scenario + " --out " + out.string() +
                                    " --scale 20 --set stop.t_max=0.01 --set stop.rest_duration=0.005 --set output.snapshot_interval=0"
                                    " --set 'terrain.release=[[10, 10], [11, 10], [11, 11], [10, 11]]' >/dev/null 2>&1").c_str());
    ASSERT_TRUE(WIFEXITED(status));
    EXPECT_EQ(WEXITSTATUS(status), 2);
    EXPECT_FALSE(fs::exists(out));
    fs::remove_all(out);
}

// A terrain release polygon's lid, which the mass settles last without, is its top: the edge
// facing most upwards, not the edge whose middle is highest (in a polygon whose top slopes
// that is a vertical side, and the mass poured out over it before t = 0).
TEST(TerrainRelease, TheLidIsTheTopEdge) {
    const test::TempFile prof = write_temp("profile-lid.csv", "x,y\n0,0.5\n2,0.4\n");
    for (const bool clockwise : {false, true}) {
        std::vector<Vec2> poly{{0.06, 1.17}, {0.45, 0.95}, {0.45, 1.0}, {0.06, 1.6}};
        if (clockwise) std::reverse(poly.begin(), poly.end());
        Scenario s = parse_scenario("[terrain]\nprofile = \"" + prof.path() + "\"\n", "t.toml");
        s.terrain.release = poly;
        finish_scenario(s);
        const ReleaseBox box = make_setup(s)->release_box();
        ASSERT_GE(box.lid, 0);
        const WallDef& lid = box.walls[size_t(box.lid)];
        const double top_y = std::max(lid.p0.y(), lid.p1.y()), low_y = std::min(lid.p0.y(), lid.p1.y());
        EXPECT_DOUBLE_EQ(top_y, 1.6) << (clockwise ? "clockwise" : "counter-clockwise");
        EXPECT_DOUBLE_EQ(low_y, 1.0) << (clockwise ? "clockwise" : "counter-clockwise");
    }
}

// Settling a release stops at release.settle_max_time, whatever the step (the fuzzer's find):
// soft contacts (kn = 1.2e5 N/m, discs of 6-7 cm) give steps of about 6e-3 s, and chunks of
// 200 of them settled for 2.2 s where 0.0075 s was asked; the mass poured out of its triangle,
// whose top was open, and one disc started the run under the ground. Now the settling takes
// at most the time asked (one step over at each of its stages) and the mass stays in its
// polygon.
TEST(TerrainRelease, SettlingStopsAtItsMaximumTime) {
    const test::TempFile prof = write_temp("profile-soft.csv",
                                           "x_m,y_m\n-0.8687,1.2436\n-0.1162,0.3881\n0.1640,-0.2751\n0.3460,0.2018\n"
                                           "0.4714,0.8245\n1.3956,0.5735\n1.5832,-0.2328\n");
    Scenario s = parse_scenario("[terrain]\nprofile = \"" + prof.path() +
                                    "\"\nrelease = [[0.6242, 1.5154], [1.4448, 1.5154], [0.6242, 2.2667]]\n"
                                    "[material]\nkn = 123736.6\nks = 3699.0\n[rotation]\nmodel = 3\nu_rr = 0\n"
                                    "[release]\nr_max = 0.07079\nr_min = 0.05875\nsettle_max_time = 0.0074862\n"
                                    "accept_unsettled = true\n",
                                "soft.toml");
    finish_scenario(s);
    const ReleaseMass m = generate_release(s);
    ASSERT_GT(m.pos.size(), 10u);
    // one step over at each stage: about 7.4e-3 s at the real stiffness without local damping,
    // 1 / sqrt(1 + alpha) of it with local damping alpha, 1 / sqrt(f) of that while soft
    const ReleaseDef& rd = s.release;
    const double step = 7.5e-3, f = rd.settle_stiffness_factor;
    const double dt_bound = step / std::sqrt(1.0 + rd.settle_alpha) * (1.0 / std::sqrt(f) + 1.0) +
                            step / std::sqrt(1.0 + rd.settle_friction_alpha);
    EXPECT_LE(m.settle_time, s.release.settle_max_time + dt_bound);
    for (size_t i = 0; i < m.pos.size(); ++i) {
        EXPECT_GT(m.pos[i].y(), 1.5154 - m.radius[i]) << "disc " << i;
        EXPECT_GT(m.pos[i].x(), 0.6242 - m.radius[i]) << "disc " << i;
    }
    const World w = world_of_scenario(s);
    for (size_t i = 0; i < w.disc_count(); ++i) EXPECT_GT(w.positions()[i].y(), 1.0) << "disc " << i;
}

// A file saved with a UTF-8 byte-order mark (spreadsheet programs' "CSV UTF-8") reads as the
// same file without it (issue 48, row 3): a profile (its mark before a number, which was taken
// for a header and lost a point, or before a comment, which was refused), an elevation grid, a
// release mass, a disc file, a CSV table and a header read on its own.
TEST(Files, AByteOrderMarkIsReadAsTheSameFileWithoutIt) {
    const std::string bom = "\xEF\xBB\xBF";
    auto both = [&](const std::string& name, const std::string& text, const auto& read) {
        const test::TempFile plain(name, text), marked("bom-" + name, bom + text);
        EXPECT_EQ(read(marked.path()), read(plain.path())) << name;
    };
    both("profile.csv", "0,1\n1.5,0.5\n2,0.5\n", [](const std::string& p) { return read_profile_csv(p); });
    both("profile-h.csv", "# ground\nx,y\n0,1\n1.5,0.5\n", [](const std::string& p) { return read_profile_csv(p); });
    both("grid.asc", "ncols 2\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2\n3 4\n",
         [](const std::string& p) { return read_esri_grid(p).z; });
    both("release.csv", "# demlab release mass\n# settle_ratio 0.0004\nid,x_m,y_m,r_m,layer,grid\n0,0.1,0.2,0.01,0,0\n1,0.3,0.2,0.01,0,1\n",
         [](const std::string& p) {
             const ReleaseMass m = load_release(p);
             return std::make_tuple(m.pos, m.radius, m.grid, m.settle_ratio);
         });
    both("discs.xyr", "# id x y r\n0 0.1 0.2 0.01\n", [](const std::string& p) { return read_xyr(p).size(); });
    both("table.csv", "t_s,x_m\n0,1\n0.5,2\n", [](const std::string& p) {
        const CsvTable t = read_csv_table(p);
        return std::make_pair(t.names, t.rows);
    });
    EXPECT_EQ(CsvHeader(bom + "t_s,x_m", "h.csv").column("t_s"), 0u);
    // a scenario file, for completeness
    both("s.toml", "[scenario]\nname = \"marked\"\n", [](const std::string& p) { return load_scenario(p).name; });
}

// A barrier on the profile (terrain.barrier): walls after the profile's, the bed path up its
// face; refused off the ground, going down from its foot, or of one point.
TEST(TerrainProfile, BarrierStandsOnTheProfile) {
    const test::TempFile prof = write_temp("profile-b.csv", "0,1\n1,0\n3,0\n");
    auto load = [&](const std::string& barrier) {
        Scenario s = parse_scenario("[terrain]\nprofile = \"" + prof.path() + "\"\nbarrier = " + barrier +
                                        "\n[[discs]]\nposition = [0.2, 0.9]\nradius = 0.05\n",
                                    "t.toml");
        finish_scenario(s);
        return s;
    };
    expect_refused([&] { load("[[2, 0]]"); }, {"terrain.barrier", "at least 2"});
    expect_refused([&] { load("[[2, 0.1], [2, 0.5]]"); }, {"terrain.barrier", "not on the profile"});
    expect_refused([&] { load("[[2, 0], [2.5, 0]]"); }, {"terrain.barrier", "must rise"});
    expect_refused([&] { load("[[2, 0], [2, 0]]"); }, {"terrain.barrier", "coincide"});
    expect_refused([&] { load("[[2, 0], [1, 1]]"); }, {"terrain.barrier", "back upstream"});
    expect_refused([&] { load("[[2, 0], [2, 1], [1.9, 1.2]]"); }, {"terrain.barrier", "from point 1 to 2"});
    const Scenario s = load("[[2, 0], [2, 0.3], [2.1, 0.3], [2.1, 0]]");
    const auto setup = make_setup(s);
    ASSERT_EQ(setup->walls().size(), 5u);
    EXPECT_EQ(setup->force_walls().barrier, (std::vector<int>{2, 3, 4}));
    EXPECT_EQ(setup->force_walls().slope, (std::vector<int>{0, 1}));
    WorldDef d;
    World w(d);
    for (const MaterialDef& m : scenario_materials(s)) w.add_material(m);
    for (const WallDef& wd : setup->walls()) w.add_wall(wd);
    w.add_disc({{0.2, 0.9}, 0.05, Vec2::Zero(), 0.0, 0.0, 0});
    w.finalize();
    const auto path = setup->bed_path(w);
    // the slope (sqrt 2), the flat to the foot (1 m), then the barrier's 0.3 + 0.1 + 0.3 m
    EXPECT_NEAR(path->length(), std::sqrt(2.0) + 1.0 + 0.7, 1e-12);
    const BarrierMarks marks = setup->barrier(*path);
    EXPECT_NEAR(marks.s_barrier, std::sqrt(2.0) + 1.0, 1e-12);
    double sp, hp;
    path->project(Vec2(1.95, 0.2), sp, hp);  // against the face, 0.2 m up
    EXPECT_NEAR(sp, marks.s_barrier + 0.2, 1e-12);
    EXPECT_NEAR(hp, 0.05, 1e-12);
    // the resolved scenario keeps the barrier
    EXPECT_EQ(parse_scenario(resolved_toml(s), "resolved.toml").terrain.barrier.size(), 4u);
}

// The shipped snow slab running into its dam (scenarios/snow-slide-dam.toml), to 6.5 s: the
// front reaches the dam (20 m past the toe) after about 5.5 s, the dam's load is in
// forces.csv's barrier columns and its peak in the summary.
TEST(TerrainProfile, SnowSlabLoadsTheDam) {
    Scenario s = load_scenario(std::string(DEMLAB_SOURCE_DIR) + "/scenarios/snow-slide-dam.toml");
    apply_override(s, "stop.t_max=6.5");
    apply_override(s, "output.snapshot_interval=0");
    finish_scenario(s);
    const fs::path dir = temp_dir("snow-dam");
    const RunSummary r = run_scenario(s, {dir.string(), false, {}});
    EXPECT_GT(r.t_front_at_barrier, 5.0);  // 5.55 s when measured
    EXPECT_LT(r.t_front_at_barrier, 6.0);
    EXPECT_GT(r.t_peak_fx_barrier, r.t_front_at_barrier);
    // the slab's momentum, about 22,500 kg/m at 10-13 m/s, is stopped over a fraction of a
    // second: a peak of the order of 1e5 N/m (225 kN/m when measured)
    EXPECT_GT(r.peak_fx_barrier, 5e4);
    EXPECT_LT(r.peak_fx_barrier, 2e6);
    EXPECT_GT(r.max_runup_height_during_run, 1.0);
    // forces.csv's fx_barrier: zero before the front arrives, the peak among its samples
    const std::vector<double> t = csv_column(dir / "forces.csv", "t_s"), fx = csv_column(dir / "forces.csv", "fx_barrier_N_per_m");
    double peak = 0.0, before = 0.0;
    for (size_t k = 0; k < t.size(); ++k) {
        peak = std::max(peak, std::abs(fx[k]));
        if (t[k] < r.t_front_at_barrier - 0.1) before = std::max(before, std::abs(fx[k]));
    }
    EXPECT_EQ(before, 0.0);
    EXPECT_NEAR(peak, r.peak_fx_barrier_sampled, 1e-9 * peak);  // (forces.csv has 10 digits)
    EXPECT_GE(r.peak_fx_barrier, r.peak_fx_barrier_sampled);     // of every step
    fs::remove_all(dir);
}

// The shipped terrain scenario at scale 20: the mass is generated in its polygon, runs down the
// profile, and front.csv, deposit.csv and summary.json measure it along the profile.
TEST(TerrainProfile, ShippedScenarioRunsDownTheProfile) {
    const fs::path root = DEMLAB_SOURCE_DIR;
    Scenario s = load_scenario((root / "scenarios/terrain-slope-dam.toml").string());
    apply_override(s, "release.scale=20");
    apply_override(s, "stop.t_max=1.0");
    apply_override(s, "output.snapshot_interval=0");
    finish_scenario(s);
    RunOptions o;
    o.out_dir = temp_dir("terrain").string();
    const RunSummary r = run_scenario(s, o);
    EXPECT_GT(r.n_discs, 20);
    EXPECT_EQ(setup_kind_of_run(o.out_dir), "terrain");
    // the front: monotone enough to have moved well down the 1.6 m slope in 1 s
    const fs::path front = fs::path(o.out_dir) / "front.csv";
    EXPECT_EQ(demlab::test::read_file_header(front), "t_s,s_front_m,displacement_m");
    const std::vector<double> sf = csv_column(front, "s_front_m");
    ASSERT_FALSE(sf.empty());
    const double s_first = sf.front(), s_last = sf.back();
    EXPECT_LT(s_first, 0.6);   // the polygon ends 0.45 m along x: s < 0.52 m
    EXPECT_GT(s_last, 1.0);    // g sin 30 - friction: well over a metre in 1 s
    EXPECT_GT(r.runout_s, s_last - 0.1);
    EXPECT_LT(r.runout_s, 3.2);  // on the profile (3.12 m long)
    EXPECT_LT(r.energy_balance_error, 0.05);
    // the summary's deposit figures are deposit.csv's: its largest height and the bins that hold mass
    const std::vector<double> bins = csv_column(fs::path(o.out_dir) / "deposit.csv", "s_m"),
                              heights = csv_column(fs::path(o.out_dir) / "deposit.csv", "height_m");
    ASSERT_GE(bins.size(), 2u);
    double highest = 0.0, first = NAN, last = NAN;
    for (size_t k = 0; k < bins.size(); ++k) {
        highest = std::max(highest, heights[k]);
        if (heights[k] > 0.0) {
            if (std::isnan(first)) first = bins[k];
            last = bins[k];
        }
    }
    EXPECT_GT(highest, 0.0);
    EXPECT_NEAR(r.deposit_max_height, highest, 1e-5 * highest);  // (deposit.csv has 6 digits)
    EXPECT_NEAR(r.deposit_length, last - first + (bins[1] - bins[0]), 1e-6);
    // the profile's load is in forces.csv's slope columns and the total: it carries the weight
    const std::string forces = read_file(fs::path(o.out_dir) / "forces.csv");
    EXPECT_NE(forces.find("fx_slope_N_per_m"), std::string::npos);
    fs::remove_all(o.out_dir);
}

// The porosity inside a mass against the closed forms of two regular packings of equal discs
// in a walled box: hexagonal 1 - pi / (2 sqrt 3) = 0.0931, square 1 - pi / 4 = 0.2146. The
// points near the walls and the free surface are left out, so the box's gaps do not count.
TEST(Packing, InteriorPorosityOfRegularPackings) {
    const double r = 0.002;
    for (bool hexagonal : {true, false}) {
        std::vector<Vec2> pos;
        std::vector<double> radius;
        const double dy = hexagonal ? std::sqrt(3.0) * r : 2.0 * r;
        for (int row = 0; row < 40; ++row)
            for (int col = 0; col < 50; ++col) {
                const double shift = hexagonal && row % 2 ? r : 0.0;
                pos.emplace_back(r + shift + 2.0 * r * col, r + dy * row);
                radius.push_back(r);
            }
        // a box a little wider than the lattice: gaps of up to one radius at its walls
        const double width = 101.0 * r, height = 40.0 * dy + 3.0 * r;
        const std::vector<std::array<Vec2, 2>> box = {std::array<Vec2, 2>{Vec2(0, 0), Vec2(width, 0)},
                                                      {Vec2(width, 0), Vec2(width, height)},
                                                      {Vec2(0, height), Vec2(0, 0)}};
        const PackingMeasure m = interior_porosity(pos, radius, box);
        const double exact = hexagonal ? 1.0 - kPi / (2.0 * std::sqrt(3.0)) : 1.0 - kPi / 4.0;
        EXPECT_GT(m.samples, 20000);
        EXPECT_NEAR(m.porosity, exact, 0.004) << (hexagonal ? "hexagonal" : "square");
        // over the whole box the gaps at the walls and the open top count too: looser
        double solid = 0;
        for (double ri : radius) solid += kPi * ri * ri;
        EXPECT_GT(1.0 - solid / (width * height), m.porosity + 0.01);
    }
    // a mass thinner than twice the clearance has no interior
    const PackingMeasure thin = interior_porosity({Vec2(0, 0), Vec2(0.004, 0)}, {0.002, 0.002}, {});
    EXPECT_EQ(thin.samples, 0);
    EXPECT_EQ(thin.porosity, -1.0);
}
