// Plots of a run folder's CSVs with gnuplot (pngcairo): force in x and y over time for the
// path, the arc and the barrier (thesis Fig. 42/43), the front over time (Fig. 37) and the
// kinetic energy over time.
#pragma once
#include <string>
#include <vector>

namespace demlab {

// True when gnuplot can be run.
bool gnuplot_available();

// Runs gnuplot on `script` (a file name in `dir`, which names only files of that folder) without
// a shell, its messages into dir/gnuplot.log; then checks that every PNG in `pngs` is whole (a
// full disk or a file size limit lets gnuplot end well with a cut file, or none). Throws
// RunError when gnuplot fails, WriteError (exit 5) naming a PNG left cut or missing, which is
// removed first: no cut file stays under a final name.
void run_gnuplot(const std::string& dir, const std::string& script, const std::vector<std::string>& pngs);

// Writes RUN_DIR/plots/{forces_x,forces_y,front,kinetic_energy}.png (those whose CSV exists)
// at width x height px and returns their paths. Throws RunError when gnuplot is missing or fails.
std::vector<std::string> make_plots(const std::string& run_dir, int width = 1000, int height = 600);

}  // namespace demlab
