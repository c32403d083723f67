// demlab run SCENARIO: a flume (or any scenario) from its release to rest.
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "commands.h"
#include "error.h"
#include "run.h"
#include "frame.h"
#include "image.h"
#include "plot.h"
#include "render_run.h"
#include "scenario.h"

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
    bool no_plots = false;
};

int run_command(const RunCliOptions& o) {
    Scenario s = load_scenario(o.scenario);
    if (o.model) apply_override(s, "rotation.model=" + std::to_string(o.model));
    if (!o.variant.empty()) apply_override(s, "release.variant=\"" + o.variant + "\"");
    if (o.scale) apply_override(s, "release.scale=" + std::to_string(o.scale));
    if (!o.release_from.empty()) s.release.from_file = o.release_from;
    for (const std::string& a : o.set) apply_override(s, a);
    finish_scenario(s);
    s.world.threads = o.threads;
    RunOptions ro;
    ro.out_dir = o.out.empty() ? "runs/" + s.name : o.out;
    ro.force = o.force;
    if (o.frames) attach_frame_hook(ro, s.flume.enabled);
    const RunSummary r = run_scenario(s, ro);
    std::printf("%s: %ld discs, model %d, variant %s, %ld steps to t = %.3f s (%s), dt %.3g-%.3g s\n", s.name.c_str(),
                r.n_discs, s.world.rotation.model, s.release.variant.c_str(), r.steps, r.t_end, r.stop_reason.c_str(),
                r.dt_min, r.dt_max);
    std::printf("  wall time %.1f s, %.3e particle-steps/s\n", r.wall_seconds, r.particle_steps_per_second);
    if (s.flume.enabled) {
        std::printf("  porosity %.3f; front at the barrier %.3f s; peak x-force on the barrier %.3f s; peak y-force on the arc %.3f s\n",
                    r.porosity, r.t_front_at_barrier, r.t_peak_fx_barrier, r.t_peak_fy_arc);
        std::printf("  run-out s = %.3f m; run-up %.3f m (max during run %.3f m)\n", r.runout_s, r.runup_height,
                    r.max_runup_height_during_run);
    }
    std::printf("  energy ledger closes to %.2f %% of the dissipated energy\n", 100.0 * r.energy_balance_error);
    std::printf("  wrote %s/\n", ro.out_dir.c_str());
    if (!o.no_plots) {
        if (gnuplot_available()) {
            make_plots(ro.out_dir);
            std::printf("  plots in %s/plots/\n", ro.out_dir.c_str());
        } else {
            std::printf("  no plots: gnuplot is not installed (apt-get install gnuplot-nox)\n");
        }
    }
    return kExitOk;
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
    sub->add_option("--out", o->out, "Output folder (default runs/<scenario name>); must not exist unless --force");
    sub->add_option("--set", o->set, "Override a scenario key: --set key=value (repeatable), e.g. --set material.friction_disc_deg=16");
    sub->add_option("--release-from", o->release_from, "Start from a settled release mass (release.csv of an earlier run)");
    sub->add_flag("--force", o->force, "Replace the files of an existing output folder");
    sub->add_option("--threads", o->threads, "Worker threads (results are the same bits for any count)")
        ->capture_default_str()->check(CLI::Range(1, 64));
    sub->add_flag("--frames", o->frames, "Render a PNG frame at every snapshot while running (RUN_DIR/frames)");
    sub->add_flag("--no-plots", o->no_plots, "Do not make the plots (RUN_DIR/plots) at the end");
    return [o] { return run_command(*o); };
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
