// One instant of a run as the renderer sees it, read back from the run's VTK snapshots.
// Frames always come from the files (also when rendering during a run), so a replay draws
// exactly what the run drew.
#pragma once
#include <string>
#include <utility>
#include <vector>

#include "core/vec2.h"

namespace demlab {

struct Frame {
    double time = 0;
    std::vector<Vec2> pos;
    std::vector<double> radius, angle, speed;
    std::vector<int> layer, grid;
    // a run with bonds: per disc its intact and broken bonds, and the intact bonds (disc ids);
    // all empty without bonds
    std::vector<int> bonds_intact, bonds_broken;
    std::vector<std::pair<int, int>> bonds;
    std::vector<std::vector<Vec2>> walls;  // polylines of the walls present
    std::vector<int> wall_id;              // wall index of each polyline
    // drawn on top (analysis figures): polylines in a colour, and text at world positions
    struct Overlay {
        std::vector<Vec2> line;
        double r = 0.8, g = 0.1, b = 0.1;
    };
    std::vector<Overlay> overlays;
    // filled convex polygons drawn under the discs (a continuum run's flow, in sand colour)
    struct Fill {
        std::vector<Vec2> polygon;
        double r = 0.84, g = 0.55, b = 0.24;
    };
    std::vector<Fill> fills;
    std::vector<std::pair<Vec2, std::string>> notes;
};

// Reads snapshots/discs_NNNNN.vtp and walls_NNNNN.vtp. Throws InputError on a malformed file.
Frame read_frame(const std::string& discs_vtp, const std::string& walls_vtp);

// A continuum (DAN) run's frames, one per time of its blocks.csv: the flow as a filled profile
// (the boundary blocks' bed points and the surface H above them: straight up for vertical
// columns, along the bed's normal for normal ones), over the flume's
// walls W1, arc and W3 (ids 0, 1, 2, so the flume's marks are drawn). Throws InputError.
std::vector<Frame> read_dan_frames(const std::string& run_dir);

struct SnapshotEntry {
    double time;
    std::string discs, walls;  // file paths
};
// The snapshots of a run folder, from snapshots/discs.pvd (or by listing when it is missing).
std::vector<SnapshotEntry> list_snapshots(const std::string& run_dir);

}  // namespace demlab
