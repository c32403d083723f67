// `demlab sweep SWEEP.toml`: any scenario run over a table of overrides (a grid of values, or
// explicit rows), several seeds a row, on one machine (--jobs) or spread over MPI ranks as the
// calibration is (ranks.h), resumable (a finished run of the same scenario fingerprint is
// reused); sweep.csv gathers each run's summary by row.
//
//   [sweep]
//   scenario = "../scenarios/geometry-A.toml"   # relative to the sweep file
//   seeds = 3                                   # runs per row (scenario.seed, +1, +2, ...)
//   set = ["release.scale=20"]                  # overrides of every row
//   columns = ["runout_s", "runup_height"]      # summary keys gathered (default: every number
//                                               # but the wall-clock ones)
//   [grid]                                      # every combination, keys in the order written
//   "material.friction_disc_deg" = [14, 15.5, 17]
//   "rotation.model" = [1, 3]
//   # or, instead of [grid], explicit rows:
//   [[rows]]
//   "material.friction_disc_deg" = 14
//   "rotation.model" = 1
#pragma once
#include <string>
#include <vector>

namespace demlab {

struct SweepConfig {
    std::string source;                        // the sweep file
    std::string scenario;                      // resolved against the sweep file's folder, absolute
    std::string scenario_as_given;             // the sweep file's folder joined as given (the id of earlier builds' folders)
    int seeds = 1;
    std::vector<std::string> common;           // key=value of every row
    std::vector<std::string> keys;             // the varied keys, in order
    std::vector<std::vector<std::string>> rows;  // per row, a TOML literal per key
    std::vector<std::string> columns;          // summary keys; empty: every number but the timings
};

// Reads and checks a sweep file, and every row's scenario (InputError before any run).
SweepConfig load_sweep(const std::string& path);

struct SweepOptions {
    std::string out;   // folder: runs/<fingerprint>/ (a run each, named by its scenario), sweep.csv, timings.csv
    int jobs = 0;      // runs at once on this machine; 0 = the cores
    bool force = false;
};

struct SweepResult {
    int runs_done = 0, runs_reused = 0;  // this rank's
    double wall_seconds = 0;
};

SweepResult run_sweep(const SweepConfig& c, const SweepOptions& o);

}  // namespace demlab
