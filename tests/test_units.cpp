// Every column of a run's CSV series names its unit, summary.json names the unit of every
// number, and the readers (plots, `demlab compare`, DAN's reference front) find the columns by
// name: in any order, and in run folders of earlier builds (unitless names).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <set>

#include "core/csv.h"
#include "core/error.h"
#include "files.h"
#include "output/plot.h"
#include "run/run.h"
#include "run/summary_file.h"
#include "scenario/scenario.h"

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
