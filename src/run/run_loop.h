// The run loop both solvers run through (the DEM's run_scenario, DAN's run_dan): it steps the
// solver, samples the series and takes snapshots on their intervals, stops at stop.t_max,
// stop.max_steps or rest, shows progress (and calls RunOptions::on_progress), and on a signal
// or the checkpoint timer writes a checkpoint between two steps. What a solver measures and
// writes is its RunParts, which the loop calls: one call per step, never per disc or block.
#pragma once
#include <functional>
#include <string>

#include "run/run.h"
#include "run/solver.h"

namespace demlab {

// The loop's clock between two steps; the solver's run saves these in its checkpoints.
struct LoopClock {
    double& next_series;  // s, the next series sample
    double& next_snap;    // s, the next snapshot
    double& peak_ke;      // J/m, the largest kinetic energy so far (the rest watch's scale)
    double& rest_since;   // s, since when the kinetic energy is below stop.rest_ke_fraction of it (-1: it is not)
};

struct RunParts {
    std::function<void()> sample;               // the series' rows now
    std::function<void()> snapshot;             // a snapshot now (empty: the run takes none)
    // after each step: the solver's own measures; a stop reason ends the run ("" goes on)
    std::function<std::string()> after_step;
    std::function<void()> watch;                // every watch_steps steps, before the rest watch (may be empty)
    std::function<void()> step_failed;          // the step threw a RunError: name its cause (may be empty)
    std::function<void()> write_checkpoint;
    // the rest watch and progress every this many steps (the DEM's kinetic energy is summed by
    // its integration: reading it every step would cost)
    int watch_steps = 1;
};

// Runs to the stop; returns its reason ("t_max", "max_steps", "rest" or one of after_step's).
// The last instant is sampled once whatever the stop.
std::string run_loop(Solver& solver, RunParts& parts, const Scenario& s, const RunOptions& o, LoopClock clock);

}  // namespace demlab
