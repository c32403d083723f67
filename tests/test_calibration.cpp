// The dam-break calibration: envelope and slope angles of known deposits; the sweep end to end
// at scale 20; resuming; applying the result.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <thread>

#include "calibration/calibration.h"
#include "calibration/rank_jobs.h"
#include "calibration/sweep.h"
#include "run/run_folder.h"
#include "run/summary_file.h"
#include "geometry/deposit.h"
#include "core/error.h"
#include "core/interrupt.h"
#include "core/output_dir.h"
#include "scenario/scenario.h"
#include "files.h"

using namespace demlab;
using demlab::test::read_file;
namespace fs = std::filesystem;

namespace {
std::string test_read(const std::string& path) {
    std::ifstream in(path);
    std::stringstream b;
    b << in.rdbuf();
    return b.str();
}

std::vector<std::string> split(const std::string& line) {
    std::vector<std::string> out;
    std::istringstream in(line);
    std::string cell;
    while (std::getline(in, cell, ',')) out.push_back(cell);
    return out;
}

// discs of radius r in columns 2r apart under a surface y(x), the top disc touching it
void stack_under(double (*surface)(double), double r, double x_end, std::vector<Vec2>& pos, std::vector<double>& rad) {
    for (double x = r; x < x_end; x += 2 * r) {
        const double top = surface(x) - r;
        for (double y = top; y > r * 0.5; y -= 2 * r) {
            pos.emplace_back(x, y);
            rad.push_back(r);
        }
    }
}

// sections (from the wall): 5 at 35 deg, 4 at 30, 3 at 25, 2 at 18, 1 at 10; toe at 0.5 m
const double kAngles[5] = {10, 18, 25, 30, 35};  // gamma_1 .. gamma_5
double known_surface(double x) {
    // integrate the slopes from the toe (height 0.01 m at x = 0.5) back to the wall
    double y = 0.01, xs = 0.5;
    for (int i = 1; i <= 5; ++i) {
        const double lo = (5 - i) * 0.1;
        const double t = std::tan(kAngles[i - 1] * kPi / 180.0);
        if (x >= lo) return y + (xs - x) * t;
        y += (xs - lo) * t;
        xs = lo;
    }
    return y;
}
}  // namespace

TEST(Envelope, ExactTopOfTheOutlines) {
    const std::vector<Vec2> pos{Vec2(0.1, 0.1), Vec2(0.12, 0.05)};
    const std::vector<double> rad{0.01, 0.03};
    const Envelope e = upper_envelope(pos, rad, {}, 0.0, 0.2, 0.001);
    EXPECT_NEAR(e.y[100], 0.11, 1e-12);                                                  // top of the first disc
    EXPECT_NEAR(e.y[120], 0.08, 1e-12);                                                  // top of the second
    EXPECT_NEAR(e.y[140], 0.05 + std::sqrt(0.03 * 0.03 - 0.02 * 0.02), 1e-12);          // on its side
    EXPECT_TRUE(std::isnan(e.y[10]));                                                    // nothing there
}

TEST(Envelope, SlopeAnglesOfASyntheticDepositWithinHalfADegree) {
    for (double r : {0.0005, 0.001}) {
        std::vector<Vec2> pos;
        std::vector<double> rad;
        stack_under(known_surface, r, 0.5, pos, rad);
        const auto conn = connected_discs(pos, rad, r);
        const Envelope e = upper_envelope(pos, rad, conn, 0.0, 1.0, 0.0005);
        const SlopeAngles a = slope_angles(e);
        for (int i = 0; i < 5; ++i) EXPECT_NEAR(a.gamma[i], kAngles[i], 0.5) << "section " << i + 1 << ", r " << r;
        EXPECT_NEAR(a.toe_x, 0.5, 2 * r);
        EXPECT_NEAR(a.gamma_ges, std::atan(known_surface(0.0) / 0.5) * 180 / kPi, 0.5);
    }
}

TEST(Envelope, LoneDiscsAheadOfTheToeAreIgnored) {
    std::vector<Vec2> pos;
    std::vector<double> rad;
    stack_under(known_surface, 0.001, 0.5, pos, rad);
    pos.emplace_back(0.9, 0.001);  // a disc that rolled away
    rad.push_back(0.001);
    const auto conn = connected_discs(pos, rad, 0.001);
    EXPECT_FALSE(conn.back());
    EXPECT_NEAR(slope_angles(upper_envelope(pos, rad, conn, 0.0, 1.0, 0.0005)).toe_x, 0.5, 0.002);
}

TEST(Envelope, WallGapLeavesOutDiscsClingingToTheWall) {
    std::vector<Vec2> pos;
    std::vector<double> rad;
    stack_under(known_surface, 0.001, 0.5, pos, rad);
    for (double y = 0.2; y < 0.35; y += 0.002) {  // a thin column stuck to the back wall
        pos.emplace_back(0.001, y);
        rad.push_back(0.001);
    }
    const auto conn = connected_discs(pos, rad, 0.001);
    const Envelope e = upper_envelope(pos, rad, conn, 0.0, 1.0, 0.0005);
    EXPECT_GT(std::abs(slope_angles(e).gamma[4] - kAngles[4]), 2.0);   // the column spoils gamma_5 ...
    EXPECT_NEAR(slope_angles(e, 0.1, 0.01).gamma[4], kAngles[4], 0.5);  // ... unless the fit starts 1 cm out
    EXPECT_NEAR(slope_angles(e, 0.1, 0.01).gamma[0], kAngles[0], 0.5);  // other sections unchanged
}

