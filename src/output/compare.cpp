#include "output/compare.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/csv.h"
#include "core/error.h"
#include "core/fileio.h"
#include "core/interrupt.h"
#include "core/output_dir.h"
#include "core/process.h"
#include "output/plot.h"
#include "run/dan_run.h"
#include "run/summary_file.h"
#include "scenario/scenario.h"

namespace demlab {

namespace {
namespace fs = std::filesystem;

struct RunInfo {
    std::string dir, label;
    bool dan = false, flume = false;
    Scenario scenario;
    SummaryFile summary;
};

RunInfo read_run(const std::string& dir) {
    RunInfo r;
    r.dir = dir;
    if (!fs::is_directory(dir)) throw InputError(dir + ": no such run folder");
    // a finished run without a bed path (explicit discs and walls) has no front to set beside
    // the others: said as such, not as an unfinished folder
    if (fs::is_regular_file(dir + "/summary.json") && fs::is_regular_file(dir + "/scenario.toml") &&
        !fs::is_regular_file(dir + "/front.csv"))
        throw InputError(dir + ": a run without a bed path (discs and walls of its own) has no front, run-out "
                         "along a path or barrier forces to compare; compare takes flume, terrain and dam-break runs");
    for (const char* f : {"scenario.toml", "summary.json", "front.csv", "forces.csv"})
        if (!fs::is_regular_file(dir + "/" + f))
            throw InputError(dir + ": not a finished run folder (no " + f + "); compare takes folders written by demlab run");
    // every series compare reads, whole: one cut short (a full disk, a killed writer) is refused
    // naming the file and the row, before anything is drawn or copied from it
    for (const char* f : {"front.csv", "forces.csv", "deposit.csv", "front_synced.csv"})
        if (fs::is_regular_file(dir + "/" + f)) read_csv_table(dir + "/" + f);
    r.scenario = parse_scenario(read_input_file(dir + "/scenario.toml", kMaxScenarioBytes, "scenario file"), dir + "/scenario.toml");
    r.summary = read_summary_file(dir + "/summary.json");
    r.dan = r.summary.text("model") == "dan";
    r.flume = r.scenario.flume.enabled;
    std::string name = fs::path(dir).lexically_normal().filename().string();
    if (name.empty() || name == ".") name = fs::path(dir).lexically_normal().parent_path().filename().string();
    if (r.dan) {
        r.label = name + " (DAN, " + std::to_string(r.scenario.dan.blocks) + " blocks)";
    } else {
        r.label = name + " (DEM";
        if (r.flume) r.label += ", model " + std::to_string(r.scenario.world.rotation.model) + ", scale " + std::to_string(r.scenario.release.scale);
        r.label += ")";
    }
    return r;
}

// whether a run's CSV series has the column `name`
bool has_column(const std::string& path, const std::string& name) {
    std::string line;
    std::getline(std::ifstream(path) >> std::ws, line);
    return CsvHeader(line, path).has(name);
}

// gnuplot's "using a:b" for two columns of a run's CSV series, found by name (a run folder
// of an earlier build has the names without their units)
std::string columns(const std::string& path, const std::string& x, const std::string& y) {
    std::string line;
    std::getline(std::ifstream(path) >> std::ws, line);
    const CsvHeader h(line, path);
    auto legacy = [](const std::string& n) {
        for (const char* unit : {"_N_per_m", "_m", "_s"})
            if (n.size() > std::strlen(unit) && n.compare(n.size() - std::strlen(unit), std::string::npos, unit) == 0)
                return n.substr(0, n.size() - std::strlen(unit));
        return n;
    };
    return std::to_string(h.column(x, legacy(x)) + 1) + ":" + std::to_string(h.column(y, legacy(y)) + 1);
}

std::string quoted(const std::string& s) { return gnuplot_quote(s); }

// A run's series copied into the comparison's folder under a name of ours: the gnuplot script
// names no path a user chose (it runs in that folder), and the comparison keeps its data.
std::string copy_series(const std::string& src, const std::string& out, size_t k, const char* what) {
    const std::string name = "run" + std::to_string(k) + "_" + what + ".csv";
    write_file_atomic(out + "/" + name, read_input_file(src, kMaxTableBytes, "run's " + std::string(what) + " series"));
    return name;
}

std::string cell(double v, int digits = 3, const char* none = "-") {
    if (!std::isfinite(v)) return none;
    char b[32];
    std::snprintf(b, sizeof b, "%.*f", digits, v);
    return b;
}
}  // namespace

namespace {
// A run's surface.csv as x_m,y_m rows for the plot: the surface where mass stands, a blank
// line (a gap in gnuplot's line) where none does.
std::string surface_over_x(const std::string& src) {
    const CsvTable t = read_csv_table(src);  // (a cut or malformed file: an InputError naming its line)
    const CsvHeader h(t.names, src);
    const size_t cx = h.column("x_m"), cs = h.column("surface_m"), cd = h.column("depth_m");
    std::ostringstream out;
    out.precision(10);
    out << "x_m,y_m\n";
    bool gap = false;
    for (const std::vector<double>& r : t.rows) {
        if (!(r[cd] > 0.0)) {
            if (!gap) out << '\n';
            gap = true;
            continue;
        }
        gap = false;
        out << r[cx] << ',' << r[cs] << '\n';
    }
    return out.str();
}

// deposit.png: the final deposits, over the flume in x, y (each run's surface from its own
// path) when all runs are flume runs, else along s.
void compare_deposits(const CompareOptions& o, const std::vector<RunInfo>& runs, bool all_flume, std::ostringstream& gp,
                      std::vector<std::string>& made) {
    std::ostringstream plot;
    // each run's flume from its own scenario: one grey line when all runs share it, else each
    // run's bed in the run's colour (a deposit is drawn over the flume it ran on)
    bool one_bed = all_flume;
    std::vector<std::string> beds;
    if (all_flume) {
        for (const RunInfo& r : runs) {
            const DanPath bed = flume_dan_path(r.scenario);
            std::ostringstream b;
            b.precision(10);
            b << "x_m,y_m\n";
            for (double s = 0.0; s <= bed.length() + 1e-9; s += 0.005) b << bed.at(s).p.x() << ',' << bed.at(s).p.y() << '\n';
            beds.push_back(b.str());
            one_bed = one_bed && beds.back() == beds.front();
        }
    }
    if (one_bed) {
        write_file_atomic(o.out + "/bed.csv", beds.front());
        plot << "plot 'bed.csv' using 1:2 with lines lw 3 lc rgb '#303030' title 'flume'";
    } else if (all_flume) {
        plot << "plot ";
        for (size_t k = 0; k < runs.size(); ++k) {
            const std::string file = "bed_" + std::to_string(k) + ".csv";
            write_file_atomic(o.out + "/" + file, beds[k]);
            plot << (k ? ", " : "") << "'" << file << "' using 1:2 with lines lw 3 lc " << k + 1 << " dt 3 title "
                 << quoted("flume of " + runs[k].label);
        }
    } else {
        plot << "plot ";
    }
    for (size_t k = 0; k < runs.size(); ++k) {
        const RunInfo& r = runs[k];
        const std::string file = "deposit_" + std::to_string(k) + ".csv";
        auto add_line = [&] {
            plot << (k > 0 || all_flume ? ", " : "") << "'" << file << "' using 1:2 with lines lw 2 lc " << k + 1 << " title "
                 << quoted(r.label);
        };
        // over the flume a run's own surface over x (surface.csv), which deposit.csv's height
        // normal to the bed cannot give over the concave arc (docs/flume.md)
        const std::string over_x = r.dir + "/surface.csv";
        if (all_flume && fs::exists(over_x)) {
            write_file_atomic(o.out + "/" + file, surface_over_x(over_x));
            add_line();
            continue;
        }
        const std::string src = r.dir + "/deposit.csv";
        if (!fs::exists(src)) continue;
        std::ifstream in(src);
        std::string line;
        std::getline(in, line);
        const CsvHeader header(line, src);
        const size_t cs = header.column("s_m"), ch = header.column("height_m");
        std::ostringstream surf;
        surf << "x_m,y_m\n";
        const DanPath* path = nullptr;
        std::unique_ptr<DanPath> own;
        if (all_flume) {
            own = std::make_unique<DanPath>(flume_dan_path(r.scenario));
            path = own.get();
        }
        double last_x = -INFINITY;
        while (std::getline(in, line)) {
            const std::vector<std::string> c = csv_cells(line);
            if (std::max(cs, ch) >= c.size()) throw InputError(src + ": a short row '" + line + "'");
            const double s = parse_number_cell(c[cs], src), height = parse_number_cell(c[ch], src);
            if (path) {
                const DanPathPoint q = path->at(s);
                if (height <= 0.0) {
                    surf << '\n';  // a gap in the surface where there is no mass
                    continue;
                }
                // over the arc the bed's normals converge: a deposit thicker than the
                // radius maps back on itself there, so a point behind the last is left out
                const Vec2 p = q.p + height * q.normal();
                if (p.x() <= last_x) continue;
                last_x = p.x();
                surf << p.x() << ',' << p.y() << '\n';
            } else {
                surf << s << ',' << height << '\n';
            }
        }
        write_file_atomic(o.out + "/" + file, surf.str());
        add_line();
    }
    gp << "set output 'deposit.png'\nset title 'Final deposits'\n";
    if (all_flume) gp << "set size ratio -1\nset xlabel 'x (m)'\nset ylabel 'y (m)'\n";
    else gp << "set xlabel 's along the bed path (m)'\nset ylabel 'height normal to the bed (m)'\n";
    gp << plot.str() << "\nset size noratio\n";
    made.push_back(o.out + "/deposit.png");
}

// comparison.md and comparison.csv: the landmarks side by side, and why a "-" was not measured.
void compare_table(const CompareOptions& o, const std::vector<RunInfo>& runs, std::vector<std::string>& made) {
    // the landmarks side by side
    std::ostringstream md, csv;
    md << "# Comparison\n\n| run | front at the barrier (s) | run-out s (m) | run-up (m) | highest run-up (m) | peak fx on the "
          "barrier (N/m) | at (s) | filtered peak fx (N/m) | static fx (N/m) | deposit's depth (m) | at rest (s) | stop |\n"
          "|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    csv << "run,model,t_front_at_barrier_s,runout_s_m,runup_height_m,max_runup_height_during_run_m,peak_fx_barrier_N_per_m,"
           "t_peak_fx_barrier_s,t_end_s,stop_reason,peak_fx_barrier_filtered_N_per_m,static_fx_barrier_N_per_m,"
           "deposit_max_depth_m,x_deposit_max_depth_m\n";
    for (const RunInfo& r : runs) {
        const SummaryFile& s = r.summary;
        const double shift = s.number("sync_shift");
        const std::string arrival = cell(s.number("t_front_at_barrier")) +
                                    (std::isfinite(shift) ? " (" + cell(s.number("t_front_at_barrier") + shift) + " synchronised)" : "");
        // mass that left the flume: the run-out and run-up are lower bounds (">=")
        const std::string bound = s.number("runout_lower_bound") == 1.0 ? ">= " : "";
        md << "| " << r.label << " | " << arrival << " | " << bound << cell(s.number("runout_s")) << " | " << bound
           << cell(s.number("runup_height")) << " | " << cell(s.number("max_runup_height_during_run")) << " | "
           << cell(s.number("peak_fx_barrier"), 1) << " | " << cell(s.number("t_peak_fx_barrier")) << " | "
           << cell(s.number("peak_fx_barrier_filtered"), 1) << " | " << cell(s.number("static_fx_barrier"), 1) << " | "
           << cell(s.number("deposit_max_depth")) << " | " << cell(s.number("t_end")) << " | " << s.text("stop_reason") << " |\n";
        csv << '"' << r.label << "\"," << (r.dan ? "dan" : "dem") << ',' << cell(s.number("t_front_at_barrier"), 6, "") << ','
            << cell(s.number("runout_s"), 6, "") << ',' << cell(s.number("runup_height"), 6, "") << ','
            << cell(s.number("max_runup_height_during_run"), 6, "") << ',' << cell(s.number("peak_fx_barrier"), 3, "") << ','
            << cell(s.number("t_peak_fx_barrier"), 6, "") << ',' << cell(s.number("t_end"), 6, "") << ',' << s.text("stop_reason") << ','
            << cell(s.number("peak_fx_barrier_filtered"), 3, "") << ',' << cell(s.number("static_fx_barrier"), 3, "") << ','
            << cell(s.number("deposit_max_depth"), 6, "") << ',' << cell(s.number("x_deposit_max_depth"), 6, "") << '\n';
    }
    md << "\nRun-out: s of the deposit's front along the bed path (DEM: the foremost connected disc; DAN: the front "
          "block). Run-up: the deposit's highest point on the barrier above its foot. Deposit's depth: its largest "
          "vertical depth above the bed (surface.csv). \">=\": mass left the flume (summary.json's left_flume), so "
          "the figure is a lower bound.\n";
    // "-": a landmark the run did not measure; why, from its summary
    bool heading = false;
    for (const RunInfo& r : runs)
        for (const auto& [key, why] : r.summary.not_measured) {
            if (!heading) md << "\n\"-\": not measured:\n\n";
            heading = true;
            md << "- " << r.label << ", " << key << ": " << why << "\n";
        }
    write_file_atomic(o.out + "/comparison.md", md.str());
    write_file_atomic(o.out + "/comparison.csv", csv.str());
    made.push_back(o.out + "/comparison.md");
    made.push_back(o.out + "/comparison.csv");
}

std::vector<std::string> compare_into(const CompareOptions& o, const std::vector<RunInfo>& runs) {
    std::vector<std::string> made;
    bool all_flume = true;
    for (const RunInfo& r : runs) all_flume = all_flume && r.flume;

    std::ostringstream gp;
    gp << "set terminal pngcairo size 1100,600 font 'DejaVu Sans,11'\nset datafile separator ','\nset grid\n"
       << "set key below\n";
    compare_deposits(o, runs, all_flume, gp, made);
    // the fronts over time
    gp << "set output 'front.png'\nset title 'Front along the bed path'\nset xlabel 't (s)'\n"
       << "set ylabel 's of the front (m)'\nplot ";
    for (size_t k = 0; k < runs.size(); ++k) {
        const RunInfo& r = runs[k];
        gp << (k ? ", " : "") << "'" << copy_series(r.dir + "/front.csv", o.out, k, "front") << "' every ::1 using " << columns(r.dir + "/front.csv", "t_s", "s_front_m")
           << " with lines lw 2 title " << quoted(r.label);
        if (fs::exists(r.dir + "/front_synced.csv"))
            gp << ", '" << copy_series(r.dir + "/front_synced.csv", o.out, k, "front_synced") << "' every ::1 using " << columns(r.dir + "/front_synced.csv", "t_s", "s_front_m")
               << " with lines lw 2 dt 2 title "
               << quoted(r.label + ", synchronised at " + cell(r.scenario.dan.sync_time, 2) + " s");
    }
    gp << "\n";
    made.push_back(o.out + "/front.png");
    // the barrier's force histories, of the runs that have a barrier (a terrain without one has
    // no barrier columns)
    std::vector<size_t> with_barrier;
    for (size_t k = 0; k < runs.size(); ++k)
        if (has_column(runs[k].dir + "/forces.csv", "fx_barrier_N_per_m") || has_column(runs[k].dir + "/forces.csv", "fx_barrier"))
            with_barrier.push_back(k);
    for (const char* axis : with_barrier.empty() ? std::vector<const char*>{} : std::vector<const char*>{"x", "y"}) {
        const std::string column = std::string("f") + axis + "_barrier_N_per_m";
        gp << "set output 'barrier_f" << axis << ".png'\nset title 'Force on the barrier, " << axis
           << " (per metre of width)'\nset ylabel 'f" << axis << " (N/m)'\nplot ";
        for (const size_t k : with_barrier)
            gp << (k != with_barrier.front() ? ", " : "") << "'" << (axis[0] == 'x' ? copy_series(runs[k].dir + "/forces.csv", o.out, k, "forces") : "run" + std::to_string(k) + "_forces.csv") << "' every ::1 using " << columns(runs[k].dir + "/forces.csv", "t_s", column) << " with lines lw 1.5 title "
               << quoted(runs[k].label);
        gp << "\n";
        made.push_back(o.out + "/barrier_f" + axis + ".png");
    }
    const std::string script = o.out + "/compare.gp";
    write_file_atomic(script, gp.str());
    run_gnuplot(o.out, "compare.gp", made);  // no shell; the script names only the files of this folder

    compare_table(o, runs, made);
    return made;
}

}  // namespace

std::vector<std::string> compare_runs(const CompareOptions& o) {
    if (o.runs.empty()) throw InputError("compare: give one or more run folders");
    std::vector<RunInfo> runs;
    for (const std::string& d : o.runs) runs.push_back(read_run(d));
    // runs of different scenarios (geometries): each label names its scenario
    bool same_scenario = true;
    for (const RunInfo& r : runs) same_scenario = same_scenario && r.scenario.name == runs[0].scenario.name;
    if (!same_scenario)
        for (RunInfo& r : runs) r.label += ", " + r.scenario.name;
    if (!gnuplot_available())
        throw RunError("gnuplot is not installed, so no comparison was drawn (apt-get install gnuplot-nox, or "
                       "scripts/install-deps.sh)");
    prepare_output_dir(o.out, o.force, o.runs);
    InterruptScope interrupts;  // a Ctrl-C while gnuplot draws: an interruption, the old folder put back
    try {
        std::vector<std::string> made = compare_into(o, runs);
        remove_replaced_output(o.out);
        return made;
    } catch (...) {
        abandon_output(o.out);  // a failed comparison leaves nothing to block its retry
        throw;
    }
}

}  // namespace demlab
