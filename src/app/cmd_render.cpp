// demlab render RUN_DIR: replays a finished run's snapshots into PNG frames; demlab plot RUN_DIR.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>

#include "app/commands.h"
#include "core/error.h"
#include "output/frame.h"
#include "core/output_dir.h"
#include "output/plot.h"
#include "output/render_run.h"
#include "output/renderer.h"
#include "core/validate.h"

namespace demlab {

Command add_render_command(CLI::App& app) {
    auto o = std::make_shared<RenderRunOptions>();
    CLI::App* sub = app.add_subcommand("render", "Replay a run's snapshots into PNG frames (off-screen, no display needed)");
    sub->add_option("run_dir", o->run_dir, "A run folder written by demlab run")->required()->check(CLI::ExistingDirectory);
    sub->add_option("--every", o->every, "Seconds of simulated time between frames (from saved snapshots only)")
        ->check(CLI::PositiveNumber);
    sub->add_option("--fps", o->fps, "Frames per simulated second (alternative to --every)")->check(CLI::PositiveNumber);
    sub->add_option("--size", o->size, "Frame size WxH in pixels")->capture_default_str();
    sub->add_option("--color", o->color,
                    "Colouring: layers (initial bands), grid, speed (with a colour bar), rotation (a radial line per disc), "
                    "bonds (the intact bonds as lines, discs by the share of their bonds lost); default bonds for a run "
                    "with bonds, layers otherwise");
    sub->add_option("--view", o->view, "flume (whole flume), barrier (arc and barrier), or x0,y0,x1,y1 in metres")
        ->capture_default_str();
    sub->add_option("--speed-max", o->speed_max, "Top of the speed colour bar, m/s")->capture_default_str();
    sub->add_option("--out", o->out, "Output folder (default RUN_DIR/frames); must not exist unless --force");
    sub->add_flag("--force", o->force, "Replace the files of an existing output folder");
    sub->add_flag("--last", o->last_only, "Render only the final snapshot (the deposit)");
    sub->add_option("--strip", o->strip,
                    "Tile the frames into one PNG, three to a row; without --out (and --video) only this file is "
                    "written, so it can be made beside a run's existing frames")
        ->check([](const std::string& v) { return v.empty() ? std::string("an empty file name") : std::string(); });
    sub->add_flag("--video", o->video, "Also assemble the frames into video.mp4 with ffmpeg (when installed)");
    sub->add_option("--threads", o->threads, "Frames rendered at once (0: one per core, at most 8); the same files for any count")
        ->check(CLI::Range(0, 64))
        ->capture_default_str();
    return [o] {
        render_run(*o);
        return kExitOk;
    };
}

Command add_plot_command(CLI::App& app) {
    auto dir = std::make_shared<std::string>();
    CLI::App* sub = app.add_subcommand("plot", "Plot a run's forces (x, y on path, arc, barrier), front and kinetic energy as PNG");
    sub->add_option("run_dir", *dir, "A run folder written by demlab run")->required()->check(CLI::ExistingDirectory);
    return [dir] {
        for (const auto& p : make_plots(*dir)) std::printf("%s\n", p.c_str());
        return kExitOk;
    };
}

}  // namespace demlab
