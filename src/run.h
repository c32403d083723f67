// `demlab run`: builds the world of a scenario (a flume with its release mass, or explicit
// walls and discs), runs it to rest or t_max and writes the run folder:
//   scenario.toml (resolved), release.csv, forces.csv, front.csv, energy.csv, track.csv,
//   deposit.csv, summary.json, snapshots/ (VTK).
#pragma once
#include <functional>
#include <string>

#include "scenario.h"

namespace demlab {

struct RunOptions {
    std::string out_dir;
    bool force = false;     // replace the files of an existing folder
    // called after each snapshot is written, with the two files and the snapshot's index
    std::function<void(const std::string& discs_vtp, const std::string& walls_vtp, int index)> on_snapshot;
};

struct RunSummary {
    long n_discs = 0;
    double total_mass = 0;              // kg per metre of thickness
    double porosity = 0;                // of the release mass (settled), -1 for explicit discs
    double dt = 0;                      // s, the last step (automatic steps vary)
    double dt_min = 0, dt_max = 0;
    long steps = 0;
    double t_end = 0;
    std::string stop_reason;            // "rest" or "t_max"
    double wall_seconds = 0;            // of the run after the release mass was ready
    double particle_steps_per_second = 0;
    double runout_s = 0;                // m along the path: the deposit's front
    double runup_height = 0;            // m: highest point of the deposit on the barrier above its foot
    double max_runup_height_during_run = 0;
    double t_front_at_barrier = -1;     // s, -1 if never
    double t_peak_fx_barrier = -1;
    double t_peak_fy_arc = -1;
    double energy_balance_error = 0;    // |balance drift| / energy dissipated
};

RunSummary run_scenario(const Scenario& s, const RunOptions& o);

}  // namespace demlab
