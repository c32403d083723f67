// demlab run SCENARIO: a flume (or any scenario) from its release to rest.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "app/commands.h"
#include "core/error.h"
#include "core/interrupt.h"
#include "run/checkpoint_file.h"
#include "run/measures.h"
#include "run/run.h"
#include "output/frame.h"
#include "output/image.h"
#include "output/plot.h"
#include "output/render_run.h"
#include "output/terrain_view.h"
#include "scenario/scenario.h"
#include "setups/setup.h"

namespace demlab {

namespace {
struct RunCliOptions {
    std::string scenario;
    int model = 0;
    std::string variant;
    int scale = 0;
    std::string out;
    std::vector<std::string> set;
    std::string release_from;
    bool force = false;
    bool frames = false;
    int threads = 1;
    bool scalar = false;
    bool no_avx512 = false;
    bool no_plots = false;
    double checkpoint_every = 0.0;
    std::string solver;  // empty: the scenario's
    bool out_given = false;
};

// A landmark for the console: its value, or none with the reason (measures.h, not_measured).
std::string landmark(const RunSummary& r, const char* key, double v, const char* unit) {
    const std::string why = not_measured_reason(r, key);
    if (!why.empty()) return "none (" + why + ")";
    char b[64];
    std::snprintf(b, sizeof b, "%.3f %s", v, unit);
    return b;
}

// The landmarks' lines: arrival and peak times where the set-up has a barrier or an arc, then
// run-out and run-up.
void print_landmarks(const RunSummary& r) {
    if (r.has_barrier || r.has_barrier_forces || r.has_arc)
        std::printf("  front at the barrier %s; peak x-force on the barrier %s; peak y-force on the arc %s\n",
                    landmark(r, "t_front_at_barrier", r.t_front_at_barrier, "s").c_str(),
                    landmark(r, "t_peak_fx_barrier", r.t_peak_fx_barrier, "s").c_str(),
                    landmark(r, "t_peak_fy_arc", r.t_peak_fy_arc, "s").c_str());
    if (r.has_path || r.has_envelope) {
        const std::string why = not_measured_reason(r, "deposit_max_height");
        if (why.empty())
            std::printf("  run-out %s; deposit %s high, %s long; %s deep at x = %s\n", landmark(r, "runout_s", r.runout_s, "m").c_str(),
                        landmark(r, "deposit_max_height", r.deposit_max_height, "m").c_str(),
                        landmark(r, "deposit_length", r.deposit_length, "m").c_str(),
                        landmark(r, "deposit_max_depth", r.deposit_max_depth, "m").c_str(),
                        landmark(r, "x_deposit_max_depth", r.x_deposit_max_depth, "m").c_str());
        else  // (DAN: its depth over x, surface.csv, but no height normal to the bed)
            std::printf("  run-out %s; deposit height and length none (%s); %s deep at x = %s\n",
                        landmark(r, "runout_s", r.runout_s, "m").c_str(), why.c_str(),
                        landmark(r, "deposit_max_depth", r.deposit_max_depth, "m").c_str(),
                        landmark(r, "x_deposit_max_depth", r.x_deposit_max_depth, "m").c_str());
    }
    if (r.has_barrier_forces) {
        // the barrier's design loads (docs/barrier-loads.md): each figure, or none with its reason
        auto figure = [&](const char* key, double v, const char* format) {
            const std::string why = not_measured_reason(r, key);
            if (!why.empty()) return "none (" + why + ")";
            char b[64];
            std::snprintf(b, sizeof b, format, v);
            return std::string(b);
        };
        std::printf("  barrier x-load: every-step peak %s, filtered peak %s, static %s\n",
                    figure("peak_fx_barrier", r.peak_fx_barrier, "%.0f N/m").c_str(),
                    figure("peak_fx_barrier_filtered", r.peak_fx_barrier_filtered, "%.0f N/m").c_str(),
                    figure("static_fx_barrier", r.static_fx_barrier, "%.0f N/m").c_str());
        std::printf("  design coefficients: alpha %s, K %s\n", figure("impact_coefficient_alpha", r.impact_coefficient_alpha, "%.2f").c_str(),
                    figure("static_coefficient_k", r.static_coefficient_k, "%.2f").c_str());
    }
    if (r.has_barrier)
        std::printf("  run-up %s (max during run %s)\n", landmark(r, "runup_height", r.runup_height, "m").c_str(),
                    landmark(r, "max_runup_height_during_run", r.max_runup_height_during_run, "m").c_str());
}

}  // namespace

// The lines a finished run prints, and its plots.
int report_run(const Scenario& s, const RunSummary& r, const std::string& dir, bool plots) {
    if (s.solver == "dem3") {
        std::printf("%s (3-D, DEBRIS): %ld spheres, %ld steps to t = %.3f s (%s), dt %.3g-%.3g s, wall time %.1f s, %.3e particle-steps/s\n",
                    s.name.c_str(), r.n_discs, r.steps, r.t_end, r.stop_reason.c_str(), r.dt_min, r.dt_max, r.wall_seconds,
                    r.particle_steps_per_second);
        std::printf("  peak rasters, frames and summary.json in the folder\n");
    } else if (s.solver == "dan") {
        std::printf("%s (DAN): %d blocks, %ld steps to t = %.3f s (%s), dt %.3g s, wall time %.2f s\n", s.name.c_str(),
                    s.dan.blocks, r.steps, r.t_end, r.stop_reason.c_str(), r.dt, r.wall_seconds);
        print_landmarks(r);
        if (r.runout_lower_bound) std::printf("  the front passed the flume's end: the run-out and run-up are lower bounds\n");
    } else {
    std::printf("%s: %ld discs, model %d, variant %s, %ld steps to t = %.3f s (%s), dt %.3g-%.3g s\n", s.name.c_str(),
                r.n_discs, s.world.rotation.model, s.release.variant.c_str(), r.steps, r.t_end, r.stop_reason.c_str(),
                r.dt_min, r.dt_max);
    std::printf("  wall time %.1f s, %.3e particle-steps/s\n", r.wall_seconds, r.particle_steps_per_second);
    if (make_setup(s)->kind() == "flume")
        std::printf("  porosity %.3f over the release box, %.3f inside the mass\n", r.porosity_over_release_box,
                    r.porosity_inside_mass);
    print_landmarks(r);
    if (r.left_flume_discs > 0)
        std::printf("  %ld disc%s (%.4g kg/m) left the bed path from t = %.3f s: the run-out and run-up are lower bounds\n",
                    r.left_flume_discs, r.left_flume_discs == 1 ? "" : "s", r.left_flume_mass, r.t_left_flume);
    else if (r.runout_lower_bound)
        std::printf("  the deposit reaches the end of the bed path: the run-out is a lower bound\n");
    if (r.lost_discs > 0)
        std::printf("  %ld disc%s left the domain and %s taken out (lost.csv; world.lost_discs)\n", r.lost_discs,
                    r.lost_discs == 1 ? "" : "s", r.lost_discs == 1 ? "was" : "were");
    std::printf("  energy ledger closes to %.2f %% of the energy put in\n", 100.0 * r.energy_balance_error);
    }
    std::printf("  wrote %s/\n", dir.c_str());
    if (plots) {
        if (gnuplot_available()) {
            make_plots(dir);
            std::printf("  plots in %s/plots/\n", dir.c_str());
        } else {
            std::printf("  no plots: gnuplot is not installed (apt-get install gnuplot-nox)\n");
        }
    }
    return kExitOk;
}

// A run (new or resumed) with its frames: the DEM's as each snapshot is written, DAN's from its
// blocks.csv after the run; then its report.
int run_with_frames(const Scenario& s, RunOptions& ro) {
    if (s.solver == "dem3") attach_terrain_pictures(ro);
    else if (ro.frames && s.solver != "dan") attach_frame_hook(ro, make_setup(s)->kind() == "flume");
    const RunSummary r = run_scenario(s, ro);
    if (ro.frames && s.solver == "dan") {
        RenderRunOptions frames;
        frames.run_dir = ro.out_dir;
        frames.force = ro.force;
        render_run(frames);
    }
    return report_run(s, r, ro.out_dir, ro.plots);
}

namespace {

int run_command(const RunCliOptions& o) {
    // (CLI11's range checks let NaN through: every comparison with it is false)
    if (!std::isfinite(o.checkpoint_every)) throw InputError("--checkpoint-every nan: must be seconds in [0, 1e7]");
    if (o.out_given && o.out.empty()) throw InputError("--out '': an output folder needs a name");
    Scenario s = load_scenario(o.scenario);
    // an option and a --set of the key it sets: which one was meant is not ours to guess
    const std::pair<bool, const char*> option_keys[] = {{o.model != 0, "rotation.model"}, {!o.variant.empty(), "release.variant"},
                                                       {o.scale != 0, "release.scale"}, {!o.solver.empty(), "scenario.solver"},
                                                       {!o.release_from.empty(), "release.from_file"}};
    const char* option_names[] = {"--model", "--variant", "--scale", "--solver", "--release-from"};
    for (const std::string& a : o.set) {
        const size_t eq = a.find('=');
        std::string key = a.substr(0, eq);
        while (!key.empty() && (key.back() == ' ' || key.back() == '\t')) key.pop_back();
        while (!key.empty() && (key.front() == ' ' || key.front() == '\t')) key.erase(key.begin());
        for (size_t k = 0; k < std::size(option_keys); ++k)
            if (option_keys[k].first && key == option_keys[k].second)
                throw InputError(std::string(option_names[k]) + " and --set " + a + " both set " + option_keys[k].second +
                                 ": give it once");
    }
    if (o.model) apply_override(s, "rotation.model=" + std::to_string(o.model));
    if (!o.variant.empty()) apply_override(s, "release.variant=\"" + o.variant + "\"");
    if (o.scale) apply_override(s, "release.scale=" + std::to_string(o.scale));
    // a path typed on the command line is the working directory's; kept absolute, so the run
    // folder's scenario.toml (and a resume from another directory) reads the same file
    if (!o.release_from.empty())
        s.release.from_file = std::filesystem::absolute(o.release_from).lexically_normal().string();
    for (const std::string& a : o.set) apply_override(s, a);
    if (!o.solver.empty()) apply_override(s, "scenario.solver=\"" + o.solver + "\"");
    finish_scenario(s);
    // the release options apply to a generated release mass (a [flume], [dam_break] or a
    // terrain's release polygon): on explicit discs or a lattice they would be silently unused
    const std::string no_box = s.lattice_release.enabled ? ": its discs are a [lattice_release] (lattice_release.r_min, r_max)"
                                                         : ": its discs are given ([[discs]]), not generated in a release box";
    if (o.scale && (!has_release(s) || s.lattice_release.enabled))
        throw InputError("--scale does not apply to " + o.scenario + no_box);
    if (!o.variant.empty() && !s.flume.enabled)
        throw InputError("--variant does not apply to " + o.scenario + ": the variants are a [flume]'s gate (removed, or lifted)");
    if (s.solver == "dan" && (o.model || !o.release_from.empty() || o.scale || !o.variant.empty()))
        throw InputError(std::string("--solver dan: ") +
                         (o.model                   ? "--model (the rotation models are the discs')"
                          : !o.release_from.empty() ? "--release-from (DAN fills the release box itself)"
                          : o.scale                 ? "--scale (the discs' size; DAN's resolution is dan.blocks)"
                                                    : "--variant (the gate's removal; DAN releases at once)") +
                         " does not apply to the continuum model");
    s.world.threads = o.threads;
    s.world.simd = !o.scalar;
    s.world.avx512 = !o.no_avx512;
    RunOptions ro;
    ro.out_dir = o.out.empty() ? "runs/" + s.name : o.out;
    ro.force = o.force;
    ro.checkpoint_every = o.checkpoint_every;
    ro.handle_signals = true;
    ro.frames = o.frames;
    ro.plots = !o.no_plots;
    return run_with_frames(s, ro);
}
}  // namespace

Command add_run_command(CLI::App& app) {
    auto o = std::make_shared<RunCliOptions>();
    CLI::App* sub = app.add_subcommand("run", "Run a scenario (a flume geometry, or explicit walls and discs) to rest");
    sub->add_option("scenario", o->scenario, "Scenario file (TOML), e.g. scenarios/geometry-A.toml")->required();
    sub->add_option("--model", o->model, "Rotation model: 1 locked, 2 rolling resistance, 3 plus rotational damping")
        ->check(CLI::Range(1, 3));
    sub->add_option("--variant", o->variant, "Release: I deletes the gate at t = 0, II lifts it at 2.25 m/s")
        ->check(CLI::IsMember({"I", "II"}));
    sub->add_option("--scale", o->scale, "Upscaling of the sand (Table 14: 2, 4, 20): radii [0.25, 0.5] mm times this")
        ->check(CLI::Range(1, 100));
    CLI::Option* out = sub->add_option("--out", o->out, "Output folder (default runs/<scenario name>); must not exist unless --force");
    sub->add_option("--solver", o->solver, "dem (the discs, default) or dan (the continuum model on the flume's path; scenario.solver)")
        ->check(CLI::IsMember({"dem", "dan"}));
    sub->add_option("--set", o->set, "Override a scenario key: --set key=value (repeatable), e.g. --set material.friction_disc_deg=16");
    sub->add_option("--release-from", o->release_from, "Start from a settled release mass (release.csv of an earlier run)");
    sub->add_flag("--force", o->force, "Replace the files of an existing output folder");
    sub->add_option("--threads", o->threads, "Worker threads (results are the same bits for any count)")
        ->capture_default_str()->check(CLI::Range(1, 64));
    sub->add_flag("--scalar", o->scalar, "Use the scalar loops (pair forces, integration) even if the CPU has AVX2 (the same bits; for comparison)");
    sub->add_flag("--no-avx512", o->no_avx512, "Run the pair law four pairs and the integration four discs at a time (AVX2) even if the CPU has AVX-512 (the same bits; for comparison)");
    sub->add_flag("--frames", o->frames, "Render a PNG frame at every snapshot while running (RUN_DIR/frames)");
    sub->add_flag("--no-plots", o->no_plots, "Do not make the plots (RUN_DIR/plots) at the end");
    sub->add_option("--checkpoint-every", o->checkpoint_every,
                    "Write RUN_DIR/checkpoint.bin every this many seconds of wall-clock time (0: only on SIGINT/SIGTERM)")
        ->check(CLI::Range(0.0, 1.0e7));
    return [o, out] {
        o->out_given = out->count() > 0;
        return run_command(*o);
    };
}

namespace {
struct ResumeCliOptions {
    std::string dir;
    int threads = 1;
    bool scalar = false;
    bool no_avx512 = false;
    double checkpoint_every = -1.0;
};

int resume_command(const ResumeCliOptions& o) {
    namespace fs = std::filesystem;
    const std::string dir = o.dir;
    // (CLI11's range check lets nan through, as for run's option)
    if (std::isnan(o.checkpoint_every)) throw InputError("--checkpoint-every nan: must be seconds in [0, 1e7]");
    if (!fs::is_directory(dir)) throw InputError(dir + ": no such run folder");
    const std::string scenario_file = dir + "/scenario.toml";
    if (!fs::exists(scenario_file)) throw InputError(dir + ": not a run folder (no scenario.toml)");
    const bool has_checkpoint = fs::exists(dir + "/" + kCheckpointFile);
    if (!has_checkpoint && fs::exists(dir + "/summary.json"))
        throw InputError(dir + ": the run has finished already (summary.json); there is nothing to resume");
    Scenario s = load_run_folder_scenario(dir);
    s.world.threads = o.threads;
    s.world.simd = !o.scalar;
    s.world.avx512 = !o.no_avx512;
    RunOptions ro;
    ro.out_dir = dir;
    ro.handle_signals = true;
    if (has_checkpoint) {
        const CheckpointInfo info = read_checkpoint_info(dir);
        ro.resume = true;
        ro.checkpoint_every = o.checkpoint_every >= 0 ? o.checkpoint_every : info.checkpoint_every;
        ro.frames = info.frames;
        ro.plots = info.plots;
        std::fprintf(stderr, "resuming %s at t = %.4f s of %.4f s (step %ld)\n", dir.c_str(), info.time, info.t_max,
                     info.steps);
    } else {
        // stopped before its first checkpoint (or in the release generation): the same
        // scenario and seed from the start give the same run
        ro.force = true;
        ro.rerun = true;
        ro.checkpoint_every = std::max(0.0, o.checkpoint_every);
        ro.frames = fs::exists(dir + "/frames");
        std::fprintf(stderr, "%s has no checkpoint: running it again from the start (same scenario and seed)\n", dir.c_str());
    }
    return run_with_frames(s, ro);
}
}  // namespace

Command add_resume_command(CLI::App& app) {
    auto o = std::make_shared<ResumeCliOptions>();
    CLI::App* sub = app.add_subcommand(
        "resume", "Continue an interrupted run from RUN_DIR/checkpoint.bin (outputs byte-identical to an uninterrupted run)");
    sub->add_option("run_dir", o->dir, "The run folder (its scenario.toml and checkpoint.bin)")->required();
    sub->add_option("--threads", o->threads, "Worker threads (results are the same bits for any count)")
        ->capture_default_str()->check(CLI::Range(1, 64));
    sub->add_flag("--scalar", o->scalar, "Use the scalar loops (pair forces, integration) even if the CPU has AVX2 (the same bits; for comparison)");
    sub->add_flag("--no-avx512", o->no_avx512, "Run the pair law four pairs and the integration four discs at a time (AVX2) even if the CPU has AVX-512 (the same bits; for comparison)");
    sub->add_option("--checkpoint-every", o->checkpoint_every,
                    "Seconds of wall-clock time between checkpoints (default: as the run was started)")
        ->check(CLI::Range(0.0, 1.0e7));
    return [o] { return resume_command(*o); };
}

Command add_keys_command(CLI::App& app) {
    CLI::App* sub = app.add_subcommand("keys", "Print the scenario reference: every key with its unit, default and range");
    (void)sub;
    return [] {
        std::fputs(scenario_reference_markdown().c_str(), stdout);
        return kExitOk;
    };
}

}  // namespace demlab
