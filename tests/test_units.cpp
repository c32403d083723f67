// Every column of a run's CSV series names its unit, summary.json names the unit of every
// number, and the readers (plots, `demlab compare`, DAN's reference front) find the columns by
// name: in any order, and in run folders of earlier builds (unitless names).
#include <gtest/gtest.h>

#include <filesystem>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

#include "core/csv.h"
#include "run/measures.h"
#include "core/error.h"
#include "files.h"
#include "output/compare.h"
#include "output/plot.h"
#include "run/run.h"
#include "run/summary_file.h"
#include "scenario/scenario.h"
#include "setups/setup.h"
#include "run/series_columns.h"

using namespace demlab;
using demlab::test::read_file;
using demlab::test::read_file_header;
using demlab::test::temp_dir;
namespace fs = std::filesystem;

namespace {

// a column's unit is the end of its name; these have none (ids, counts, ratios)
bool names_its_unit(const std::string& c) {
    static const std::set<std::string> unitless = {"id", "i", "k", "bonds_intact_fraction"};
    if (unitless.count(c)) return true;
    for (const char* u : {"_s", "_m", "_N_per_m", "_Ns_per_m", "_J_per_m", "_m_per_s", "_rad", "_rad_per_s", "_kg_per_m", "_Pa"})
        if (c.size() > std::string(u).size() && c.compare(c.size() - std::string(u).size(), std::string::npos, u) == 0)
            return true;
    return false;
}

// geometry A at scale 20 to 0.3 s with two tracers, and its DAN twin
fs::path run_flume(const std::string& name, const std::string& solver) {
    Scenario s = load_scenario(std::string(DEMLAB_SOURCE_DIR) + "/scenarios/geometry-A.toml");
    for (const std::string& a : {std::string("release.scale=20"), std::string("stop.t_max=0.3"),
                                 std::string("output.snapshot_interval=0.1"), std::string("output.track=[3, 7]"),
                                 "scenario.solver=" + solver})
        apply_override(s, a);
    finish_scenario(s);
    const fs::path dir = temp_dir(name);
    run_scenario(s, {dir.string(), false, {}});
    return dir;
}

}  // namespace

TEST(Units, EveryColumnAndSummaryNumberNamesItsUnit) {
    for (const char* solver : {"dem", "dan"}) {
        SCOPED_TRACE(solver);
        const fs::path dir = run_flume(std::string("units-") + solver, solver);
        int files = 0;
        for (const auto& e : fs::directory_iterator(dir)) {
            if (e.path().extension() != ".csv" || e.path().filename() == "release.csv") continue;
            ++files;
            for (const std::string& c : csv_cells(read_file_header(e.path())))
                EXPECT_TRUE(names_its_unit(c)) << e.path().filename() << ": " << c;
        }
        EXPECT_GE(files, 4);
        const SummaryFile sum = read_summary_file((dir / "summary.json").string());
        EXPECT_GT(sum.numbers.size(), 15u);
        for (const auto& [key, value] : sum.numbers) {
            if (key == "left_flume" || key == "runout_lower_bound") continue;  // booleans
            EXPECT_FALSE(sum.unit(key).empty()) << key;
        }
        for (const auto& [key, unit] : sum.units) EXPECT_TRUE(sum.numbers.count(key)) << key << " has a unit but no number";
        EXPECT_EQ(sum.unit("runout_s"), "m");  // s is the path coordinate, not seconds
        EXPECT_EQ(sum.unit("peak_fx_barrier"), "N/m");
        EXPECT_EQ(sum.unit("t_front_at_barrier"), "s");
        EXPECT_FALSE(sum.text("scenario").empty());  // the units object leaves the strings alone
        fs::remove_all(dir);
    }
}