TEST(CalibrationConfig, BadKeysAreRefused) {
    const fs::path p = fs::temp_directory_path() / ("demlab-cal-" + std::to_string(::getpid()) + ".toml");
    std::ofstream(p) << "[calibration]\nscenario = \"x.toml\"\nangels = [15]\n";
    EXPECT_THROW(load_calibration(p.string()), InputError);
    std::ofstream(p) << "[calibration]\nscenario = \"x.toml\"\nangles = [15, 95]\n";
    EXPECT_THROW(load_calibration(p.string()), InputError);
    std::ofstream(p) << "[calibration]\nangles = [15]\n";
    EXPECT_THROW(load_calibration(p.string()), InputError);  // no scenario
    fs::remove(p);
}

TEST(Calibration, TinySweepEndToEndAndResume) {
    CalibrationConfig c = load_calibration(std::string(DEMLAB_SOURCE_DIR) + "/calibration/dam-break.toml");
    c.scale = 20;
    c.angles = {15.0, 17.0};
    c.refine = false;
    CalibrationOptions o;
    o.out = (fs::temp_directory_path() / ("demlab-calibrate-" + std::to_string(::getpid()))).string();
    fs::remove_all(o.out);
    o.jobs = 2;
    const CalibrationResult r = calibrate(c, o);
    EXPECT_EQ(r.runs_done, 2);
    EXPECT_TRUE(r.best_angle == 15.0 || r.best_angle == 17.0);
    // the table: a header and 7 rows (gamma_ges, gamma_1..5, objective), columns angle, lab, 2 angles
    std::ifstream in(o.out + "/table.csv");
    std::string line;
    std::vector<std::string> lines;
    while (std::getline(in, line)) lines.push_back(line);
    ASSERT_EQ(lines.size(), 8u);
    EXPECT_EQ(lines[0], "angle,lab,phi17.00,phi15.00");
    EXPECT_EQ(lines[7].rfind("objective,", 0), 0u);
    for (const auto& l : lines) EXPECT_EQ(std::count(l.begin(), l.end(), ','), 3) << l;
    EXPECT_TRUE(fs::exists(o.out + "/table.md"));
    EXPECT_TRUE(fs::exists(o.out + "/runs/phi15.00-seed1/deposit.png"));
    // resuming a finished sweep runs nothing new
    const CalibrationResult again = calibrate(c, o);
    EXPECT_EQ(again.runs_done, 0);
    EXPECT_EQ(again.runs_reused, 2);
    EXPECT_EQ(again.best_angle, r.best_angle);
    fs::remove_all(o.out);
}

TEST(Calibration, ApplyWritesACopyAndNeverOverwrites) {
    const fs::path dir = fs::temp_directory_path() / ("demlab-apply-" + std::to_string(::getpid()));
    fs::create_directories(dir);
    fs::copy_file(std::string(DEMLAB_SOURCE_DIR) + "/scenarios/geometry-A.toml", dir / "geometry-A.toml");
    const std::string out = apply_calibration((dir / "geometry-A.toml").string(), 15.7, false);
    EXPECT_EQ(fs::path(out).filename(), "geometry-A-calibrated.toml");
    Scenario s = load_scenario(out);
    EXPECT_DOUBLE_EQ(s.disc_friction_deg, 15.7);
    EXPECT_DOUBLE_EQ(load_scenario((dir / "geometry-A.toml").string()).disc_friction_deg, 15.5);  // original intact
    EXPECT_THROW(apply_calibration((dir / "geometry-A.toml").string(), 16.0, false), InputError);
    // what --apply would refuse is found before the calibration runs: the copy exists, the
    // scenario is missing
    EXPECT_THROW(check_apply_calibration((dir / "geometry-A.toml").string(), false), InputError);
    EXPECT_NO_THROW(check_apply_calibration((dir / "geometry-A.toml").string(), true));
    EXPECT_THROW(check_apply_calibration((dir / "missing.toml").string(), false), InputError);
    // the key indented under [material] is replaced where it stands, not added twice
    std::string text = test_read((dir / "geometry-A.toml").string());
    const size_t at = text.find("\nfriction_disc_deg");
    ASSERT_NE(at, std::string::npos);
    text.insert(at + 1, "    ");
    std::ofstream(dir / "indented.toml") << text;
    EXPECT_NO_THROW(check_apply_calibration((dir / "indented.toml").string(), false));
    EXPECT_DOUBLE_EQ(load_scenario(apply_calibration((dir / "indented.toml").string(), 15.9, false)).disc_friction_deg, 15.9);
    fs::remove_all(dir);
}

// A calibration states its answer's confidence (issue 55, row 6): with one seed it is not
// established; with several, an angle whose mean objective lies within twice the standard
// error of the difference from the best's is named as not told apart; --apply writes where
// the value came from.
TEST(Calibration, ConfidenceWeighsTheBestAgainstTheSpreadOverSeeds) {
    auto angle = [](double a, double mean, double se) {
        AngleResult r;
        r.angle = a;
        r.objective_mean = mean;
        r.objective_se = se;
        return r;
    };
    CalibrationResult res;
    res.grid = {angle(14.0, 9.0, 0.5), angle(15.0, 6.0, 0.5), angle(16.0, 6.8, 0.5)};
    res.best_angle = 15.0;
    res.best_objective = 6.0;
    res.best_se = 0.5;
    // 16 deg is 0.8 above, under 2 sqrt(0.5^2 + 0.5^2) = 1.41; 14 deg is 3.0 above
    CalibrationConfidence c = calibration_confidence(res, 3);
    EXPECT_FALSE(c.established);
    EXPECT_EQ(c.not_separated, std::vector<double>{16.0});
    EXPECT_NE(c.text.find("16 deg"), std::string::npos) << c.text;
    // a refined angle counts too
    res.refined = {angle(15.5, 6.5, 0.5)};
    EXPECT_EQ(calibration_confidence(res, 3).not_separated, (std::vector<double>{15.5, 16.0}));
    // a smaller spread tells them apart
    res.refined.clear();
    for (AngleResult& a : res.grid) a.objective_se = 0.1;
    res.best_se = 0.1;
    c = calibration_confidence(res, 3);
    EXPECT_TRUE(c.established) << c.text;
    EXPECT_TRUE(c.not_separated.empty());
    // one seed: never established, whatever the differences
    c = calibration_confidence(res, 1);
    EXPECT_FALSE(c.established);
    EXPECT_NE(c.text.find("one seed"), std::string::npos);

    const fs::path dir = fs::temp_directory_path() / ("demlab-apply-provenance-" + std::to_string(::getpid()));
    fs::create_directories(dir);
    fs::copy_file(std::string(DEMLAB_SOURCE_DIR) + "/scenarios/geometry-A.toml", dir / "geometry-A.toml");
    const std::string out = apply_calibration((dir / "geometry-A.toml").string(), 15.0, false,
                                              {"calibration: dam-break.toml, scale 4, 3 seed(s)", "confidence: " + c.text});
    std::ifstream in(out);
    std::stringstream text;
    text << in.rdbuf();
    EXPECT_NE(text.str().find("# calibration: dam-break.toml, scale 4, 3 seed(s)\n"), std::string::npos);
    EXPECT_NE(text.str().find("# confidence: not established"), std::string::npos);
    EXPECT_DOUBLE_EQ(load_scenario(out).disc_friction_deg, 15.0);
    fs::remove_all(dir);
}

