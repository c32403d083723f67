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
    std::string scenario;                  // scenario file (relative paths: to the config file)
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
};

struct CalibrationResult {
    std::vector<AngleResult> grid, refined;
    double best_angle = 0, best_objective = 0;
    int runs_done = 0, runs_reused = 0;
    std::set<std::string> reused_runs;  // "phi15.00-seed1": taken from an earlier invocation (all ranks')
    double wall_seconds = 0;
};

CalibrationResult calibrate(const CalibrationConfig& c, const CalibrationOptions& o);

// The run folder of an angle and seed (0-based) under OUT/runs/: "phi15.50-seed1", with more
// decimals where two decimals would not tell the angle apart ("phi15.001-seed1").
std::string calibration_run_name(double angle, int seed);

// Writes a copy of a scenario with material.friction_disc_deg set (never over an existing file
// unless force). Returns the path written.
std::string apply_calibration(const std::string& scenario, double angle, bool force);

}  // namespace demlab
