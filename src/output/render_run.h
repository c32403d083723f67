// `demlab render RUN_DIR`: replays a run's snapshots into PNG frames (and optionally an MP4),
// and the frame hook of `demlab run --frames`. Frames come from saved snapshots only.
#pragma once
#include <string>

#include "run/run.h"

namespace demlab {

struct RenderRunOptions {
    std::string run_dir;
    std::string out;                // default RUN_DIR/frames
    std::string size = "1280x720";  // WxH px
    std::string color;              // layers, grid, speed, rotation, bonds; empty: bonds for a
                                    // run with bonds, layers otherwise
    std::string view = "flume";     // flume, barrier, or x0,y0,x1,y1 (m)
    double every = 0;               // s between frames; 0 with fps 0: every snapshot
    double fps = 0;                 // frames per simulated second
    double speed_max = 3.0;         // m/s
    bool force = false;
    bool video = false;
    bool last_only = false;         // only the final snapshot
    std::string strip;              // also tile the frames into this one PNG (3 columns)
    int threads = 0;                // renderers working at once, each on every threads-th frame;
                                    // 0: one per core, at most 8 (the same bytes for any count)
};

// Renders the frames; returns the number written. Throws InputError on bad options.
int render_run(const RenderRunOptions& o);

// Makes run_scenario() render a frame (default look: bonds colouring for a run with bonds)
// after every snapshot into OUT/frames.
void attach_frame_hook(RunOptions& ro, bool flume);

}  // namespace demlab
