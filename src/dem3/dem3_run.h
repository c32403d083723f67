// `demlab run` with scenario.solver = "dem3": the 3-D solver (world3.h) on its terrain through
// the run loop (run_loop.h), as DAN's run goes: the loop's stops, progress, signals and
// checkpoints; the run's own files:
//   series.csv        t, the ledger, the mass's centre, its largest travel and speed, contacts
//   snapshots/        spheres_NNNN.vtp (radius, velocity), terrain.vtp, spheres.pvd (ParaView)
//   frames/           oblique and map views of the terrain with the spheres (PNG): the last
//                     instant always, every snapshot with --frames
//   peak_thickness.asc, peak_speed.asc, deposit_thickness.asc  AvaFrame's peak fields on the
//                     terrain's grid (peak_rasters.h), and a PNG of each over the hillshade
//   summary.json      counts, volumes, steps, the landmarks of a rock avalanche
#pragma once
#include <memory>

#include "run/run_loop.h"

namespace demlab {

// Everything is read and checked (terrain, top surface, the release's spheres) before the
// run's folder is touched; InputError names what is wrong.
std::unique_ptr<SolverRun> make_dem3_run(const Scenario& s, const RunOptions& o);

}  // namespace demlab