// The flume's forces.csv columns are the ones DAN writes and earlier runs have (compare and the
// plots read both alike); a terrain without a barrier has no barrier or arc columns.
TEST(Units, ForcesColumnsFollowTheSetUpsWalls) {
    Scenario a = load_scenario(std::string(DEMLAB_SOURCE_DIR) + "/scenarios/geometry-A.toml");
    finish_scenario(a);
    // the columns of earlier builds and DAN first, then every step's extremes, then the
    // barrier's and the arc's filtered loads
    const std::string flume = forces_header(make_setup(a)->force_walls());
    EXPECT_EQ(flume.substr(0, std::string(kForcesColumns).size() + 1), std::string(kForcesColumns) + ",");
    EXPECT_EQ(flume.substr(std::string(kForcesColumns).size()),
              ",fx_slope_max_N_per_m,fx_slope_min_N_per_m,fy_slope_max_N_per_m,fy_slope_min_N_per_m,fx_arc_max_N_per_m,"
              "fx_arc_min_N_per_m,fy_arc_max_N_per_m,fy_arc_min_N_per_m,fx_barrier_max_N_per_m,fx_barrier_min_N_per_m,"
              "fy_barrier_max_N_per_m,fy_barrier_min_N_per_m,fx_total_max_N_per_m,fx_total_min_N_per_m,fy_total_max_N_per_m,"
              "fy_total_min_N_per_m,fx_barrier_filtered_N_per_m,fy_arc_filtered_N_per_m");
    Scenario d = load_scenario(std::string(DEMLAB_SOURCE_DIR) + "/scenarios/dam-break.toml");
    finish_scenario(d);
    EXPECT_EQ(forces_header(make_setup(d)->force_walls()),
              "t_s,fx_floor_N_per_m,fy_floor_N_per_m,fx_back_wall_N_per_m,fy_back_wall_N_per_m,fx_total_N_per_m,"
              "fy_total_N_per_m,ix_floor_Ns_per_m,iy_floor_Ns_per_m,ix_back_wall_Ns_per_m,iy_back_wall_Ns_per_m,"
              "ix_total_Ns_per_m,iy_total_Ns_per_m,fx_gate_N_per_m,fy_gate_N_per_m,ix_gate_Ns_per_m,iy_gate_Ns_per_m,"
              "fx_floor_max_N_per_m,fx_floor_min_N_per_m,fy_floor_max_N_per_m,fy_floor_min_N_per_m,fx_back_wall_max_N_per_m,"
              "fx_back_wall_min_N_per_m,fy_back_wall_max_N_per_m,fy_back_wall_min_N_per_m,fx_total_max_N_per_m,"
              "fx_total_min_N_per_m,fy_total_max_N_per_m,fy_total_min_N_per_m");
    ForceWalls terrain;
    terrain.slope = {0, 1};
    EXPECT_EQ(forces_header(terrain), "t_s,fx_slope_N_per_m,fy_slope_N_per_m,fx_total_N_per_m,fy_total_N_per_m,"
                                      "ix_slope_Ns_per_m,iy_slope_Ns_per_m,ix_total_Ns_per_m,iy_total_Ns_per_m,"
                                      "fx_slope_max_N_per_m,fx_slope_min_N_per_m,fy_slope_max_N_per_m,fy_slope_min_N_per_m,"
                                      "fx_total_max_N_per_m,fx_total_min_N_per_m,fy_total_max_N_per_m,fy_total_min_N_per_m");
}

// The plots read forces.csv, front.csv and energy.csv by name: with the columns in another
// order they draw the same curves, with the unitless names of earlier builds too, and a
// missing column is an input error that names it.
TEST(Units, PlotsReadTheColumnsByName) {
    const fs::path dir = run_flume("units-plots", "dem");
    ASSERT_NO_THROW(make_plots(dir.string(), 320, 200));
    const std::string smooth = read_file(dir / "plots/forces_smoothed.csv");
    // forces.csv reversed, column by column
    const CsvTable forces = read_csv_table((dir / "forces.csv").string());
    std::ofstream out(dir / "forces.csv");
    for (size_t c = forces.names.size(); c-- > 0;) out << forces.names[c] << (c ? "," : "\n");
    out.precision(17);
    for (const auto& row : forces.rows)
        for (size_t c = row.size(); c-- > 0;) out << row[c] << (c ? "," : "\n");
    out.close();
    ASSERT_NO_THROW(make_plots(dir.string(), 320, 200));
    EXPECT_EQ(read_file(dir / "plots/forces_smoothed.csv"), smooth);
    // an earlier build's names
    for (const char* f : {"forces.csv", "front.csv", "energy.csv"}) {
        std::string text = read_file(dir / f);
        std::string header = text.substr(0, text.find('\n'));
        std::string old;
        for (std::string c : csv_cells(header)) {
            for (const char* u : {"_N_per_m", "_Ns_per_m", "_J_per_m", "_m", "_s"})
                if (c.size() > std::string(u).size() && c.compare(c.size() - std::string(u).size(), std::string::npos, u) == 0) {
                    c.resize(c.size() - std::string(u).size());
                    break;
                }
            old += (old.empty() ? "" : ",") + c;
        }
        std::ofstream(dir / f) << old << text.substr(text.find('\n'));
    }
    ASSERT_NO_THROW(make_plots(dir.string(), 320, 200));
    EXPECT_EQ(read_file(dir / "plots/forces_smoothed.csv"), smooth);
    // a column gone
    std::ofstream(dir / "front.csv") << "t_s,displacement_m\n0,0\n";
    try {
        make_plots(dir.string(), 320, 200);
        ADD_FAILURE() << "a front.csv without s_front_m was plotted";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("s_front_m"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("front.csv"), std::string::npos) << e.what();
    }
    fs::remove_all(dir);
}

