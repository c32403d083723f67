// Snapshots of a run as VTK XML PolyData (.vtp: the arrays appended as zlib-compressed raw
// binary, or as text with output.snapshot_format = "ascii"), one file for the discs and one for the
// walls per instant, indexed by ParaView collections (discs.pvd, walls.pvd). Discs are points
// with radius, velocity, angle, omega, speed, layer, grid and id; open them in ParaView with
// "Point Gaussian" scaled by radius. A run with bonds adds per disc its intact and broken
// bonds (bonds_intact, bonds_broken) and the intact bonds as line cells between the centres
// (ParaView draws them with the "Wireframe" or "Surface" representation). The same files are
// what `demlab render` replays.
#pragma once
#include <string>
#include <vector>

#include "dem/world.h"

namespace demlab {

class SnapshotWriter {
public:
    // dir is created; layer and grid are per-disc colour tags (may be empty); binary: the
    // arrays appended raw and zlib-compressed (output.snapshot_format), else as text.
    SnapshotWriter(std::string dir, std::vector<int> layer, std::vector<int> grid, bool binary = true);
    void write(const World& w);
    // Writes the .pvd collections (call at the end; also safe to call repeatedly).
    void finish();
    int count() const { return int(times_.size()); }
    // the instants written so far (checkpoints) and their restoration
    const std::vector<double>& times() const { return times_; }
    void restore_times(std::vector<double> t) { times_ = std::move(t); }
    // the files of the last snapshot written
    std::string last_discs() const;
    std::string last_walls() const;

private:
    std::string dir_;
    std::vector<int> layer_, grid_;
    std::vector<double> times_;
    bool binary_;
};

}  // namespace demlab
