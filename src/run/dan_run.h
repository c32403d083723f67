// `demlab run` with scenario.solver = "dan": the continuum model (dan/) on a flume's path,
// into the same run folder as a DEM run where the quantity exists (docs/spec/DAN.md section
// 2, "Outputs"): scenario.toml, front.csv (t, s_front, displacement, s_tail, v_front),
// forces.csv (the DEM's columns: the bed's load on slope, arc and barrier), energy.csv (t,
// kinetic, potential, dissipated_friction, other, balance), blocks.csv (every block at each
// snapshot interval), deposit.csv (s, height, block_height), surface.csv (the DEM's columns:
// the deposit over x), front_synced.csv (with
// dan.sync_front) and summary.json. run_scenario takes it through the folder, the run loop
// and its checkpoints as it does the discs.
#pragma once
#include "dan/dan_solver.h"
#include <memory>

#include "run/run.h"
#include "run/run_loop.h"

namespace demlab {

// A DAN scenario's run for the loop, its set-up checked (every refusal here, before the
// run folder is touched).
std::unique_ptr<SolverRun> make_dan_run(const Scenario& s, const RunOptions& o);

// The solver of a flume scenario's DAN run at t = 0 (its path from the world-joined walls, its
// release from the release box), without a run folder: tests and scripting.
DanSolver dan_of_scenario(const Scenario& s);

// A flume scenario's path (W1, arc, W3) as the DEM world joins its walls.
DanPath flume_dan_path(const Scenario& s);

// surface.csv of a DAN run (x_m, bed_m, surface_m, depth_m, as a DEM run's): the free surface
// through the boundary blocks' points p(S_k) + H_k n(S_k), over x every dx of the path's
// span; its deepest sample into sum (deposit_max_depth, x_deposit_max_depth).
std::string dan_surface(const DanSolver& dan, double dx, RunSummary& sum);

}  // namespace demlab