// demlab sweep: a grid of two keys over two values each, one seed; sweep.csv holds a row per
// run with the varied values and the run's own summary numbers; a rerun computes nothing.
TEST(Sweep, GridRowsSummariesAndResume) {
    const fs::path dir = fs::temp_directory_path() / ("demlab-sweep-" + std::to_string(::getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
    const fs::path file = dir / "s.toml";
    std::ofstream(file) << "[sweep]\nscenario = \"" << DEMLAB_SOURCE_DIR << "/scenarios/geometry-A.toml\"\n"
                        << "set = [\"release.scale=20\", \"stop.t_max=0.4\", \"output.snapshot_interval=0\"]\n"
                        << "columns = [\"runout_s\", \"t_end\", \"n_discs\"]\n"
                        << "[grid]\n\"material.friction_disc_deg\" = [14, 17.5]\n\"release.variant\" = [\"I\", \"II\"]\n";
    const SweepConfig c = load_sweep(file.string());
    ASSERT_EQ(c.rows.size(), 4u);
    EXPECT_EQ(c.keys, (std::vector<std::string>{"material.friction_disc_deg", "release.variant"}));
    EXPECT_EQ(c.rows[1], (std::vector<std::string>{"14", "\"II\""}));  // the first key slowest
    SweepOptions o;
    o.out = (dir / "out").string();
    o.jobs = 2;
    const SweepResult r = run_sweep(c, o);
    EXPECT_EQ(r.runs_done, 4);
    std::ifstream in(o.out + "/sweep.csv");
    std::string line;
    std::vector<std::string> lines;
    while (std::getline(in, line)) lines.push_back(line);
    ASSERT_EQ(lines.size(), 5u);
    EXPECT_EQ(lines[0], "row,seed,run,reused,material.friction_disc_deg,release.variant,runout_s_m,t_end_s,n_discs");
    // each row's numbers are its run's summary; its run folder is named in the row
    const std::vector<std::string> row3 = split(lines[3]);
    ASSERT_EQ(row3.size(), 9u) << lines[3];
    const SummaryFile s3 = read_summary_file(o.out + "/runs/" + row3[2] + "/summary.json");
    std::ostringstream want;
    want.precision(10);
    want << "3,1," << row3[2] << ",0,17.5,\"I\"," << s3.number("runout_s") << ',' << s3.number("t_end") << ',' << s3.number("n_discs");
    EXPECT_EQ(lines[3], want.str());
    EXPECT_EQ(lines[4].rfind("4,1,", 0), 0u) << lines[4];
    EXPECT_NE(lines[4].find(",0,17.5,\"II\","), std::string::npos) << lines[4];
    EXPECT_TRUE(fs::exists(o.out + "/timings.csv"));
    const SweepResult again = run_sweep(c, o);
    EXPECT_EQ(again.runs_done, 0);
    EXPECT_EQ(again.runs_reused, 4);
    std::ifstream in2(o.out + "/sweep.csv");
    std::getline(in2, line);
    while (std::getline(in2, line)) EXPECT_EQ(split(line)[3], "1") << "a reused run says so: " << line;
    fs::remove_all(dir);
}

TEST(Sweep, BadFilesAreRefusedBeforeAnyRun) {
    const fs::path dir = fs::temp_directory_path() / ("demlab-sweep-bad-" + std::to_string(::getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
    const fs::path file = dir / "s.toml";
    const std::string scenario = std::string("[sweep]\nscenario = \"") + DEMLAB_SOURCE_DIR + "/scenarios/geometry-A.toml\"\n";
    auto message = [&](const std::string& text) {
        std::ofstream(file) << text;
        try {
            load_sweep(file.string());
        } catch (const InputError& e) {
            return std::string(e.what());
        }
        return std::string("accepted");
    };
    EXPECT_NE(message(scenario + "[grid]\n\"material.frction_disc_deg\" = [14]\n").find("did you mean 'material.friction_disc_deg'"), std::string::npos);
    EXPECT_NE(message(scenario + "[grid]\n\"material.friction_disc_deg\" = [14, 95]\n").find("row 2"), std::string::npos);
    EXPECT_NE(message(scenario + "[grid]\n\"release.scale\" = 20\n").find("non-empty array"), std::string::npos);
    EXPECT_NE(message("[sweep]\nseeds = 2\n").find("scenario is required"), std::string::npos);
    EXPECT_NE(message(scenario + "seeds = 0\n").find("seeds (1 to 100)"), std::string::npos);
    EXPECT_NE(message(scenario + "[grid]\n\"scenario.seed\" = [1, 2]\n").find("[sweep] seeds"), std::string::npos);
    EXPECT_NE(message(scenario + "[grid]\n\"rotation.model\" = [1]\n[[rows]]\n\"rotation.model\" = 1\n").find("not both"), std::string::npos);
    EXPECT_NE(message(scenario + "[[rows]]\n\"rotation.model\" = 1\n[[rows]]\n\"release.scale\" = 20\n").find("same keys"), std::string::npos);
    EXPECT_FALSE(fs::exists(dir / "runs"));
    fs::remove_all(dir);
}

namespace {
// A sweep over the density of two discs on a terrain profile read from a file (a fraction of
// a second each).
struct DensitySweep {
    fs::path dir;
    std::string ground = "x,y\n0,0.5\n1,0\n3,0\n";
    explicit DensitySweep(const std::string& name) : dir(fs::temp_directory_path() / (name + "-" + std::to_string(::getpid()))) {
        fs::remove_all(dir);
        fs::create_directories(dir);
        std::ofstream(dir / "ground.csv") << ground;
        std::ofstream(dir / "two.toml") << "[terrain]\nprofile = \"ground.csv\"\n[stop]\nt_max = 0.05\nrest_duration = 0.01\n"
                                           "[output]\nsnapshot_interval = 0\n[[discs]]\nposition = [1.5, 0.05]\nradius = 0.05\n"
                                           "[[discs]]\nposition = [2.0, 0.05]\nradius = 0.05\n";
    }
    ~DensitySweep() { fs::remove_all(dir); }
    SweepConfig config(const std::string& densities, const std::string& columns = "[\"total_mass\"]") const {
        std::ofstream(dir / "s.toml") << "[sweep]\nscenario = \"two.toml\"\ncolumns = " << columns
                                      << "\n[grid]\n\"material.density\" = " << densities << "\n";
        return load_sweep((dir / "s.toml").string());
    }
    // sweep.csv's rows: run folder, reused, density, total mass
    std::vector<std::vector<std::string>> table() const {
        std::ifstream in(dir / "out" / "sweep.csv");
        std::string line;
        std::getline(in, line);
        std::vector<std::vector<std::string>> rows;
        while (std::getline(in, line)) {
            const std::vector<std::string> c = split(line);
            rows.push_back({c.at(2), c.at(3), c.at(4), c.at(5)});
        }
        return rows;
    }
};
}  // namespace

// A sweep rerun (--force) with its grid changed from [2000, 3000] to [3000, 2000, 2500] takes
// the runs of the same scenario, wherever their rows were, and runs the new one: the row of
// 3000 reports the 3000 run's mass (by row position it reported the 2000 run's). Then the
// terrain profile the scenario reads is edited: nothing is reused.
TEST(Sweep, RerunReusesOnlyRunsOfTheSameScenarioAndFiles) {
    DensitySweep w("demlab-sweep-reuse");
    SweepOptions o;
    o.out = (w.dir / "out").string();
    o.jobs = 1;
    const SweepResult first = run_sweep(w.config("[2000, 3000]"), o);
    EXPECT_EQ(first.runs_done, 2);
    const auto t1 = w.table();
    ASSERT_EQ(t1.size(), 2u);
    const double mass2000 = std::stod(t1[0][3]);
    EXPECT_NEAR(std::stod(t1[1][3]), 1.5 * mass2000, 1e-9 * mass2000);
    o.force = true;  // another grid: another sweep.id
    const SweepResult second = run_sweep(w.config("[3000, 2000, 2500]"), o);
    EXPECT_EQ(second.runs_done, 1);
    EXPECT_EQ(second.runs_reused, 2);
    const auto t2 = w.table();
    ASSERT_EQ(t2.size(), 3u);
    EXPECT_EQ(t2[0][2], "3000");
    EXPECT_NEAR(std::stod(t2[0][3]), 1.5 * mass2000, 1e-9 * mass2000) << "the row of 3000 reports another run's mass";
    EXPECT_NEAR(std::stod(t2[1][3]), mass2000, 1e-9 * mass2000);
    EXPECT_NEAR(std::stod(t2[2][3]), 1.25 * mass2000, 1e-9 * mass2000);
    EXPECT_EQ(t2[0][0], t1[1][0]);  // the 3000 run's folder, reused
    EXPECT_EQ(t2[0][1], "1");
    EXPECT_EQ(t2[1][1], "1");
    EXPECT_EQ(t2[2][1], "0");
    // the profile edited: the same keys, another input
    std::ofstream(w.dir / "ground.csv") << "x,y\n0,0.6\n1,0\n3,0\n";
    const SweepResult third = run_sweep(w.config("[3000, 2000, 2500]"), o);
    EXPECT_EQ(third.runs_done, 3);
    EXPECT_EQ(third.runs_reused, 0);
    for (const auto& r : w.table()) EXPECT_EQ(r[1], "0");
}

// A sweep's folder names its scenario by its absolute path: another sweep file naming another
// scenario of the same name (d2/s.toml's two.toml) is refused without --force, where it
// overwrote the first's sweep.csv; the same sweep file loaded through another relative path is
// the same sweep; an id written by an earlier build (the scenario joined relative to the
// working directory) is still this sweep's. An --out whose `..` follows a folder that does not
// exist (which the system resolves only when the folders are made, into an existing folder of
// the user's) and an empty --out are refused before anything is written.
TEST(Sweep, TheFolderNamesItsScenarioAbsoluteAndTheOutPathIsChecked) {
    DensitySweep w("demlab-sweep-id");
    SweepOptions o;
    o.out = (w.dir / "out").string();
    o.jobs = 1;
    w.config("[2000]");  // (s.toml written)
    const fs::path cwd = fs::current_path();
    fs::current_path(w.dir);
    const SweepConfig c = load_sweep("s.toml");  // relative, as typed in its folder
    fs::current_path(cwd);
    EXPECT_TRUE(fs::path(c.scenario).is_absolute()) << c.scenario;
    EXPECT_EQ(run_sweep(c, o).runs_done, 1);
    EXPECT_NE(read_file(w.dir / "out/sweep.id").find("scenario = " + c.scenario + "\n"), std::string::npos);
    // the same sweep file through a relative path from another working directory: reused
    fs::current_path(w.dir / "out");
    EXPECT_EQ(run_sweep(load_sweep("../s.toml"), o).runs_reused, 1);
    // an earlier build's id, with the scenario joined as given ("../two.toml" here)
    std::string earlier = read_file(w.dir / "out/sweep.id");
    earlier.replace(earlier.find(c.scenario), c.scenario.size(), "../two.toml");
    std::ofstream(w.dir / "out/sweep.id") << earlier;
    EXPECT_EQ(run_sweep(load_sweep("../s.toml"), o).runs_reused, 1);
    fs::current_path(cwd);
    // another folder's sweep file naming its own two.toml
    fs::create_directories(w.dir / "d2");
    fs::copy_file(w.dir / "two.toml", w.dir / "d2/two.toml");
    fs::copy_file(w.dir / "ground.csv", w.dir / "d2/ground.csv");
    fs::copy_file(w.dir / "s.toml", w.dir / "d2/s.toml");
    // loaded as typed in its own folder, "s.toml" naming "two.toml" as the first did there
    const std::string before = read_file(w.dir / "out/sweep.csv");
    fs::current_path(w.dir / "d2");
    EXPECT_THROW(run_sweep(load_sweep("s.toml"), o), InputError);
    fs::current_path(cwd);
    EXPECT_EQ(read_file(w.dir / "out/sweep.csv"), before);
    // --out through a `..` after a folder that does not exist, into a folder of the user's
    fs::create_directories(w.dir / "mine");
    std::ofstream(w.dir / "mine/notes.txt") << "x";
    o.out = (w.dir / "nonexistent/../mine").string();
    EXPECT_THROW(run_sweep(c, o), InputError);
    EXPECT_FALSE(fs::exists(w.dir / "mine/runs"));
    EXPECT_FALSE(fs::exists(w.dir / "nonexistent"));
    o.out = "";
    EXPECT_THROW(run_sweep(c, o), InputError);
}

// A run folder another process is making (a second sweep into the same folder) holds its
// lock: the sweep refuses it instead of deleting it under that run.
TEST(Sweep, ARunFolderInUseIsRefusedNotDeleted) {
    DensitySweep w("demlab-sweep-lock");
    SweepOptions o;
    o.out = (w.dir / "out").string();
    o.jobs = 1;
    const SweepConfig c = w.config("[2000]");
    run_sweep(c, o);
    const auto rows = w.table();
    const fs::path run = w.dir / "out/runs" / rows.at(0).at(0);
    fs::remove(run / "summary.json");  // unfinished, as a run in progress
    {
        RunFolderLock held(run.string());
        try {
            run_sweep(c, o);
            ADD_FAILURE() << "a locked run folder was taken";
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find(rows[0][0]), std::string::npos) << e.what();
        }
        EXPECT_TRUE(fs::exists(run / "scenario.toml"));
    }
    EXPECT_EQ(run_sweep(c, o).runs_done, 1);  // free again: run afresh
}

// A run of a sweep that cannot write (a file size limit, as a full disk) ends the sweep with
// the write's exit code, 5, as `demlab run` does (it was 3, a failed run).
TEST(Sweep, AFailedWriteEndsTheSweepWithExitFive) {
    const fs::path dir = fs::temp_directory_path() / ("demlab-sweep-fsize-" + std::to_string(::getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
    std::ofstream(dir / "s.toml") << "[sweep]\nscenario = \"" << DEMLAB_SOURCE_DIR << "/scenarios/geometry-A.toml\"\n"
                                  << "set = [\"release.scale=20\", \"stop.t_max=0.002\", \"stop.rest_duration=0.001\", "
                                     "\"output.snapshot_interval=0\"]\n";
    const int status = std::system(("ulimit -f 10; " + std::string(DEMLAB_EXE) + " sweep " + (dir / "s.toml").string() +
                                    " --jobs 1 --out " + (dir / "out").string() + " >/dev/null 2>&1").c_str());
    ASSERT_TRUE(WIFEXITED(status));
    EXPECT_EQ(WEXITSTATUS(status), 5);
    fs::remove_all(dir);
}

// A row's value holding a comma is one CSV cell in sweep.csv: quoted, its own quotes doubled
// (it was written as ""a,b"", which a CSV reader splits into two cells).
TEST(Sweep, AValueWithACommaIsOneCellOfTheTable) {
    DensitySweep w("demlab-sweep-comma");
    std::ofstream(w.dir / "s.toml") << "[sweep]\nscenario = \"two.toml\"\ncolumns = [\"total_mass\"]\n"
                                    << "[[rows]]\n\"scenario.name\" = \"a,b\"\n[[rows]]\n\"scenario.name\" = \"c\"\n";
    SweepOptions o;
    o.out = (w.dir / "out").string();
    o.jobs = 1;
    run_sweep(load_sweep((w.dir / "s.toml").string()), o);
    const std::string table = read_file(w.dir / "out/sweep.csv");
    EXPECT_NE(table.find(",0,\"\"\"a,b\"\"\","), std::string::npos) << table;
    EXPECT_NE(table.find(",0,\"c\","), std::string::npos) << table;
}

// Input a run finds wrong only once its mass is made (a tracer beyond the release's discs) ends
// the sweep as bad input (exit 2), naming the row, as `demlab run` does for the same input.
TEST(Sweep, ARowWithInputFoundWrongAtItsRunIsAnInputErrorNamingTheRow) {
    const fs::path dir = fs::temp_directory_path() / ("demlab-sweep-track-" + std::to_string(::getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
    const fs::path file = dir / "s.toml";
    std::ofstream(file) << "[sweep]\nscenario = \"" << DEMLAB_SOURCE_DIR << "/scenarios/geometry-A.toml\"\n"
                        << "set = [\"release.scale=20\", \"stop.t_max=0.002\", \"stop.rest_duration=0.001\", "
                           "\"output.snapshot_interval=0\"]\n"
                        << "[[rows]]\n\"output.track\" = [1]\n[[rows]]\n\"output.track\" = [100000]\n";
    SweepOptions o;
    o.out = (dir / "out").string();
    o.jobs = 1;
    try {
        run_sweep(load_sweep(file.string()), o);
        ADD_FAILURE() << "a tracer beyond the discs was accepted";
    } catch (const InputError& e) {
        const std::string m = e.what();
        EXPECT_NE(m.find("row002"), std::string::npos) << m;
        EXPECT_NE(m.find("output.track"), std::string::npos) << m;
    }
    fs::remove_all(dir);
}

// An output folder a sweep or calibration cannot make (a symbolic link to nowhere, a file on
// the way) is refused as input (exit 2) naming the folder and why, before any run; it was a
// raw file-system message, and for calibrate a failed run (exit 3), on rank 0 alone.
TEST(Sweep, AnOutputFolderThatCannotBeMadeIsRefusedAsInputNamingIt) {
    DensitySweep w("demlab-sweep-unmakeable");
    std::ofstream(w.dir / "afile") << "the user's\n";
    fs::create_symlink(w.dir / "nowhere", w.dir / "dangling");
    CalibrationConfig cal = load_calibration(std::string(DEMLAB_SOURCE_DIR) + "/calibration/dam-break.toml");
    cal.scale = 20;
    cal.angles = {15.0};
    cal.refine = false;
    for (const auto& [out, why] : {std::pair<std::string, std::string>{"dangling", "symbolic link"},
                                   std::pair<std::string, std::string>{"afile/x", "Not a directory"}}) {
        SweepOptions o;
        o.out = (w.dir / out).string();
        o.jobs = 1;
        try {
            run_sweep(w.config("[1000.0]"), o);
            ADD_FAILURE() << out << " was accepted";
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find("cannot create output folder '" + o.out + "'"), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
        }
        CalibrationOptions co;
        co.out = o.out;
        co.jobs = 1;
        try {
            calibrate(cal, co);
            ADD_FAILURE() << out << " was accepted";
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
        }
    }
    EXPECT_FALSE(fs::exists(w.dir / "nowhere"));
    EXPECT_EQ(test_read((w.dir / "afile").string()), "the user's\n");
}

namespace {
// Two jobs on two threads that fail at once: job 0 throws FIRST, then job 1 throws SECOND once
// job 0's error has had time to be kept. Returns the class run_rank_jobs threw with its message.
template <typename First, typename Second>
std::pair<std::string, std::string> two_failures(const char* tag) {
    const fs::path dir = fs::temp_directory_path() / (std::string("demlab-rankjobs-") + tag + "-" + std::to_string(::getpid()));
    fs::remove_all(dir);
    std::atomic<int> started{0};
    std::atomic<bool> first_thrown{false};
    RankJobsDef def;
    def.count = 2;
    def.threads = 2;
    def.what = "sweep";
    def.folder = [&](size_t k) { return (dir / ("job" + std::to_string(k))).string(); };
    def.finished = [](size_t) { return false; };
    def.resumable = [](size_t) { return false; };
    def.describe = [](size_t k) { return "job" + std::to_string(k); };
    def.run = [&](size_t k, bool) {
        ++started;
        while (started.load() < 2) std::this_thread::yield();  // both jobs taken before either fails
        if (k == 0) {
            first_thrown = true;
            throw First("job 0's error");
        }
        while (!first_thrown.load()) std::this_thread::yield();
        std::this_thread::sleep_for(std::chrono::milliseconds(200));  // job 0's error kept by now
        throw Second("job 1's error");
    };
    std::pair<std::string, std::string> out{"none", ""};
    try {
        run_rank_jobs(def);
    } catch (const InputError& e) {
        out = {"input", e.what()};
    } catch (const WriteError& e) {
        out = {"write", e.what()};
    } catch (const RunError& e) {
        out = {"run", e.what()};
    } catch (const Interrupted& e) {
        out = {"interrupted", e.what()};
    }
    fs::remove_all(dir);
    return out;
}
}  // namespace

// Two jobs of one machine failing at once end the sweep with the most telling error, bad input
// (exit 2) before a failed write (5) before a failed run (3), whichever failed first: the order
// in which two runs fail is a matter of timing, and the exit code must not be. (The first
// error to arrive was kept before: a failed run hid the bad input the user has to fix.)
TEST(RankJobs, TwoJobsFailingAtOnceEndWithTheMostTellingErrorWhicheverCameFirst) {
    auto r = two_failures<RunError, InputError>("run-input");
    EXPECT_EQ(r.first, "input") << r.second;
    EXPECT_NE(r.second.find("job 1's error"), std::string::npos) << r.second;
    r = two_failures<InputError, RunError>("input-run");
    EXPECT_EQ(r.first, "input") << r.second;
    EXPECT_NE(r.second.find("job 0's error"), std::string::npos) << r.second;
    r = two_failures<RunError, WriteError>("run-write");
    EXPECT_EQ(r.first, "write") << r.second;
    r = two_failures<WriteError, RunError>("write-run");
    EXPECT_EQ(r.first, "write") << r.second;
    r = two_failures<InputError, WriteError>("input-write");
    EXPECT_EQ(r.first, "input") << r.second;
    // a run stopped by a signal beside one that failed: the failure decides (exit 3, not 4)
    r = two_failures<Interrupted, RunError>("signal-run");
    EXPECT_EQ(r.first, "run") << r.second;
    EXPECT_NE(r.second.find("job 1's error"), std::string::npos) << r.second;
}

// A run folder whose checkpoint cannot be read for a reason other than its content (memory,
// the system: checkpoint_continues lets anything but an InputError through) fails the job and
// keeps the folder with its checkpoint for the next try; only a folder whose checkpoint is of
// another run (or that has none) is emptied and run again.
TEST(RankJobs, AFolderWhoseCheckpointCannotBeReadIsKeptAndTheJobFails) {
    const fs::path dir = fs::temp_directory_path() / ("demlab-rankjobs-keep-" + std::to_string(::getpid()));
    fs::remove_all(dir);
    const fs::path job = dir / "job0";
    fs::create_directories(job);
    mark_output_dir(job.string());
    std::ofstream(job / "checkpoint.bin") << "the stopped run's state";
    bool ran = false;
    RankJobsDef def;
    def.count = 1;
    def.threads = 1;
    def.what = "sweep";
    def.folder = [&](size_t) { return job.string(); };
    def.finished = [](size_t) { return false; };
    def.resumable = [](size_t) -> bool { throw std::bad_alloc(); };
    def.describe = [](size_t) { return std::string("job0"); };
    def.run = [&](size_t, bool) { ran = true; };
    EXPECT_THROW(run_rank_jobs(def), RunError);
    EXPECT_FALSE(ran);
    EXPECT_EQ(test_read((job / "checkpoint.bin").string()), "the stopped run's state");
    // a checkpoint of another run (checkpoint_continues says false): the folder is emptied and
    // the job runs afresh
    def.resumable = [](size_t) { return false; };
    run_rank_jobs(def);
    EXPECT_TRUE(ran);
    EXPECT_FALSE(fs::exists(job / "checkpoint.bin"));
    fs::remove_all(dir);
}

// Ctrl-C on a sweep (SIGINT): the runs in progress write their checkpoints and
// stop, the command ends as interrupted (exit 4, it said nothing and died by the signal), and
// the same command then finishes the sweep, resuming the stopped runs from their checkpoints
// (they started again from the beginning) to the same bytes as a sweep never stopped.
TEST(Sweep, AnInterruptedSweepEndsWithExitFourAndTheSameCommandFinishesIt) {
    const fs::path dir = fs::temp_directory_path() / ("demlab-sweep-int-" + std::to_string(::getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
    std::ofstream(dir / "s.toml") << "[sweep]\nscenario = \"" << DEMLAB_SOURCE_DIR << "/scenarios/geometry-A.toml\"\n"
                                  << "set = [\"release.scale=20\", \"stop.t_max=1\", \"stop.rest_ke_fraction=1e-12\", "
                                     "\"output.snapshot_interval=0\"]\n[grid]\n\"material.friction_disc_deg\" = [14, 15, 16]\n";
    const std::string sweep = std::string(DEMLAB_EXE) + " sweep " + (dir / "s.toml").string() + " --jobs 2 --out " +
                              (dir / "out").string() + " >" + (dir / "log").string() + " 2>&1";
    // the signal once two runs are past their release (their folders hold release.csv), however
    // fast this build runs (the sanitizers' is several times slower)
    const std::string runs = (dir / "out/runs").string();
    const int stopped = std::system(("(exec " + sweep + ") & pid=$!; n=0; while kill -0 $pid 2>/dev/null && [ $n -lt 2400 ] && "
                                     "[ $(ls " + runs + "/*/release.csv 2>/dev/null | wc -l) -lt 2 ]; do sleep 0.05; n=$((n+1)); "
                                     "done; kill -INT $pid; wait $pid")
                                        .c_str());
    ASSERT_TRUE(WIFEXITED(stopped)) << "killed by the signal";
    EXPECT_EQ(WEXITSTATUS(stopped), 4);
    std::ifstream log(dir / "log");
    std::stringstream text;
    text << log.rdbuf();
    EXPECT_NE(text.str().find("sweep stopped by a signal"), std::string::npos) << text.str();
    EXPECT_FALSE(fs::exists(dir / "out/sweep.csv"));
    // the runs the signal stopped after their release hold a checkpoint
    int checkpoints = 0;
    for (const auto& run : fs::directory_iterator(dir / "out/runs")) checkpoints += fs::exists(run.path() / "checkpoint.bin");
    EXPECT_GE(checkpoints, 1) << text.str();
    const int again = std::system(sweep.c_str());
    ASSERT_TRUE(WIFEXITED(again));
    EXPECT_EQ(WEXITSTATUS(again), 0);
    EXPECT_TRUE(fs::exists(dir / "out/sweep.csv"));
    const std::string second = read_file(dir / "log");
    size_t resumed = 0;
    for (size_t at = second.find("(resumed from its checkpoint)"); at != std::string::npos;
         at = second.find("(resumed from its checkpoint)", at + 1))
        ++resumed;
    EXPECT_EQ(resumed, size_t(checkpoints)) << second;
    // the same sweep without a stop: every run's series the same bytes
    const std::string whole = std::string(DEMLAB_EXE) + " sweep " + (dir / "s.toml").string() + " --jobs 2 --out " +
                              (dir / "whole").string() + " >" + (dir / "log2").string() + " 2>&1";
    ASSERT_EQ(std::system(whole.c_str()), 0) << read_file(dir / "log2");
    int compared = 0;
    for (const auto& run : fs::directory_iterator(dir / "out/runs")) {
        EXPECT_FALSE(fs::exists(run.path() / "checkpoint.bin"));
        for (const char* file : {"forces.csv", "front.csv", "deposit.csv", "energy.csv"}) {
            const fs::path other = dir / "whole/runs" / run.path().filename() / file;
            ASSERT_TRUE(fs::exists(other)) << other;
            EXPECT_EQ(read_file(run.path() / file), read_file(other)) << run.path() / file;
            ++compared;
        }
    }
    EXPECT_EQ(compared, 12);
    fs::remove_all(dir);
}

// A grid value listed twice (or two that resolve alike), and a column no summary holds, are
// refused when the sweep file is read, before any run.
TEST(Sweep, DuplicateRowsAndUnknownColumnsAreRefusedBeforeAnyRun) {
    DensitySweep w("demlab-sweep-dup");
    auto message = [&](const std::string& densities, const std::string& columns) {
        try {
            w.config(densities, columns);
        } catch (const InputError& e) {
            return std::string(e.what());
        }
        return std::string("accepted");
    };
    const std::string ok = "[\"total_mass\"]";
    const std::string twice = message("[2000, 3000, 2000]", ok);
    EXPECT_NE(twice.find("row 3 (material.density=2000) is the same scenario as row 1"), std::string::npos) << twice;
    const std::string alike = message("[2000, 2000.0]", ok);
    EXPECT_NE(alike.find("row 2 (material.density=2000.0) is the same scenario as row 1"), std::string::npos) << alike;
    const std::string column = message("[2000, 3000]", "[\"total_mass\", \"runout\"]");
    EXPECT_NE(column.find("'runout' is not a number of a run's summary.json; did you mean 'runout_s'?"), std::string::npos) << column;
    EXPECT_EQ(message("[2000, 3000]", ok), "accepted");
    EXPECT_FALSE(fs::exists(w.dir / "out"));
}

// Two angles equal to two decimals get their own run folders (they shared phi15.00-seed1); an
// angle of two decimals keeps its name.
TEST(Calibration, CloseAnglesHaveTheirOwnRunFolders) {
    EXPECT_EQ(calibration_run_name(15.5, 0), "phi15.50-seed1");
    EXPECT_EQ(calibration_run_name(15.0, 1), "phi15.00-seed2");
    EXPECT_EQ(calibration_run_name(15.001, 0), "phi15.001-seed1");
    EXPECT_EQ(calibration_run_name(15.004, 0), "phi15.004-seed1");
    EXPECT_NE(calibration_run_name(15.1 + 1e-12, 0), calibration_run_name(15.1, 0));
}

// A calibration run again after its scenario file was edited makes its runs again (they were
// reused with the old scenario's objective); unchanged, it reuses them.
TEST(Calibration, RerunAfterTheScenarioIsEditedRunsAgain) {
    const fs::path dir = fs::temp_directory_path() / ("demlab-calibrate-edit-" + std::to_string(::getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
    std::string text = test_read(std::string(DEMLAB_SOURCE_DIR) + "/scenarios/dam-break.toml");
    const std::string t_max = "t_max = 4.0";
    ASSERT_NE(text.find(t_max), std::string::npos);
    auto write_scenario = [&](const std::string& value) {
        std::string t = text;
        t.replace(t.find(t_max), t_max.size(), "t_max = " + value);
        std::ofstream(dir / "dam-break.toml") << t;
    };
    write_scenario("0.3");
    CalibrationConfig c;
    c.scenario = (dir / "dam-break.toml").string();
    c.scale = 20;
    c.angles = {15.0};
    c.refine = false;
    CalibrationOptions o;
    o.out = (dir / "out").string();
    o.jobs = 1;
    EXPECT_EQ(calibrate(c, o).runs_done, 1);
    write_scenario("0.35");
    const CalibrationResult edited = calibrate(c, o);
    EXPECT_EQ(edited.runs_done, 1);
    EXPECT_EQ(edited.runs_reused, 0);
    EXPECT_NEAR(read_summary_file(o.out + "/runs/phi15.00-seed1/summary.json").number("t_end"), 0.35, 0.01);
    const CalibrationResult again = calibrate(c, o);
    EXPECT_EQ(again.runs_done, 0);
    EXPECT_EQ(again.runs_reused, 1);
    EXPECT_EQ(again.reused_runs, (std::set<std::string>{"phi15.00-seed1"}));
    const std::string timings = test_read(o.out + "/timings.csv");
    EXPECT_EQ(timings.rfind("run,wall_seconds,reused\nphi15.00-seed1,", 0), 0u) << timings;
    EXPECT_NE(timings.find(",1\nsweep,"), std::string::npos) << timings;
    fs::remove_all(dir);
}

// the known deposit moved 0.2 m out behind a level plateau: sections from 0.2 m find its angles
double shifted_surface(double x) { return x < 0.2 ? known_surface(0.0) : known_surface(x - 0.2); }

TEST(Envelope, SectionsStartWhereTheScenarioSays) {
    std::vector<Vec2> pos;
    std::vector<double> rad;
    stack_under(shifted_surface, 0.001, 0.7, pos, rad);
    const auto conn = connected_discs(pos, rad, 0.001);
    const Envelope e = upper_envelope(pos, rad, conn, 0.0, 1.0, 0.0005);
    const SlopeAngles a = slope_angles(e, 0.1, 0.0, 0.2);
    for (int i = 0; i < 5; ++i) EXPECT_NEAR(a.gamma[i], kAngles[i], 0.5) << "section " << i + 1;
    EXPECT_NEAR(a.toe_x, 0.7, 0.002);
    EXPECT_NEAR(a.gamma_ges, std::atan(known_surface(0.0) / 0.5) * 180 / kPi, 0.5);
    EXPECT_NEAR(a.h_start, a.h_wall, 0.002);                                 // (level between)
    EXPECT_LT(slope_angles(e).gamma[4], 1.0);                                // from the wall: the plateau
}
