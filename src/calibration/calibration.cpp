#include "calibration/calibration.h"

#include <toml++/toml.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <sstream>
#include <thread>

#include "calibration/rank_jobs.h"
#include "calibration/ranks.h"
#include "geometry/deposit.h"
#include "core/error.h"
#include "core/process.h"
#include "core/fileio.h"
#include "core/output_dir.h"
#include "output/frame.h"
#include "output/image.h"
#include "output/plot.h"
#include "core/progress.h"
#include "output/renderer.h"
#include "run/run.h"
#include "run/summary_file.h"
#include "run/checkpoint_file.h"
#include "scenario/fingerprint.h"
#include "scenario/scenario.h"
#include "setups/setup.h"
#include "core/validate.h"

namespace demlab {

namespace fs = std::filesystem;

// ------------------------------------------------------------------ configuration

CalibrationConfig load_calibration(const std::string& path) {
    CalibrationConfig c;
    c.source = path;
    toml::table t;
    try {
        t = toml::parse(read_input_file(path, kMaxScenarioBytes, "calibration file"), path);
    } catch (const toml::parse_error& e) {
        throw InputError(path + ":" + std::to_string(e.source().begin.line) + ": TOML syntax error: " +
                         std::string(e.description()));
    }
    const auto where = [&](const toml::node& n, const std::string& key) {
        return path + ":" + std::to_string(n.source().begin.line) + ": key '" + key + "'";
    };
    const std::vector<std::string> lab_keys = {"gamma_ges", "gamma_1", "gamma_2", "gamma_3", "gamma_4", "gamma_5"};
    bool have_scenario = false;
    for (const auto& [sec, node] : t) {
        const std::string section(sec.str());
        const toml::table* tab = node.as_table();
        if (!tab || (section != "calibration" && section != "lab"))
            throw InputError(where(node, section) + ": unknown table; accepted: [calibration], [lab]");
        for (const auto& [k, v] : *tab) {
            const std::string key = section + "." + std::string(k.str());
            const std::string w = where(v, key);
            auto number = [&](const toml::node& n, double lo, double hi, const char* unit) {
                auto x = n.value<double>();
                if (!x || !(n.is_number()) || !(*x >= lo && *x <= hi))
                    throw InputError(w + ": must be a number in [" + format_number(lo) + ", " + format_number(hi) + "] " + unit);
                return *x;
            };
            // a count or a section: a whole number (1.5 seeds is not 1)
            auto whole = [&](const toml::node& n, double lo, double hi, const char* unit) {
                const double x = number(n, lo, hi, unit);
                if (x != std::floor(x))
                    throw InputError(w + ": must be a whole number in [" + format_number(lo) + ", " + format_number(hi) + "] " + unit);
                return int(x);
            };
            if (key == "calibration.scenario") {
                auto s = v.value_exact<std::string>();
                if (!s) throw InputError(w + ": must be the path of a scenario file");
                c.scenario = *s;
                have_scenario = true;
            } else if (key == "calibration.angles") {
                const toml::array* a = v.as_array();
                if (!a || a->empty()) throw InputError(w + ": must be a non-empty array of angles in degrees");
                c.angles.clear();
                for (const auto& e : *a) c.angles.push_back(number(e, 0.0, 60.0, "deg"));
            } else if (key == "calibration.seeds") {
                c.seeds = whole(v, 1, 100, "(count)");
            } else if (key == "calibration.sections") {
                const toml::array* a = v.as_array();
                if (!a || a->empty()) throw InputError(w + ": must be an array of section numbers 1 to 5");
                c.sections.clear();
                for (const auto& e : *a) c.sections.push_back(whole(e, 1, 5, "(section)"));
            } else if (key == "calibration.refine") {
                auto b = v.value_exact<bool>();
                if (!b) throw InputError(w + ": must be true or false");
                c.refine = *b;
            } else if (key == "calibration.tolerance") {
                c.tolerance = number(v, 0.01, 5.0, "deg");
            } else if (key == "calibration.wall_gap") {
                c.wall_gap = number(v, 0.0, 0.05, "m");
            } else if (key == "calibration.scale") {
                c.scale = whole(v, 0, 100, "(scale factor)");
            } else if (section == "lab") {
                auto it = std::find(lab_keys.begin(), lab_keys.end(), std::string(k.str()));
                if (it == lab_keys.end())
                    throw InputError(w + ": unknown key; accepted: lab.gamma_ges, lab.gamma_1 ... lab.gamma_5");
                c.lab[it - lab_keys.begin()] = number(v, -90, 90, "deg");
            } else {
                throw InputError(w + ": unknown key; accepted: scenario, angles, seeds, sections, refine, tolerance, scale, wall_gap");
            }
        }
    }
    if (!have_scenario) throw InputError(path + ": missing key 'calibration.scenario' (the dam-break scenario file)");
    // absolute: the folder's calibration.id names it (see SweepConfig::scenario)
    if (fs::path(c.scenario).is_relative()) {
        c.scenario_as_given = (fs::path(path).parent_path() / c.scenario).lexically_normal().string();
        c.scenario = fs::absolute(fs::path(path).parent_path() / c.scenario).lexically_normal().string();
    }
    std::sort(c.angles.begin(), c.angles.end());
    c.angles.erase(std::unique(c.angles.begin(), c.angles.end()), c.angles.end());
    return c;
}

// ------------------------------------------------------------------ runs

namespace {

std::map<std::string, double> read_summary(const std::string& path) { return read_summary_file(path).numbers; }

// An angle's name in run folders and tables: two decimals (phi15.50), or as many more as the
// angle needs to be told apart from every other (phi15.001, phi15.004): each angle its own folder.
std::string angle_tag(double angle) {
    char buf[64];
    for (int digits = 2; digits <= 17; ++digits) {
        std::snprintf(buf, sizeof buf, "phi%.*f", digits, angle);
        if (std::strtod(buf + 3, nullptr) == angle) break;
    }
    return buf;
}

}  // namespace

std::string calibration_run_name(double angle, int seed) { return angle_tag(angle) + "-seed" + std::to_string(seed + 1); }

namespace {

double objective_of(const std::map<std::string, double>& r, const CalibrationConfig& c) {
    double sum = 0;
    for (int i : c.sections) {
        auto it = r.find("gamma_" + std::to_string(i));
        const double g = it == r.end() ? NAN : it->second;
        if (std::isnan(g)) return INFINITY;  // the deposit did not reach that section
        sum += std::abs(g - c.lab[i]);
    }
    return sum;
}

// the deposit with its envelope, the 10 cm sections, their fitted lines and angles
void render_deposit(const std::string& run_dir, const std::map<std::string, double>& summary, double wall_gap, double start) {
    const auto snaps = list_snapshots(run_dir);
    Frame f = read_frame(snaps.back().discs, snaps.back().walls);
    const Envelope e = read_envelope_csv(run_dir + "/envelope.csv");
    std::vector<Vec2> env;
    for (size_t k = 0; k < e.y.size(); ++k)
        if (!std::isnan(e.y[k])) env.emplace_back(e.x(k), e.y[k]);
    if (env.empty()) return;
    f.overlays.push_back({env, 0.85, 0.1, 0.1});
    for (int i = 1; i <= 5; ++i) {
        const double lo = start + (5 - i) * 0.1, hi = start + (6 - i) * 0.1;
        f.overlays.push_back({{Vec2(lo, 0.0), Vec2(lo, 0.45)}, 0.5, 0.5, 0.5});
        double slope = 0, icpt = 0;
        if (!fit_line(e, std::max(lo, wall_gap), hi, slope, icpt)) continue;
        f.overlays.push_back({{Vec2(lo, icpt + slope * lo), Vec2(hi, icpt + slope * hi)}, 0.1, 0.3, 0.9});
        char buf[48];
        auto it = summary.find("gamma_" + std::to_string(i));
        std::snprintf(buf, sizeof buf, "g%d = %.1f", i, it == summary.end() ? NAN : it->second);
        f.notes.emplace_back(Vec2(lo + 0.01, icpt + slope * (lo + 0.05) + 0.04), buf);
    }
    RenderStyle st;
    st.width = 1000;
    st.height = 450;
    st.view_set = true;
    st.view_lo = Vec2(-0.02, -0.02);
    double top = 0.0;
    for (const Vec2& p : env) top = std::max(top, p.y());
    st.view_hi = Vec2(std::max(0.6, env.back().x() + 0.05), top + 0.06);
    Renderer r(st);
    write_png(run_dir + "/deposit.png", r.render(f));
}

}  // namespace

double AngleResult::mean(const std::string& key) const {
    double s = 0;
    int n = 0;
    for (const auto& r : runs) {
        auto it = r.find(key);
        if (it != r.end() && !std::isnan(it->second)) {
            s += it->second;
            ++n;
        }
    }
    return n ? s / n : NAN;
}

namespace {

// The scenario of one run: the file at the angle, the configuration's scale, the seed's offset;
// checked, and refused unless it is a dam break.
Scenario calibration_scenario(const CalibrationConfig& c, double angle, int seed) {
    Scenario s = load_scenario(c.scenario);
    apply_override(s, "material.friction_disc_deg=" + format_number(angle));
    if (c.scale) apply_override(s, "release.scale=" + std::to_string(c.scale));
    apply_override(s, "scenario.seed=" + std::to_string(s.seed + unsigned(seed)));
    finish_scenario(s);
    if (make_setup(s)->kind() != "dam_break") throw InputError(c.scenario + ": not a [dam_break] scenario");
    return s;
}

// The folder: new, or one made for this same configuration (resume).
void open_calibration_folder_here(const CalibrationConfig& c, const CalibrationOptions& o) {
    auto id_naming = [&](const std::string& scenario) {
        std::ostringstream cfg;
        cfg << "scenario = " << scenario << "\nseeds = " << c.seeds << "\nscale = " << c.scale << "\n";
        return cfg.str();
    };
    const std::string cfg = id_naming(c.scenario);
    check_output_path(o.out);
    const std::string marker = o.out + "/calibration.id";
    if (fs::exists(o.out)) {
        std::ifstream in(marker);
        std::stringstream have;
        have << in.rdbuf();
        // a folder of this calibration made by an earlier build, whose id named the scenario as
        // given relative to the working directory: the same calibration from the same directory
        const bool earlier = !c.scenario_as_given.empty() && have.str() == id_naming(c.scenario_as_given);
        if (have.str() != cfg && !earlier) {
            if (!o.force)
                throw InputError("output folder '" + o.out + "' exists and was not made by this calibration "
                                 "(scenario, seeds, scale); choose another --out or pass --force");
            // forced over another folder: only one demlab made, holding no input (output_dir.h)
            check_output_dir(o.out, true, {c.source, c.scenario});
        }
    }
    create_output_tree(o.out, o.out + "/runs");
    mark_output_dir(o.out);
    write_file_atomic(marker, cfg);
}

// Rank 0 opens the folder; the others wait for it (and stop with it if it refused).
void open_calibration_folder(const CalibrationConfig& c, const CalibrationOptions& o) {
    open_folder_on_root(o.out, [&] { open_calibration_folder_here(c, o); });
}

// Runs the dam break for each (angle, seed) not yet finished, `jobs` at a time, and gathers
// each angle's objective over its seeds.
std::vector<AngleResult> evaluate_angles(const CalibrationConfig& c, const CalibrationOptions& o, int jobs,
                                         const std::vector<double>& angles, CalibrationResult& res) {
    struct Job {
        double angle;
        int seed;
    };
    std::vector<Job> todo;
    for (double a : angles)
        for (int k = 0; k < c.seeds; ++k) todo.push_back({a, k});
    // each run's scenario and fingerprint (scenario/fingerprint.h): a finished run in the
    // folder is reused only when it ran this scenario with these input files (the scenario
    // file edited since, or a file it reads, and the run is made again)
    std::vector<Scenario> scenarios;
    std::vector<std::string> fingerprints;
    for (const Job& job : todo) {
        Scenario s = calibration_scenario(c, job.angle, job.seed);
        fingerprints.push_back(scenario_fingerprint(s));
        scenarios.push_back(std::move(s));
    }
    std::map<std::pair<double, int>, std::map<std::string, double>> done;
    const double sections_start = load_scenario(c.scenario).dam_break.sections_start;  // m (the scenario's sections)
    auto dir_of = [&](const Job& job) { return o.out + "/runs/" + calibration_run_name(job.angle, job.seed); };
    // a run's figures: its summary and the angles of its saved envelope with this
    // configuration's sections (changing them needs no rerun)
    auto figures_of = [&](const std::string& dir) {
        auto summary = read_summary(dir + "/summary.json");
        const SlopeAngles a = slope_angles(read_envelope_csv(dir + "/envelope.csv"), 0.1, c.wall_gap, sections_start);
        summary["gamma_ges"] = a.gamma_ges;
        for (int i = 0; i < 5; ++i) summary["gamma_" + std::to_string(i + 1)] = a.gamma[i];
        return summary;
    };
    RankJobsDef def;
    def.count = todo.size();
    def.threads = jobs;
    def.what = "calibration";
    def.folder = [&](size_t k) { return dir_of(todo[k]); };
    def.finished = [&](size_t k) { return finished_run_of(dir_of(todo[k]), fingerprints[k]); };
    def.resumable = [&](size_t k) { return checkpoint_continues(def.folder(k), scenarios[k]); };
    def.run = [&](size_t k, bool resume) {
        const Scenario& s = scenarios[k];
        RunOptions ro;
        ro.out_dir = dir_of(todo[k]);
        ro.handle_signals = true;  // Ctrl-C: run_rank_jobs holds the handlers for all its runs
        ro.install_handlers = false;
        ro.resume = resume;
        run_scenario(s, ro);
    };
    def.describe = [&](size_t k) {
        const Job& job = todo[k];
        const std::string dir = dir_of(job);
        const auto summary = figures_of(dir);
        if (!fs::exists(dir + "/deposit.png")) render_deposit(dir, summary, c.wall_gap, sections_start);
        char line[96];
        std::snprintf(line, sizeof line, "%s seed %d: objective %.2f deg", angle_tag(job.angle).c_str(), job.seed + 1,
                      objective_of(summary, c));
        return std::string(line);
    };
    // every rank's runs are done (or one failed): then each rank reads them all
    const RankJobsCount count = run_rank_jobs(def);
    res.runs_done += count.ran;
    res.runs_reused += count.reused;
    for (size_t k = 0; k < todo.size(); ++k)
        if (count.reused_jobs[k]) res.reused_runs.insert(calibration_run_name(todo[k].angle, todo[k].seed));
    for (const Job& job : todo) done[{job.angle, job.seed}] = figures_of(dir_of(job));
    std::vector<AngleResult> out;
    for (double a : angles) {
        AngleResult r;
        r.angle = a;
        std::vector<double> obj;
        for (int k = 0; k < c.seeds; ++k) {
            r.runs.push_back(done[{a, k}]);
            obj.push_back(objective_of(done[{a, k}], c));
        }
        double sum = 0;
        for (double v : obj) sum += v;
        r.objective_mean = sum / double(obj.size());
        r.objective_min = *std::min_element(obj.begin(), obj.end());
        r.objective_max = *std::max_element(obj.begin(), obj.end());
        if (obj.size() > 1) {
            double ss = 0;
            for (double v : obj) ss += (v - r.objective_mean) * (v - r.objective_mean);
            r.objective_sd = std::sqrt(ss / double(obj.size() - 1));
            r.objective_se = r.objective_sd / std::sqrt(double(obj.size()));
        } else {
            r.objective_sd = r.objective_se = NAN;
        }
        out.push_back(r);
    }
    return out;
}

// Golden-section search on the bracket around the best grid angle, to c.tolerance.
void refine_best_angle(const CalibrationConfig& c, const CalibrationOptions& o, int jobs, CalibrationResult& res, size_t best) {
    // golden section on the bracket around the best grid angle
    double lo = res.grid[best == 0 ? 0 : best - 1].angle;
    double hi = res.grid[std::min(best + 1, res.grid.size() - 1)].angle;
    const double g = 0.5 * (std::sqrt(5.0) - 1.0);
    const auto eval = [&](double a) {
        a = std::round(a * 100.0) / 100.0;
        for (const AngleResult& r : res.refined)
            if (r.angle == a) return r.objective_mean;
        for (const AngleResult& r : res.grid)
            if (r.angle == a) return r.objective_mean;
        std::printf("refine: %.2f deg\n", a);
        AngleResult r = evaluate_angles(c, o, jobs, {a}, res).front();
        res.refined.push_back(r);
        if (r.objective_mean < res.best_objective) {
            res.best_objective = r.objective_mean;
            res.best_angle = r.angle;
            res.best_se = r.objective_se;
        }
        return r.objective_mean;
    };
    double x1 = hi - g * (hi - lo), x2 = lo + g * (hi - lo);
    double f1 = eval(x1), f2 = eval(x2);
    while (hi - lo > c.tolerance) {
        if (f1 <= f2) {
            hi = x2;
            x2 = x1;
            f2 = f1;
            x1 = hi - g * (hi - lo);
            f1 = eval(x1);
        } else {
            lo = x1;
            x1 = x2;
            f1 = f2;
            x2 = lo + g * (hi - lo);
            f2 = eval(x2);
        }
    }
}

// table.csv and table.md: the Table-7 layout, every angle's mean section angles and objective.
void write_calibration_table(const CalibrationConfig& c, const CalibrationOptions& o, const CalibrationResult& res,
                             const std::vector<AngleResult>& all) {
    const char* rows[6] = {"gamma_ges", "gamma_1", "gamma_2", "gamma_3", "gamma_4", "gamma_5"};
    std::ostringstream csv, md;
    csv << "angle,lab";
    md << "# Dam-break calibration (Table 7 layout)\n\nScenario `" << c.scenario << "`, " << c.seeds
       << " seed(s) per angle (mean shown; the objective's spread in brackets), objective = sum over sections";
    for (int i : c.sections) md << ' ' << i;
    md << " of |gamma_i - gamma_i,lab|. Best angle in bold (wall times: timings.csv).\n\n| angle (deg) | lab |";
    for (const auto& a : all) {
        csv << "," << angle_tag(a.angle);
        md << (a.angle == res.best_angle ? " **" : " ") << format_number(a.angle) << (a.angle == res.best_angle ? "** |" : " |");
    }
    csv << "\n";
    md << "\n|---|---|";
    for (size_t k = 0; k < all.size(); ++k) md << "---|";
    md << "\n";
    for (int r = 0; r < 6; ++r) {
        csv << rows[r] << "," << c.lab[r];
        char lab[32];
        std::snprintf(lab, sizeof lab, "%.2f", c.lab[r]);
        md << "| " << rows[r] << " | " << lab << " |";
        for (const auto& a : all) {
            char v[32];
            std::snprintf(v, sizeof v, "%.2f", a.mean(rows[r]));
            csv << "," << v;
            md << " " << v << " |";
        }
        csv << "\n";
        md << "\n";
    }
    csv << "objective,0";
    md << "| objective | 0 |";
    for (const auto& a : all) {
        char v[64];
        std::snprintf(v, sizeof v, "%.2f", a.objective_mean);
        csv << "," << v;
        if (c.seeds > 1) std::snprintf(v, sizeof v, "%.2f [%.2f, %.2f]", a.objective_mean, a.objective_min, a.objective_max);
        md << (a.angle == res.best_angle ? " **" : " ") << v << (a.angle == res.best_angle ? "** |" : " |");
    }
    csv << "\n";
    md << "\n\nBest: " << format_number(res.best_angle) << " deg (objective " << format_number(std::round(res.best_objective * 1000) / 1000)
       << " deg). The thesis (PFC2D): best 15.5 deg, objective 3.17 deg.\n\nConfidence: "
       << calibration_confidence(res, c.seeds).text << "\n\nDeposits with their envelope, sections and fitted "
          "angles: `runs/phi<angle>-seed<k>/deposit.png`; all envelopes: `envelopes.png`.\n";
    write_file_atomic(o.out + "/table.csv", csv.str());
    write_file_atomic(o.out + "/table.md", md.str());

}

// envelopes.png: the lab profile (section angles integrated from the toe at 0.5 m) and each
// run's envelope.
void plot_envelopes(const CalibrationConfig& c, const CalibrationOptions& o, const std::vector<AngleResult>& all) {
    if (gnuplot_available()) {
        std::ostringstream lab;
        lab << "x,y\n";
        double y = 0;
        lab << 0.5 << ',' << 0 << '\n';
        for (int i = 1; i <= 5; ++i) {
            y += 0.1 * std::tan(c.lab[i] * kPi / 180.0);
            lab << 0.5 - 0.1 * i << ',' << y << '\n';
        }
        write_file_atomic(o.out + "/lab_profile.csv", lab.str());
        std::ostringstream gp;
        gp << "set terminal pngcairo size 1100,600 font 'DejaVu Sans,11'\nset output 'envelopes.png'\n"
           << "set datafile separator ','\nset grid\nset key outside right top\nset xlabel 'x from the back wall (m)'\n"
           << "set ylabel 'surface height (m)'\nset title 'Dam-break deposits: envelopes against the lab profile'\n"
           << "plot 'lab_profile.csv' skip 1 using 1:2 with linespoints lw 3 lc rgb 'black' title 'lab (angles of Table 7, toe at 0.5 m)'";
        for (const auto& a : all)
            gp << ", 'runs/" << angle_tag(a.angle) << "-seed1/envelope.csv' skip 1 using 1:2 with lines title '"
               << format_number(a.angle) << " deg'";
        gp << "\n";
        write_file_atomic(o.out + "/envelopes.gp", gp.str());
        ProcessDef gnuplot;  // no shell, in the calibration's folder: the script names only its files
        gnuplot.argv = {"gnuplot", "envelopes.gp"};
        gnuplot.cwd = o.out;
        if (run_process(gnuplot) != 0)
            std::fprintf(stderr, "demlab: warning: gnuplot failed on envelopes.gp\n");
    }
}

}  // namespace

CalibrationResult calibrate(const CalibrationConfig& c, const CalibrationOptions& o) {
    const auto t0 = std::chrono::steady_clock::now();
    // the scenario as the first run reads it, before the folder is made: a missing, invalid or
    // other than dam-break scenario leaves nothing behind
    if (!c.angles.empty()) calibration_scenario(c, c.angles.front(), 0);
    open_calibration_folder(c, o);
    const int jobs = o.jobs > 0 ? o.jobs : std::max(1, int(std::thread::hardware_concurrency()));
    CalibrationResult res;
    g_progress_muted = true;
    const Ranks& ranks = Ranks::world();
    if (ranks.size() > 1) std::printf("rank %d of %d: ", ranks.rank(), ranks.size());
    std::printf("grid: %zu angles x %d seed(s), %d job(s) at a time\n", c.angles.size(), c.seeds, jobs);
    res.grid = evaluate_angles(c, o, jobs, c.angles, res);
    size_t best = 0;
    for (size_t k = 1; k < res.grid.size(); ++k)
        if (res.grid[k].objective_mean < res.grid[best].objective_mean) best = k;
    res.best_angle = res.grid[best].angle;
    res.best_objective = res.grid[best].objective_mean;
    res.best_se = res.grid[best].objective_se;
    if (c.refine && res.grid.size() >= 2) refine_best_angle(c, o, jobs, res, best);
    g_progress_muted = false;
    res.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::vector<AngleResult> all = res.grid;
    all.insert(all.end(), res.refined.begin(), res.refined.end());
    std::sort(all.begin(), all.end(), [](const AngleResult& a, const AngleResult& b) { return a.angle > b.angle; });
    // the results on rank 0, the same bytes for any number of ranks and jobs; the wall times
    // (which vary) apart, in timings.csv
    if (Ranks::world().root()) {
        write_calibration_table(c, o, res, all);
        plot_envelopes(c, o, all);
        std::ostringstream t;
        t << "run,wall_seconds,reused\n";
        for (const AngleResult& a : all)
            for (size_t k = 0; k < a.runs.size(); ++k) {
                const auto w = a.runs[k].find("wall_seconds");
                const std::string run = calibration_run_name(a.angle, int(k));
                t << run << ',' << (w == a.runs[k].end() ? NAN : w->second) << ',' << (res.reused_runs.count(run) ? 1 : 0) << '\n';
            }
        t << "sweep," << res.wall_seconds << ",\n";
        write_file_atomic(o.out + "/timings.csv", t.str());
    }
    return res;
}

CalibrationConfidence calibration_confidence(const CalibrationResult& res, int seeds) {
    CalibrationConfidence out;
    char b[256];
    if (seeds < 2) {
        out.text = "not established: one seed per angle, so the objective's spread over seeds is not known, and differences "
                   "between angles may be noise (at scale 20 it jumps by several degrees between angles 0.03 deg apart); "
                   "run --seeds 3 or more";
        return out;
    }
    std::vector<AngleResult> all = res.grid;
    all.insert(all.end(), res.refined.begin(), res.refined.end());
    for (const AngleResult& a : all) {
        if (a.angle == res.best_angle) continue;
        const double se = std::sqrt(a.objective_se * a.objective_se + res.best_se * res.best_se);
        if (!(a.objective_mean - res.best_objective > 2.0 * se)) out.not_separated.push_back(a.angle);
    }
    std::sort(out.not_separated.begin(), out.not_separated.end());
    out.not_separated.erase(std::unique(out.not_separated.begin(), out.not_separated.end()), out.not_separated.end());
    out.established = out.not_separated.empty();
    std::snprintf(b, sizeof b, "the best angle's objective is %.2f +- %.2f deg (standard error over %d seeds); ", res.best_objective,
                  res.best_se, seeds);
    out.text = b;
    if (out.established) {
        out.text += "every other angle tried is more than twice the standard error of the difference above it";
    } else {
        out.text += "within the noise (less than twice the standard error of the difference) of the best: ";
        for (size_t k = 0; k < out.not_separated.size(); ++k) out.text += (k ? ", " : "") + format_number(out.not_separated[k]);
        out.text += " deg; more seeds would tell them apart (the standard error falls as 1 / sqrt(seeds))";
    }
    return out;
}

namespace {
// The file apply_calibration writes: SCENARIO-calibrated.toml beside the scenario.
std::string calibrated_path(const std::string& scenario) {
    const fs::path p(scenario);
    return (p.parent_path() / (p.stem().string() + "-calibrated" + p.extension().string())).string();
}

// The scenario's text with material.friction_disc_deg set to `angle` (an existing key replaced
// where it stands, however indented; else added under [material], made if missing), the
// provenance above; checked to parse as a scenario.
std::string calibrated_text(const std::string& scenario, double angle, const std::vector<std::string>& provenance) {
    std::ifstream in(scenario);
    if (!in) throw InputError(scenario + ": cannot open the scenario to apply the calibration to");
    std::vector<std::string> lines;
    std::string line;
    while (std::getline(in, line)) lines.push_back(line);
    const std::string value = "friction_disc_deg = " + format_number(angle) + "  # calibrated by demlab calibrate";
    auto trimmed = [](const std::string& l) {
        const size_t b = l.find_first_not_of(" \t");
        return b == std::string::npos ? std::string() : l.substr(b);
    };
    auto is_key = [&](const std::string& l) {
        const std::string t = trimmed(l);
        if (t.rfind("friction_disc_deg", 0) != 0) return false;
        const size_t e = t.find_first_not_of(" \t", 17);
        return e != std::string::npos && t[e] == '=';
    };
    bool in_material = false, done = false;
    long material_header = -1;
    for (size_t k = 0; k < lines.size() && !done; ++k) {
        const std::string t = trimmed(lines[k]);
        if (!t.empty() && t[0] == '[') {
            in_material = t.rfind("[material]", 0) == 0;
            if (in_material && material_header < 0) material_header = long(k);
        }
        if (in_material && is_key(lines[k])) {
            lines[k] = value;
            done = true;
        }
    }
    if (!done) {
        if (material_header >= 0) lines.insert(lines.begin() + material_header + 1, value);
        else {
            lines.push_back("");
            lines.push_back("[material]");
            lines.push_back(value);
        }
    }
    const std::string out = calibrated_path(scenario);
    std::ostringstream text;
    text << "# " << out << ": " << scenario << " with the disc-disc friction angle from demlab calibrate\n";
    for (const std::string& note : provenance) text << "# " << note << "\n";
    for (const auto& l : lines) text << l << "\n";
    parse_scenario(text.str(), scenario);  // still a valid scenario (errors name the file read)
    return text.str();
}
}  // namespace

void check_apply_calibration(const std::string& scenario, bool force) {
    const std::string out = calibrated_path(scenario);
    if (fs::exists(out) && !force)
        throw InputError("--apply: " + out + " exists already: pass --force to replace it (the original " + scenario +
                         " is never changed)");
    calibrated_text(scenario, 20.0, {});  // (any angle: the edit and the parse are what is checked)
}

std::string apply_calibration(const std::string& scenario, double angle, bool force, const std::vector<std::string>& provenance) {
    const std::string out = calibrated_path(scenario);
    if (fs::exists(out) && !force)
        throw InputError(out + " exists already: pass --force to replace it (the original " + scenario + " is never changed)");
    write_file_atomic(out, calibrated_text(scenario, angle, provenance));
    return out;
}

}  // namespace demlab
