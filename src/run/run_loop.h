// The run loop both solvers run through (run_scenario, run.cpp): it steps the
// solver, samples the series and takes snapshots on their intervals, stops at stop.t_max,
// stop.max_steps or rest, shows progress (and calls RunOptions::on_progress), and on a signal
// or the checkpoint timer writes a checkpoint between two steps. What a solver measures and
// writes is its RunParts, which the loop calls: one call per step, never per disc or block.
#pragma once
#include <functional>
#include <string>
#include <vector>

#include "run/run.h"
#include "run/solver.h"
#include "scenario/fingerprint.h"

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
    // the loop's progress line on a terminal (a generator settling its mass shows its own)
    bool show_progress = true;
};

// One solver's run as the loop sees it: the solver, the parts the loop calls, the loop's
// clock, the run's own state in a checkpoint, and its files at the end. A continuum solver's
// run (DAN) is one; run_scenario takes it through the folder, the loop and its checkpoints.
class SolverRun {
public:
    virtual ~SolverRun() = default;
    virtual Solver& solver() = 0;
    virtual RunParts parts(const RunOptions& o) = 0;  // (write_checkpoint is the caller's)
    virtual LoopClock clock() = 0;
    virtual void open() = 0;                           // a new run's files
    // the run's state after the loop's clock in a checkpoint, and back (a resume: its files reopened)
    virtual void save(BinaryWriter& out, double elapsed) = 0;
    virtual void load(BinaryReader& in, double& elapsed) = 0;
    // the files and the summary of the finished run
    virtual RunSummary finish(const std::string& stop_reason, const std::vector<ScenarioInput>& inputs, double wall_seconds) = 0;
};

// Runs to the stop; returns its reason ("t_max", "max_steps", "rest" or one of after_step's).
// The last instant is sampled once whatever the stop.
std::string run_loop(Solver& solver, RunParts& parts, const Scenario& s, const RunOptions& o, LoopClock clock);

}  // namespace demlab