// A wall group's name in forces.csv's header reaches the plots' legend as a gnuplot string,
// quoted: a header crafted to close the quote and call system() is drawn as text, never run.
TEST(Units, AColumnNameInForcesCsvCannotRunAGnuplotCommand) {
    const fs::path dir = run_flume("units-plot-quote", "dem");
    const fs::path pwned = dir / "pwned";
    const std::string part = "a'.system('touch " + pwned.string() + "').'";
    const std::string text = read_file(dir / "forces.csv");
    std::istringstream in(text);
    std::string line;
    std::ostringstream out;
    for (bool first = true; std::getline(in, line); first = false)
        out << line << (first ? ",fx_" + part + "_N_per_m,fy_" + part + "_N_per_m" : ",0,0") << "\n";
    std::ofstream(dir / "forces.csv") << out.str();
    make_plots(dir.string(), 320, 200);
    const std::string gp = read_file(dir / "plots/plots.gp");
    EXPECT_NE(gp.find("title 'a''.system(''touch "), std::string::npos) << gp;
    EXPECT_EQ(gp.find("title 'a'.system("), std::string::npos) << gp;
    EXPECT_FALSE(fs::exists(pwned));
    fs::remove_all(dir);
}

// A landmark that did not happen, or that the set-up lacks, is null in summary.json with its
// reason in "not_measured", "-" in compare's table with the reason below it, and an empty
// cell in its CSV: never the -1 or 0 a sweep or a calibration would average (issue 55, row 3).
// Geometry A to 0.3 s: the front is still on the slope (it reaches the barrier at about 0.8 s).
TEST(Units, ALandmarkNotMeasuredIsNullWithItsReason) {
    const fs::path dem = run_flume("units-null-dem", "dem"), dan = run_flume("units-null-dan", "dan");
    for (const fs::path& dir : {dem, dan}) {
        SCOPED_TRACE(dir.string());
        const SummaryFile sum = read_summary_file((dir / "summary.json").string());
        for (const char* key : {"t_front_at_barrier", "peak_fx_barrier", "t_peak_fx_barrier"}) {
            ASSERT_TRUE(sum.numbers.count(key)) << key;
            EXPECT_TRUE(std::isnan(sum.number(key))) << key << " = " << sum.number(key);
            ASSERT_TRUE(sum.not_measured.count(key)) << key;
        }
        EXPECT_NE(sum.not_measured.at("t_front_at_barrier").find("did not reach the barrier"), std::string::npos);
        EXPECT_NE(sum.not_measured.at("peak_fx_barrier").find("no load"), std::string::npos);
        // what was measured stays a number, and is not listed
        EXPECT_TRUE(std::isfinite(sum.number("runout_s")));
        EXPECT_FALSE(sum.not_measured.count("runout_s"));
        // the units object and the strings are read as before
        EXPECT_EQ(sum.unit("t_front_at_barrier"), "s");
        EXPECT_FALSE(sum.text("scenario").empty());
    }
    CompareOptions c;
    c.runs = {dem.string(), dan.string()};
    c.out = temp_dir("units-null-compare").string();
    ASSERT_NO_THROW(compare_runs(c));
    const std::string md = read_file(fs::path(c.out) / "comparison.md");
    EXPECT_NE(md.find("t_front_at_barrier: the front did not reach the barrier"), std::string::npos) << md;
    // run,model,t_front_at_barrier_s,...: the arrival's cell empty after each model
    const std::string csv = read_file(fs::path(c.out) / "comparison.csv");
    EXPECT_NE(csv.find(",dem,,"), std::string::npos) << csv;
    EXPECT_NE(csv.find(",dan,,"), std::string::npos) << csv;
    EXPECT_EQ(csv.find("nan"), std::string::npos) << csv;
    for (const fs::path& d : {dem, dan, fs::path(c.out)}) fs::remove_all(d);
}

