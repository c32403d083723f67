// demlab: a discrete-element laboratory for rapid granular flows.
#include <csignal>
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <exception>

#include "app/commands.h"
#include "core/error.h"
#include "core/interrupt.h"
#include "scenario/key_registry.h"

namespace {

// "Did you mean" for a mistyped subcommand or option, as for a mistyped key: the arguments
// that are neither a subcommand, nor an option of the subcommand given (with or without its
// "=value"), matched to the nearest name. Positional values (a scenario file) are not options.
void suggest_names(const CLI::App& app, int argc, char** argv) {
    std::vector<std::string> commands;
    const CLI::App* sub = nullptr;
    for (const CLI::App* c : app.get_subcommands([](const CLI::App*) { return true; })) {
        commands.push_back(c->get_name());
        if (c->parsed()) sub = c;
    }
    if (!sub) {
        if (argc > 1 && argv[1][0] != '-') {
            const std::string near = demlab::keys::nearest(argv[1], commands);
            if (!near.empty()) std::fprintf(stderr, "demlab: no command '%s'; did you mean '%s'?\n", argv[1], near.c_str());
        }
        return;
    }
    std::vector<std::string> options;
    for (const CLI::Option* o : sub->get_options()) {
        for (const std::string& n : o->get_lnames()) options.push_back("--" + n);
        for (const std::string& n : o->get_snames()) options.push_back("-" + n);
    }
    for (int k = 2; k < argc; ++k) {
        std::string a = argv[k];
        if (a.size() < 2 || a[0] != '-' || a == "--") continue;
        a = a.substr(0, a.find('='));
        if (std::find(options.begin(), options.end(), a) != options.end()) continue;
        const std::string near = demlab::keys::nearest(a, options);
        if (!near.empty())
            std::fprintf(stderr, "demlab %s: no option '%s'; did you mean '%s'?\n", sub->get_name().c_str(), a.c_str(), near.c_str());
    }
}

}  // namespace

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
    // a file size limit (ulimit -f) makes a write fail with EFBIG, which the checked writers
    // report (exit 5, the file named, no cut file under a final name), instead of SIGXFSZ
    // killing the process with a lock and temporary files left behind
    ::signal(SIGXFSZ, SIG_IGN);
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        if (e.get_exit_code() != 0) suggest_names(app, argc, argv);
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
