// demlab demo: a small built-in dam break, run as any scenario is: a column of discs of 2 to 3
// mm radius, 0.10 m wide and 0.20 m high, generated and settled behind a gate that is removed
// at t = 0, collapses onto a 1 m floor. It writes a run folder as `demlab run` does (the
// resolved scenario.toml, the series, snapshots, summary and plots), so `render`, `plot`,
// `compare` and `resume` take it; `demlab run` of its scenario.toml gives the same bytes.
#include <cstdio>
#include <memory>
#include <string>

#include "app/commands.h"
#include "core/error.h"
#include "core/validate.h"
#include "run/run.h"
#include "scenario/scenario.h"

namespace demlab {

namespace {

constexpr const char* kDemoScenario = R"([scenario]
name = "demo"
description = "demlab demo: a 0.10 m x 0.20 m column of 2-3 mm discs collapsing onto a floor when its gate is removed"
seed = 1

[dam_break]
width = 0.10
height = 0.20
floor_length = 1.0

[release]
r_min = 0.002
r_max = 0.003
variant = "I"

[rotation]
model = 3

[stop]
t_max = 1.0

[output]
series_interval = 0.005
snapshot_interval = 0.02
)";

struct DemoOptions {
    std::string out = "runs/demo";
    bool force = false;
    double t_end = 1.0;
    int model = 3;
    std::string seed = "1";  // as typed: scenario.seed's parser checks it (a number option
                             // would wrap "-1", or saturate 99999999999999999999, unseen)
    int threads = 1;
    bool no_plots = false;
};

// An option's value into its key; a refusal names the option.
void set_from_option(Scenario& s, const std::string& option, const std::string& key, const std::string& value) {
    try {
        apply_override(s, key + "=" + value);
    } catch (const InputError& e) {
        throw InputError("demo " + option + " " + value + ": " + e.what());
    }
}

int demo(const DemoOptions& o) {
    Scenario s = parse_scenario(kDemoScenario, "demo (built in)");
    set_from_option(s, "--t-end", "stop.t_max", format_number(o.t_end));
    // a short demo still stops by time: the rest test's window at most half of it
    if (s.stop.rest_duration >= 0.5 * o.t_end) s.stop.rest_duration = 0.5 * o.t_end;
    set_from_option(s, "--model", "rotation.model", std::to_string(o.model));
    set_from_option(s, "--seed", "scenario.seed", o.seed);
    finish_scenario(s);
    s.world.threads = o.threads;
    RunOptions ro;
    ro.out_dir = o.out;
    ro.force = o.force;
    ro.handle_signals = true;
    ro.plots = !o.no_plots;
    const RunSummary r = run_scenario(s, ro);
    return report_run(s, r, ro.out_dir, ro.plots);
}

}  // namespace

Command add_demo_command(CLI::App& app) {
    auto opts = std::make_shared<DemoOptions>();
    CLI::App* sub = app.add_subcommand("demo", "A small built-in dam break, run into a run folder as `demlab run` writes one");
    sub->add_option("--out", opts->out, "Output folder (must not exist unless --force)")->capture_default_str();
    sub->add_flag("--force", opts->force, "Replace the files of an existing output folder");
    sub->add_option("--t-end", opts->t_end, "Simulated time after the gate is removed, s (stop.t_max)")->capture_default_str();
    sub->add_option("--model", opts->model, "Rotation model 1, 2 or 3")->capture_default_str()->check(CLI::Range(1, 3));
    sub->add_option("--seed", opts->seed, "Seed of the column's disc radii and positions")->capture_default_str();
    sub->add_option("--threads", opts->threads, "Worker threads (the same bits for any count)")
        ->capture_default_str()
        ->check(CLI::Range(1, 64));
    sub->add_flag("--no-plots", opts->no_plots, "Do not make the plots (RUN_DIR/plots) at the end");
    return [opts] { return demo(*opts); };
}

}  // namespace demlab
