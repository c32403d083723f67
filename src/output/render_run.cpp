#include "output/render_run.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <functional>
#include <filesystem>
#include <memory>
#include <sstream>
#include <system_error>
#include <thread>
#include <vector>

#include "core/error.h"
#include "output/frame.h"
#include "output/image.h"
#include "core/output_dir.h"
#include "core/process.h"
#include "output/renderer.h"
#include "core/validate.h"

namespace demlab {

namespace {

void parse_size(const std::string& s, RenderStyle& st) {
    int w = 0, h = 0;
    char x = 0;
    std::istringstream in(s);
    if (!(in >> w >> x >> h) || x != 'x' || !(in >> std::ws).eof())
        throw InputError("--size '" + s + "': expected WxH, e.g. 1280x720");
    st.width = w;
    st.height = h;
}

void parse_view(const std::string& v, const Frame& first, RenderStyle& st) {
    if (v == "flume") return;  // fit all walls
    if (v == "barrier") {
        Vec2 lo(INFINITY, INFINITY), hi(-INFINITY, -INFINITY);
        for (size_t k = 0; k < first.walls.size(); ++k)
            if (first.wall_id[k] == 1 || first.wall_id[k] == 2)
                for (const Vec2& p : first.walls[k]) {
                    lo = lo.cwiseMin(p);
                    hi = hi.cwiseMax(p);
                }
        if (!std::isfinite(lo.x())) throw InputError("--view barrier: the run has no flume arc and barrier (walls 1, 2)");
        st.view_set = true;
        st.view_lo = lo - Vec2(0.25, 0.05);
        st.view_hi = hi + Vec2(0.05, 0.05);
        return;
    }
    double x0, y0, x1, y1;
    char c1, c2, c3;
    std::istringstream in(v);
    if (!(in >> x0 >> c1 >> y0 >> c2 >> x1 >> c3 >> y1) || c1 != ',' || c2 != ',' || c3 != ',' || !(x1 > x0) || !(y1 > y0))
        throw InputError("--view '" + v + "': expected flume, barrier or x0,y0,x1,y1 (m) with x1 > x0 and y1 > y0");
    st.view_set = true;
    st.view_lo = Vec2(x0, y0);
    st.view_hi = Vec2(x1, y1);
}

// The strip's file: a new PNG, or (--force) one that is not a file the run or the frames'
// folder holds.
void check_strip_path(const RenderRunOptions& o, const std::string& out) {
    if (o.strip.empty()) return;
    std::error_code ec;
    if (std::filesystem::is_directory(o.strip, ec)) throw InputError("--strip " + o.strip + ": is a folder; give a PNG file");
    // the folder it goes into exists before a single frame is rendered
    const std::filesystem::path parent = std::filesystem::absolute(o.strip, ec).parent_path();
    if (!std::filesystem::is_directory(parent, ec))
        throw InputError("--strip " + o.strip + ": its folder " + parent.string() + " does not exist");
    if (!out.empty() && path_within(o.strip, out))
        throw InputError("--strip " + o.strip + ": lies inside the frames' folder " + out + "; give a file outside it");
    if (!std::filesystem::exists(o.strip, ec)) return;
    if (!o.force) throw InputError("--strip " + o.strip + ": the file exists; choose another name or pass --force to replace it");
    if (path_within(o.strip, o.run_dir))
        throw InputError("--strip " + o.strip + ": is a file of the run " + o.run_dir +
                         " (only a new file inside it may be written); choose another name");
}

int render_chosen(const RenderRunOptions& o, const std::string& out, const RenderStyle& style, const std::string& color,
                  const std::vector<SnapshotEntry>& snaps, const std::vector<size_t>& chosen, double every,
                  const std::function<Frame(size_t)>& frame_at);

}  // namespace

int render_run(const RenderRunOptions& o) {
    if (!(o.every >= 0) || !(o.fps >= 0) || !std::isfinite(o.every) || !std::isfinite(o.fps))
        throw InputError("--every and --fps must be > 0 (finite)");
    if (o.run_dir.empty()) throw InputError("render: a run folder is needed");
    if (o.every > 0 && o.fps > 0) throw InputError("give --every or --fps, not both");
    if (o.threads < 0 || o.threads > 64) throw InputError("--threads " + std::to_string(o.threads) + ": must be 0 to 64");
    // a continuum run draws its frames from blocks.csv, a DEM run from its snapshots
    const bool dan = !std::filesystem::exists(o.run_dir + "/snapshots") && std::filesystem::exists(o.run_dir + "/blocks.csv");
    std::vector<Frame> dan_frames;
    std::vector<SnapshotEntry> snaps;
    if (dan) {
        dan_frames = read_dan_frames(o.run_dir);
        for (const Frame& f : dan_frames) snaps.push_back({f.time, "", ""});
    } else {
        snaps = list_snapshots(o.run_dir);
    }
    auto frame_at = [&](size_t k) { return dan ? dan_frames[k] : read_frame(snaps[k].discs, snaps[k].walls); };
    RenderStyle style = default_render_style(setup_kind_of_run(o.run_dir) == "flume");
    parse_size(o.size, style);
    require_positive("--speed-max", o.speed_max, "m/s");
    style.speed_max = o.speed_max;
    const Frame first = frame_at(0);
    const bool has_bonds = !first.bonds_intact.empty();
    const std::string color = o.color.empty() ? (has_bonds ? "bonds" : "layers") : o.color;
    style.color = parse_color_mode(color);
    if (style.color == ColorMode::Bonds && !has_bonds)
        throw InputError("--color bonds: the snapshots of " + o.run_dir + " hold no bonds (the run had no [cohesion])");
    parse_view(o.view, first, style);
    if (!style.view_set) {
        // one view for the whole sequence: the walls at the first snapshot (a lifting gate
        // would otherwise rescale every frame)
        fit_view(first, style.view_lo, style.view_hi);
        style.view_set = true;
    }
    if (style.width < 16 || style.height < 16 || style.width > 8192 || style.height > 8192)
        throw InputError("--size " + o.size + ": width and height must be in [16, 8192] px");
    // --strip without --out (and no video): the strip alone, no frame files, so a strip can be
    // made beside the frames a run already has (run --frames) without touching them
    const bool strip_only = !o.strip.empty() && o.out.empty() && !o.video;
    const std::string out = strip_only ? std::string() : o.out.empty() ? o.run_dir + "/frames" : o.out;
    // the frames' folder may lie inside the run folder, never be it or hold it
    const std::vector<std::string> inputs{o.run_dir};
    if (!strip_only) check_output_dir(out, o.force, inputs);
    check_strip_path(o, out);

    // which snapshots: all, or one per frame time (never interpolated)
    const double every = o.fps > 0 ? 1.0 / o.fps : o.every;
    std::vector<size_t> chosen;
    if (every <= 0) {
        for (size_t k = 0; k < snaps.size(); ++k) chosen.push_back(k);
    } else {
        // the snapshots' spacing (they fall on the first step past each multiple of the
        // interval, so they drift by up to a step); frames on the grid t0 + k * every take
        // the snapshot within half a spacing of it
        const double spacing = snaps.size() > 1 ? (snaps.back().time - snaps.front().time) / double(snaps.size() - 1) : every;
        if (every < 0.999 * spacing)
            throw InputError(o.run_dir + ": the run saved snapshots every " + format_number(spacing) + " s; frames every " +
                             format_number(every) + " s need snapshots at least that often (output.snapshot_interval)");
        const double t0 = snaps.front().time;
        size_t k = 0;
        for (int f = 0;; ++f) {
            const double target = t0 + f * every;
            while (k < snaps.size() && snaps[k].time < target - 0.5 * spacing) ++k;
            if (k >= snaps.size()) break;
            chosen.push_back(k);
        }
    }
    if (o.last_only && !chosen.empty()) chosen = {chosen.back()};
    // every check done: the folder is made now, and removed again (the old one put back) if
    // the rendering fails, so a failure never blocks the corrected retry
    if (!strip_only) prepare_output_dir(out, o.force, inputs);
    try {
        const int frames = render_chosen(o, out, style, color, snaps, chosen, every, frame_at);
        if (!out.empty()) remove_replaced_output(out);
        return frames;
    } catch (...) {
        if (!out.empty()) abandon_output(out);
        throw;
    }
}

namespace {
int render_chosen(const RenderRunOptions& o, const std::string& out, const RenderStyle& style, const std::string& color,
                  const std::vector<SnapshotEntry>& snaps, const std::vector<size_t>& chosen, double every,
                  const std::function<Frame(size_t)>& frame_at) {
    // Frames are independent: each thread has its own renderer (an OSMesa context is current
    // in one thread only) and takes every threads-th frame. A frame's bytes do not depend on
    // which renderer drew it, so the files are the same for any thread count (test
    // SmallRun.ReplayIsTheSameBytesForAnyThreadCount). Geometry A's 120 frames: 5.1 s on one
    // thread, 3.0 s on two (docs/performance.md).
    const unsigned cores = std::max(1u, std::thread::hardware_concurrency());
    const size_t threads = std::min(chosen.size(), size_t(o.threads > 0 ? unsigned(o.threads) : std::min(cores, 8u)));
    std::vector<Image> tiles(o.strip.empty() ? 0 : chosen.size());
    // each thread stops at its first failing frame; the lowest of those is reported, the
    // error a single thread would have met first
    std::vector<std::exception_ptr> failed(threads);
    std::vector<size_t> failed_frame(threads, SIZE_MAX);
    auto work = [&](size_t t) {
        size_t f = t;
        try {
            Renderer renderer(style);
            for (; f < chosen.size(); f += threads) {
                char name[64];
                std::snprintf(name, sizeof name, "/frame_%05zu.png", f);
                Image img = renderer.render(frame_at(chosen[f]));
                if (!out.empty()) write_png(out + name, img);
                if (!tiles.empty()) tiles[f] = std::move(img);
            }
        } catch (...) {
            failed[t] = std::current_exception();
            failed_frame[t] = f;
        }
    };
    std::vector<std::thread> pool;
    try {
        for (size_t t = 1; t < threads; ++t) pool.emplace_back(work, t);
    } catch (const std::system_error& e) {  // no thread to be had: the frames it was to draw would be missing
        for (std::thread& th : pool) th.join();
        throw RunError(std::string("render: cannot start a thread (") + e.what() + "); try --threads 1");
    }
    if (threads > 0) work(0);
    for (std::thread& th : pool) th.join();
    const size_t first_failed = size_t(std::min_element(failed_frame.begin(), failed_frame.end()) - failed_frame.begin());
    if (threads > 0 && failed[first_failed]) std::rethrow_exception(failed[first_failed]);
    if (!out.empty())
        std::printf("rendered %zu frames (%dx%d, %s) into %s/\n", chosen.size(), style.width, style.height, color.c_str(),
                    out.c_str());
    const int frames = int(chosen.size());
    if (!o.strip.empty() && !tiles.empty()) {
        const int cols = std::min<int>(3, int(tiles.size())), rows = (int(tiles.size()) + cols - 1) / cols;
        Image strip;
        strip.width = cols * style.width;
        strip.height = rows * style.height;
        strip.rgb.assign(size_t(strip.width) * size_t(strip.height) * 3, 255);
        for (size_t t = 0; t < tiles.size(); ++t) {
            const int cx = int(t) % cols, cy = int(t) / cols;
            for (int y = 0; y < style.height; ++y)
                std::copy(tiles[t].at(0, y), tiles[t].at(0, y) + 3 * style.width,
                          strip.at(cx * style.width, cy * style.height + y));
        }
        write_png(o.strip, strip);
        std::printf("strip of %zu frames: %s\n", tiles.size(), o.strip.c_str());
    }
    if (o.video) {
        if (!program_available("ffmpeg")) {
            std::printf("ffmpeg is not installed: the frames are written, but no video was made "
                        "(apt-get install ffmpeg, then rerun with --video)\n");
            return frames;
        }
        const double rate = every > 0 ? 1.0 / every : (snaps.size() > 1 ? 1.0 / (snaps[1].time - snaps[0].time) : 10.0);
        // no shell, in the frames' folder: the file names are ours (a `%` in a user's path would
        // be read as ffmpeg's frame-number pattern)
        ProcessDef ffmpeg;
        ffmpeg.argv = {"ffmpeg", "-loglevel", "error", "-y", "-framerate", format_number(rate), "-i", "frame_%05d.png",
                       "-c:v", "libx264", "-pix_fmt", "yuv420p", "-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2", "video.mp4"};
        ffmpeg.cwd = out;
        ffmpeg.stderr_file = out + "/ffmpeg.log";
        if (run_process(ffmpeg) != 0) throw RunError("ffmpeg failed making " + out + "/video.mp4 (see " + out + "/ffmpeg.log)");
        std::printf("video: %s/video.mp4\n", out.c_str());
    }
    return frames;
}

}  // namespace

void attach_frame_hook(RunOptions& ro, bool flume) {
    // the same look as `demlab render RUN_DIR`, drawn from the snapshot files just written,
    // so replaying the run gives the same bytes
    // the view is fixed by the first snapshot, as in render_run
    auto renderer = std::make_shared<std::unique_ptr<Renderer>>();
    const std::string dir = ro.out_dir;
    ro.on_snapshot = [renderer, dir, flume](const std::string& discs, const std::string& walls, int index) {
        const Frame f = read_frame(discs, walls);
        if (!*renderer) {
            RenderStyle style = default_render_style(flume);
            if (!f.bonds_intact.empty()) style.color = ColorMode::Bonds;
            // a resumed run starts past the first snapshot: its view still comes from that one
            fit_view(index == 0 ? f : read_frame(dir + "/snapshots/discs_00000.vtp", dir + "/snapshots/walls_00000.vtp"),
                     style.view_lo, style.view_hi);
            style.view_set = true;
            *renderer = std::make_unique<Renderer>(style);
        }
        if (!std::filesystem::is_directory(dir + "/frames")) {
            std::filesystem::create_directories(dir + "/frames");
            mark_output_dir(dir + "/frames");
        }
        char name[64];
        std::snprintf(name, sizeof name, "/frames/frame_%05d.png", index);
        write_png(dir + name, (*renderer)->render(f));
    };
}


}  // namespace demlab
