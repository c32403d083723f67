// The subcommands of the demlab executable. Each registers its options on the CLI11 app and
// returns the callback to run when it was chosen.
#pragma once
#include <CLI/CLI.hpp>
#include <functional>
#include <string>

namespace demlab {

using Command = std::function<int()>;

struct Scenario;
struct RunSummary;
// The lines a finished run prints (its landmarks, or why one was not measured), and its plots
// (cmd_run.cpp; `demlab run`, `resume` and `demo`).
int report_run(const Scenario& s, const RunSummary& r, const std::string& dir, bool plots);

Command add_bench_command(CLI::App& app);
Command add_demo_command(CLI::App& app);
Command add_run_command(CLI::App& app);
Command add_resume_command(CLI::App& app);
Command add_keys_command(CLI::App& app);
Command add_render_command(CLI::App& app);
Command add_plot_command(CLI::App& app);
Command add_calibrate_command(CLI::App& app);
Command add_sweep_command(CLI::App& app);
Command add_compare_command(CLI::App& app);

}  // namespace demlab