// The dam break has no barrier and no arc: those landmarks are null with that reason, and its
// deposit's height and length come from its envelope over the floor (issue 55, row 4).
TEST(Units, TheDamBreakReportsItsOwnDeposit) {
    Scenario s = load_scenario(std::string(DEMLAB_SOURCE_DIR) + "/scenarios/dam-break.toml");
    for (const char* a : {"release.scale=20", "stop.t_max=0.3", "output.snapshot_interval=0"}) apply_override(s, a);
    finish_scenario(s);
    const fs::path dir = temp_dir("units-dam-break");
    const RunSummary r = run_scenario(s, {dir.string(), false, {}});
    const SummaryFile sum = read_summary_file((dir / "summary.json").string());
    for (const char* key : {"t_front_at_barrier", "runup_height", "peak_fx_barrier", "peak_fy_arc"}) {
        EXPECT_TRUE(std::isnan(sum.number(key))) << key;
        ASSERT_TRUE(sum.not_measured.count(key)) << key;
        EXPECT_NE(sum.not_measured.at(key).find("the set-up has no"), std::string::npos) << key;
    }
    EXPECT_EQ(not_measured_reason(r, "t_front_at_barrier"), sum.not_measured.at("t_front_at_barrier"));
    // the column (0.40 m) has begun to collapse: the deposit is lower than the column and longer
    // than its 0.20 m base, and ends at the run-out
    EXPECT_GT(sum.number("deposit_max_height"), 0.2);
    EXPECT_LE(sum.number("deposit_max_height"), 0.41);
    EXPECT_GT(sum.number("deposit_length"), 0.2);
    EXPECT_LE(sum.number("deposit_length"), sum.number("runout_s") + 1e-9);
    // over the floor the height is the vertical depth
    EXPECT_EQ(sum.number("deposit_max_depth"), sum.number("deposit_max_height"));
    EXPECT_GE(sum.number("x_deposit_max_depth"), 0.0);
    // forces.csv holds the dam break's own walls (it held the flume's slope, arc and barrier,
    // all zeros): the floor and the back wall carry the column, whose weight they share
    const CsvTable f = read_csv_table((dir / "forces.csv").string());
    auto col = [&](const std::string& name) {
        for (size_t c = 0; c < f.names.size(); ++c)
            if (f.names[c] == name) return c;
        ADD_FAILURE() << "no column " << name;
        return size_t(0);
    };
    for (const std::string& n : f.names)
        for (const char* absent : {"slope", "arc", "barrier"}) EXPECT_EQ(n.find(absent), std::string::npos) << n;
    const double weight = sum.number("total_mass") * 9.81;
    const std::vector<double>& first = f.rows.front();
    // at t = 0 the column stands on the floor (1,561 of its 1,722 N/m at scale 20; the back wall
    // takes friction only, and the rest of the weight is still in the contacts' springs)
    EXPECT_GT(-first[col("fy_floor_N_per_m")], 0.8 * weight);
    EXPECT_LT(-(first[col("fy_floor_N_per_m")] + first[col("fy_back_wall_N_per_m")]), 1.05 * weight);
    EXPECT_LT(first[col("fx_back_wall_N_per_m")], 0.0);  // the column pushes the back wall back
    EXPECT_EQ(first[col("fy_total_N_per_m")], first[col("fy_floor_N_per_m")] + first[col("fy_back_wall_N_per_m")]);
    // its front's run-out over time along the floor (front.csv), up to the run-out
    const CsvTable front = read_csv_table((dir / "front.csv").string());
    ASSERT_FALSE(front.rows.empty());
    EXPECT_GT(front.rows.back()[1], 0.2);  // past the gate at 0.20 m
    EXPECT_LE(front.rows.back()[1], sum.number("runout_s") + 0.05);
    // compare takes it (it refused it: "not a finished run folder"), its barrier figures "-"
    CompareOptions c;
    c.runs = {dir.string()};
    c.out = temp_dir("units-dam-break-compare").string();
    ASSERT_NO_THROW(compare_runs(c));
    EXPECT_NE(read_file(fs::path(c.out) / "comparison.md").find("t_front_at_barrier: the set-up has no barrier"), std::string::npos);
    fs::remove_all(c.out);
    fs::remove_all(dir);
}
