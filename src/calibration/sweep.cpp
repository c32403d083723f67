#include "calibration/sweep.h"

#include <toml++/toml.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <thread>

#include "calibration/rank_jobs.h"
#include "calibration/ranks.h"
#include "core/error.h"
#include "core/fileio.h"
#include "core/output_dir.h"
#include "core/progress.h"
#include "run/measures.h"
#include "run/run.h"
#include "run/summary_file.h"
#include "run/checkpoint_file.h"
#include "scenario/fingerprint.h"
#include "scenario/key_registry.h"
#include "scenario/scenario.h"

namespace demlab {

namespace fs = std::filesystem;

namespace {
// the summary's numbers that depend on the machine and the moment, not the run: they go to
// timings.csv, so that sweep.csv is the same bytes on any number of ranks
const std::set<std::string> kClockKeys = {"wall_seconds", "particle_steps_per_second", "release_wall_seconds",
                                          "broadphase_update_seconds", "force_pass_busy_share",
                                          "force_pass_busy_fallbacks", "force_pass_one_range_cuts"};

std::string read_text_or_empty(const std::string& path) {
    std::ifstream in(path);
    std::stringstream b;
    b << in.rdbuf();
    return b.str();
}

// a summary key as a column name that says its unit, as the series' columns do: runout_s_m,
// peak_fx_barrier_N_per_m (a count or ratio keeps its name)
std::string column_name(const std::string& key, const std::string& unit) {
    if (unit.empty() || unit == "-") return key;
    std::string u;
    for (char ch : unit) u += ch == '/' ? std::string("_per_") : std::string(1, ch);
    return key + "_" + u;
}

// A CSV cell (RFC 4180): as it is, unless it holds a comma or a line end (or `always`): then
// in quotes, each quote inside doubled. A row's TOML literal
// "II" stays as it is (read back: II); "a,b" becomes """a,b""" (read back: "a,b").
std::string csv_field(const std::string& v, bool always = false) {
    if (!always && v.find_first_of(",\n\r") == std::string::npos) return v;
    std::string out = "\"";
    for (char ch : v) out += ch == '"' ? std::string("\"\"") : std::string(1, ch);
    return out + "\"";
}

std::string row_tag(size_t row, int seed) {
    char b[48];
    std::snprintf(b, sizeof b, "row%03zu-seed%d", row + 1, seed + 1);
    return b;
}

// "material.density=2000, rotation.model=1" (for messages)
std::string row_values(const SweepConfig& c, size_t row) {
    std::string out;
    for (size_t k = 0; k < c.keys.size(); ++k) out += (k ? ", " : "") + c.keys[k] + "=" + c.rows[row][k];
    return out.empty() ? "the scenario alone" : out;
}

// A run's folder under runs/: named by its scenario's content (scenario/fingerprint.h), not by
// its row, so that a rerun with the rows reordered, added or changed reuses exactly the runs
// of the same scenario and input files.
std::string run_name(const std::string& fingerprint) { return fingerprint.substr(0, 16); }

// the scenario of one run: the file, the common overrides, the row's, the seed
Scenario scenario_of(const SweepConfig& c, size_t row, int seed) {
    Scenario s = load_scenario(c.scenario);
    for (const std::string& a : c.common) apply_override(s, a);
    for (size_t k = 0; k < c.keys.size(); ++k) apply_override(s, c.keys[k] + "=" + c.rows[row][k]);
    apply_override(s, "scenario.seed=" + std::to_string(s.seed + unsigned(seed)));
    finish_scenario(s);
    return s;
}
}  // namespace

SweepConfig load_sweep(const std::string& path) {
    SweepConfig c;
    c.source = path;
    toml::table t;
    try {
        t = toml::parse(read_input_file(path, kMaxScenarioBytes, "sweep file"), path);
    } catch (const toml::parse_error& e) {
        throw InputError(path + ":" + std::to_string(e.source().begin.line) + ": TOML syntax error: " + std::string(e.description()));
    }
    const auto where = [&](const toml::node& n, const std::string& key) {
        return path + ":" + std::to_string(n.source().begin.line) + ": key '" + key + "'";
    };
    auto check_key = [&](const toml::node& n, const std::string& key) {
        if (!keys::find_key(key)) keys::unknown_key(where(n, key), key, keys::key_names());
        if (key == "scenario.seed") throw InputError(where(n, key) + ": the seeds are [sweep] seeds (scenario.seed + 0, 1, ...)");
    };
    for (const auto& [sec, node] : t) {
        const std::string section(sec.str());
        if (section == "sweep") {
            const toml::table* tab = node.as_table();
            if (!tab) throw InputError(where(node, section) + ": must be a table");
            for (const auto& [k, v] : *tab) {
                const std::string key = "sweep." + std::string(k.str());
                if (key == "sweep.scenario" && v.is_string()) c.scenario = *v.value<std::string>();
                else if (key == "sweep.seeds" && v.is_integer() && *v.value<int64_t>() >= 1 && *v.value<int64_t>() <= 100)
                    c.seeds = int(*v.value<int64_t>());
                else if ((key == "sweep.set" || key == "sweep.columns") && v.is_array()) {
                    for (const toml::node& e : *v.as_array()) {
                        if (!e.is_string()) throw InputError(where(e, key) + ": must be an array of strings");
                        (key == "sweep.set" ? c.common : c.columns).push_back(*e.value<std::string>());
                    }
                } else {
                    throw InputError(where(v, key) + " = " + keys::node_text(v) +
                                     ": accepted: scenario (a file), seeds (1 to 100), set (array of \"key=value\"), columns (array of summary keys)");
                }
            }
        } else if (section == "grid") {
            const toml::table* tab = node.as_table();
            if (!tab) throw InputError(where(node, section) + ": must be a table of key = [values]");
            std::vector<std::vector<std::string>> values;
            for (const auto& [k, v] : *tab) {
                const std::string key(k.str());
                check_key(v, key);
                const toml::array* a = v.as_array();
                if (!a || a->empty()) throw InputError(where(v, key) + ": a grid key takes a non-empty array of values");
                c.keys.push_back(key);
                values.emplace_back();
                for (const toml::node& e : *a) values.back().push_back(keys::node_text(e));
            }
            // every combination, the first key slowest
            std::vector<std::vector<std::string>> rows = {{}};
            for (const auto& vs : values) {
                std::vector<std::vector<std::string>> next;
                for (const auto& r : rows)
                    for (const std::string& v : vs) {
                        next.push_back(r);
                        next.back().push_back(v);
                    }
                rows = std::move(next);
            }
            c.rows = rows;
        } else if (section == "rows") {
            const toml::array* a = node.as_array();
            if (!a || !a->is_array_of_tables()) throw InputError(where(node, section) + ": must be [[rows]] tables");
            for (const toml::node& r : *a) {
                std::vector<std::pair<std::string, std::string>> row;
                for (const auto& [k, v] : *r.as_table()) {
                    check_key(v, std::string(k.str()));
                    row.emplace_back(std::string(k.str()), keys::node_text(v));
                }
                if (c.keys.empty() && c.rows.empty())
                    for (const auto& kv : row) c.keys.push_back(kv.first);
                std::vector<std::string> vals;
                for (const std::string& key : c.keys) {
                    auto it = std::find_if(row.begin(), row.end(), [&](const auto& kv) { return kv.first == key; });
                    if (it == row.end() || row.size() != c.keys.size())
                        throw InputError(where(r, "rows") + ": every row sets the same keys as the first (" + std::to_string(c.keys.size()) + ")");
                    vals.push_back(it->second);
                }
                c.rows.push_back(vals);
            }
        } else {
            throw InputError(where(node, section) + ": unknown table; accepted: [sweep], [grid], [[rows]]");
        }
    }
    if (t.contains("grid") && t.contains("rows")) throw InputError(path + ": give either [grid] or [[rows]], not both");
    if (c.scenario.empty()) throw InputError(path + ": [sweep] scenario is required (the scenario file to sweep)");
    // absolute: the folder's sweep.id names it, and the same sweep run from another directory
    // (or another sweep file naming another scenario of the same name) must be told apart
    if (fs::path(c.scenario).is_relative()) {
        c.scenario_as_given = (fs::path(path).parent_path() / c.scenario).lexically_normal().string();
        c.scenario = fs::absolute(fs::path(path).parent_path() / c.scenario).lexically_normal().string();
    }
    if (c.rows.empty()) c.rows = {{}};  // the scenario alone, over its seeds
    // a column that no run's summary.json holds is refused now, not after every run
    const std::vector<std::string> numbers = summary_number_keys();
    for (const std::string& col : c.columns)
        if (std::find(numbers.begin(), numbers.end(), col) == numbers.end()) {
            const std::string near = keys::nearest(col, numbers);
            throw InputError(path + ": [sweep] columns: '" + col + "' is not a number of a run's summary.json" +
                             (near.empty() ? std::string() : "; did you mean '" + near + "'?"));
        }
    // every run's scenario is checked now, before any output; two rows that resolve to the
    // same scenario (a value listed twice, 2000 and 2000.0) would run it twice: refused
    std::vector<std::string> fingerprints;
    for (size_t r = 0; r < c.rows.size(); ++r) {
        try {
            fingerprints.push_back(scenario_fingerprint(scenario_of(c, r, 0)));
        } catch (const InputError& e) {
            throw InputError(path + ": row " + std::to_string(r + 1) + ": " + e.what());
        }
        for (size_t q = 0; q < r; ++q)
            if (fingerprints[q] == fingerprints[r])
                throw InputError(path + ": row " + std::to_string(r + 1) + " (" + row_values(c, r) + ") is the same scenario as row " +
                                 std::to_string(q + 1) + " (" + row_values(c, q) + "): a sweep runs each scenario once; remove the duplicate");
    }
    return c;
}

SweepResult run_sweep(const SweepConfig& c, const SweepOptions& o) {
    const auto t0 = std::chrono::steady_clock::now();
    const Ranks& ranks = Ranks::world();
    // every run's scenario and its fingerprint (the files it reads hashed now): its folder's
    // name, and what a finished run in that folder must have been run with to be reused
    struct Job {
        size_t row;
        int seed;
        Scenario scenario;
        std::string fingerprint;
    };
    std::vector<Job> todo;
    std::map<std::string, size_t> by_name;
    for (size_t r = 0; r < c.rows.size(); ++r)
        for (int k = 0; k < c.seeds; ++k) {
            Scenario s;
            try {
                s = scenario_of(c, r, k);  // (load_sweep checked each row's first seed)
            } catch (const InputError& e) {
                throw InputError(c.source + ": " + row_tag(r, k) + ": " + e.what());
            }
            const std::string fp = scenario_fingerprint(s);
            const auto [it, fresh] = by_name.emplace(run_name(fp), todo.size());
            if (!fresh)  // (load_sweep refuses a duplicate row; a file edited since could make one)
                throw InputError(c.source + ": " + row_tag(r, k) + " (" + row_values(c, r) + ") is the same scenario as " +
                                 row_tag(todo[it->second].row, todo[it->second].seed) + ": a sweep runs each scenario once");
            todo.push_back({r, k, std::move(s), fp});
        }
    // the folder: new, or made by this same sweep (resume); rank 0 opens it
    auto id_naming = [&](const std::string& scenario) {
        std::ostringstream id;
        id << "scenario = " << scenario << "\nseeds = " << c.seeds << "\n";
        for (const std::string& a : c.common) id << "set " << a << "\n";
        for (size_t r = 0; r < c.rows.size(); ++r) {
            id << "row " << r + 1 << ":";
            for (size_t k = 0; k < c.keys.size(); ++k) id << " " << c.keys[k] << "=" << c.rows[r][k];
            id << "\n";
        }
        return id.str();
    };
    const std::string id = id_naming(c.scenario);
    open_folder_on_root(o.out, [&] {
        check_output_path(o.out);
        const std::string marker = o.out + "/sweep.id";
        const std::string have = read_text_or_empty(marker);
        // a folder of this sweep made by an earlier build, whose id named the scenario as
        // given relative to the working directory: the same sweep from the same directory
        const bool earlier = !c.scenario_as_given.empty() && have == id_naming(c.scenario_as_given);
        if (fs::exists(o.out) && have != id && !earlier) {
            if (!o.force)
                throw InputError("output folder '" + o.out + "' exists and was not made by this sweep; choose another --out or pass --force");
            // forced over another folder: only one demlab made, holding no input (output_dir.h)
            check_output_dir(o.out, true, {c.source, c.scenario});
        }
        create_output_tree(o.out, o.out + "/runs");
        mark_output_dir(o.out);
        write_file_atomic(marker, id);
    });

    auto dir_of = [&](const Job& j) { return o.out + "/runs/" + run_name(j.fingerprint); };
    RankJobsDef def;
    def.count = todo.size();
    def.threads = o.jobs > 0 ? o.jobs : std::max(1, int(std::thread::hardware_concurrency()));
    def.what = "sweep";
    def.folder = [&](size_t k) { return dir_of(todo[k]); };
    def.finished = [&](size_t k) { return finished_run_of(dir_of(todo[k]), todo[k].fingerprint); };
    def.resumable = [&](size_t k) { return checkpoint_continues(def.folder(k), todo[k].scenario); };
    def.run = [&](size_t k, bool resume) {
        RunOptions ro;
        ro.out_dir = dir_of(todo[k]);
        ro.handle_signals = true;  // Ctrl-C: run_rank_jobs holds the handlers for all its runs
        ro.install_handlers = false;
        ro.resume = resume;
        run_scenario(todo[k].scenario, ro);
    };
    def.describe = [&](size_t k) { return row_tag(todo[k].row, todo[k].seed) + " (runs/" + run_name(todo[k].fingerprint) + ")"; };
    SweepResult res;
    g_progress_muted = true;
    RankJobsCount count;
    try {
        count = run_rank_jobs(def);
    } catch (...) {
        g_progress_muted = false;
        throw;
    }
    g_progress_muted = false;
    res.runs_done = count.ran;
    res.runs_reused = count.reused;
    res.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (!ranks.root()) return res;

    // sweep.csv: row, seed, its run's folder, whether that run was taken from an earlier
    // invocation, the varied values, the summary's numbers; timings.csv apart
    std::vector<SummaryFile> sums;
    for (const Job& j : todo) sums.push_back(read_summary_file(dir_of(j) + "/summary.json"));
    std::vector<std::string> columns = c.columns;
    if (columns.empty())
        for (const auto& [k, v] : sums.front().numbers)
            // (the broad phase's and the force pass's figures describe the run's numerics and
            // count from a resume: not a result)
            if (!kClockKeys.count(k) && k.rfind("broadphase_", 0) != 0 && k.rfind("force_pass_", 0) != 0) columns.push_back(k);
    std::ostringstream csv, timings;
    csv.precision(10);
    csv << "row,seed,run,reused";
    for (const std::string& k : c.keys) csv << ',' << k;
    for (const std::string& k : columns) csv << ',' << column_name(k, sums.front().unit(k));
    csv << '\n';
    timings << "run,wall_seconds,release_wall_seconds,machine,reused\n";
    for (size_t n = 0; n < todo.size(); ++n) {
        const Job& j = todo[n];
        const int reused = count.reused_jobs[n] ? 1 : 0;
        csv << j.row + 1 << ',' << j.seed + 1 << ',' << run_name(j.fingerprint) << ',' << reused;
        for (const std::string& v : c.rows[j.row]) csv << ',' << csv_field(v);
        for (const std::string& k : columns) {
            const auto it = sums[n].numbers.find(k);
            if (it == sums[n].numbers.end())
                throw InputError(o.out + ": column '" + k + "' is not a number of " + dir_of(j) + "/summary.json");
            csv << ',';  // a figure the run did not measure (null in its summary): an empty cell
            if (std::isfinite(it->second)) csv << it->second;
        }
        csv << '\n';
        auto num = [&](const char* k) {
            const auto it = sums[n].numbers.find(k);
            return it == sums[n].numbers.end() ? NAN : it->second;
        };
        timings << run_name(j.fingerprint) << ',' << num("wall_seconds") << ',' << num("release_wall_seconds") << ","
                << csv_field(sums[n].text("machine"), true) << "," << reused << "\n";
    }
    timings << "sweep," << res.wall_seconds << ",,,\n";
    write_file_atomic(o.out + "/sweep.csv", csv.str());
    write_file_atomic(o.out + "/timings.csv", timings.str());
    return res;
}

}  // namespace demlab
