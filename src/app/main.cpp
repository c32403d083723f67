// demlab: a discrete-element laboratory for rapid granular flows.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>

#include "app/commands.h"
#include "core/error.h"
#include "core/interrupt.h"

int main(int argc, char** argv) {
    using namespace demlab;
    CLI::App app{"demlab: a 2D discrete-element laboratory for rapid granular flows (PFC2D linear model)", "demlab"};
    app.require_subcommand(1);
    app.set_version_flag("--version", "demlab 0.1.0");
    std::vector<std::pair<CLI::App*, Command>> commands;
    const auto add = [&](Command (*make)(CLI::App&)) {
        Command c = make(app);
        commands.emplace_back(app.get_subcommands([](CLI::App*) { return true; }).back(), std::move(c));
    };
    add(add_run_command);
    add(add_resume_command);
    add(add_render_command);
    add(add_plot_command);
    add(add_calibrate_command);
    add(add_sweep_command);
    add(add_compare_command);
    add(add_demo_command);
    add(add_keys_command);
    add(add_bench_command);
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        const int rc = app.exit(e);
        return rc == 0 ? kExitOk : kExitUsage;
    }
    try {
        for (auto& [sub, run] : commands)
            if (sub->parsed()) return run();
    } catch (const Interrupted& e) {
        std::fprintf(stderr, "\ndemlab: interrupted: %s\n", e.what());
        return kExitInterrupted;
    } catch (const InputError& e) {
        std::fprintf(stderr, "demlab: input error: %s\n", e.what());
        return kExitInput;
    } catch (const WriteError& e) {
        std::fprintf(stderr, "demlab: cannot write the output: %s\n", e.what());
        return kExitWrite;
    } catch (const RunError& e) {
        std::fprintf(stderr, "demlab: run failed: %s\n", e.what());
        return kExitRun;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "demlab: error: %s\n", e.what());
        return kExitRun;
    }
    return kExitUsage;
}
