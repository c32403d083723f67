// The dam-break friction calibration (thesis section 4.3.3, Table 7): runs the dam break for a
// set of disc-disc friction angles (and seeds), extracts the deposit's slope angles, and finds
// the angle that minimises sum_{i in sections} |gamma_i - gamma_i,lab|, first on the grid,
// then with a golden-section search to a set tolerance.
#pragma once
#include <map>
#include <set>
#include <string>
#include <vector>

namespace demlab {

struct CalibrationConfig {
    std::string source;                    // the config file
    std::string scenario;                  // scenario file (relative paths: to the config file), absolute
    std::string scenario_as_given;         // the config's folder joined as given (the id of earlier builds' folders)
    std::vector<double> angles{14, 14.5, 15, 15.5, 16, 17, 18, 19};  // deg
    int seeds = 1;                         // runs per angle (seed, seed + 1, ...)
    std::vector<int> sections{3, 4, 5};    // sections in the objective (thesis: 3 to 5)
    bool refine = true;                    // golden-section search after the grid
    double tolerance = 0.1;                // deg, of the refinement
    double lab[6] = {22.433, 9.271, 21.453, 21.562, 28.740, 30.644};  // gamma_ges, gamma_1..5 (Table 7)
    int scale = 0;                         // 0: the scenario's
    double wall_gap = 0.0;                 // m, section 5 starts this far from the back wall (0: the thesis')
};

CalibrationConfig load_calibration(const std::string& path);

struct CalibrationOptions {
    std::string out;          // folder (resumable: finished runs in it are reused)
    int jobs = 0;             // workers; 0 = number of cores
    bool force = false;       // allow a folder made for another configuration
};

struct AngleResult {
    double angle = 0;
    std::vector<std::map<std::string, double>> runs;  // per seed: gamma_ges, gamma_1..5, wall_seconds
    double mean(const std::string& key) const;
    double objective_mean = 0, objective_min = 0, objective_max = 0;
    // over the seeds: the sample standard deviation and the mean's standard error (deg); NaN
    // with one seed (the spread is not known)
    double objective_sd = 0, objective_se = 0;
};

// How far the best angle stands from the others, against the noise of the objective over
// seeds. With several seeds an angle is told apart from the best when their means differ by
// more than twice the standard error of the difference (about 95 % for normal scatter); the
// best is established when every other evaluated angle is told apart. With one seed the
// spread is not known and the best is not established: at scale 20 the objective jumps by
// several degrees between angles 0.03 deg apart.
struct CalibrationConfidence {
    bool established = false;
    std::vector<double> not_separated;  // the angles whose objective is within that noise of the best's
    std::string text;                   // the sentence the console, table.md and --apply write
};
struct CalibrationResult;
CalibrationConfidence calibration_confidence(const CalibrationResult& res, int seeds);

struct CalibrationResult {
    std::vector<AngleResult> grid, refined;
    double best_angle = 0, best_objective = 0;
    int runs_done = 0, runs_reused = 0;
    std::set<std::string> reused_runs;  // "phi15.00-seed1": taken from an earlier invocation (all ranks')
    double best_se = 0;                 // the best angle's standard error over seeds (NaN: one seed)
    double wall_seconds = 0;
};

CalibrationResult calibrate(const CalibrationConfig& c, const CalibrationOptions& o);

// The run folder of an angle and seed (0-based) under OUT/runs/: "phi15.50-seed1", with more
// decimals where two decimals would not tell the angle apart ("phi15.001-seed1").
std::string calibration_run_name(double angle, int seed);

// What apply_calibration would refuse, checked before the calibration runs (hours of runs
// otherwise end in the refusal): the scenario cannot be read or edited into a valid one, or
// its -calibrated copy exists (unless force). Throws InputError.
void check_apply_calibration(const std::string& scenario, bool force);

// Writes a copy of a scenario with material.friction_disc_deg set (never over an existing file
// unless force). Returns the path written.
// `provenance`: comment lines written above the value (where it came from: scale, seeds,
// objective, run folder, confidence).
std::string apply_calibration(const std::string& scenario, double angle, bool force,
                              const std::vector<std::string>& provenance = {});

}  // namespace demlab
