#include "run/run_loop.h"

#include <chrono>

#include "core/error.h"
#include "core/interrupt.h"
#include "core/process.h"
#include "core/progress.h"
#include "core/validate.h"

namespace demlab {

std::string run_loop(Solver& solver, RunParts& parts, const Scenario& s, const RunOptions& o, LoopClock c) {
    const long steps_start = solver.step_count();
    Progress progress(s.stop.t_max, "s", solver.time(), steps_start, parts.show_progress);
    const auto t0 = std::chrono::steady_clock::now();
    // (the first progress call comes at once, at the first check: a script sees the run start,
    // and a run shorter than the call interval still reports while it runs)
    auto last_checkpoint = t0, last_progress_call = t0 - std::chrono::milliseconds(250);
    auto steps_per_second = [&] {
        const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        return secs > 0 ? double(solver.step_count() - steps_start) / secs : 0.0;
    };
    std::string stop = "t_max";
    // whether the series were sampled at the current time (the last row is not written twice
    // when the run ends at a sample time)
    bool sampled_now = false;
    while (true) {
        if (solver.time() >= c.next_series - 1e-12) {
            parts.sample();
            // (a step longer than the interval: the next sample after it, not one per step)
            do c.next_series += s.output.series_interval;
            while (c.next_series <= solver.time() - 1e-12);
            sampled_now = true;
        }
        if (parts.snapshot && solver.time() >= c.next_snap - 1e-12) {
            parts.snapshot();
            do c.next_snap += s.output.snapshot_interval;
            while (c.next_snap <= solver.time() - 1e-12);
        }
        if (solver.time() >= s.stop.t_max) break;
        if (s.stop.max_steps > 0 && solver.step_count() >= s.stop.max_steps) {
            stop = "max_steps";
            break;
        }
        try {
            solver.step();
        } catch (const RunError&) {
            if (parts.step_failed) parts.step_failed();
            throw;
        }
        sampled_now = false;
        if (std::string why = parts.after_step(); !why.empty()) {
            stop = why;
            break;
        }
        // a step so small that the run would not end in any time is refused at once
        if (solver.step_count() == steps_start + 1 && (s.stop.t_max - solver.time()) / solver.dt() > kMaxRunSteps)
            throw RunError(s.source + ": the run would take " + format_number((s.stop.t_max - solver.time()) / solver.dt()) +
                           " steps of " + format_number(solver.dt()) + " s to stop.t_max (more than " + format_number(kMaxRunSteps) +
                           "): the stiffnesses and densities give an absurdly small time step");
        if (solver.step_count() % parts.watch_steps == 0) {
            if (parts.watch) parts.watch();
            const double ke = solver.kinetic_energy();
            c.peak_ke = std::max(c.peak_ke, ke);
            if (c.peak_ke > 0.0 && ke < s.stop.rest_ke_fraction * c.peak_ke) {
                if (c.rest_since < 0) c.rest_since = solver.time();
                if (solver.time() - c.rest_since >= s.stop.rest_duration) {
                    stop = "rest";
                    break;
                }
            } else {
                c.rest_since = -1;
            }
            progress.update(solver.time(), solver.step_count());
            if (o.on_progress) {
                const auto now = std::chrono::steady_clock::now();
                if (now - last_progress_call >= std::chrono::milliseconds(250)) {
                    last_progress_call = now;
                    o.on_progress(solver.time(), s.stop.t_max, steps_per_second());
                }
            }
        }
        if (const int sig = o.handle_signals ? pending_interrupt() : 0) {
            progress.finish();
            parts.write_checkpoint();
            throw Interrupted("signal " + std::to_string(sig) + " at t = " + format_number(solver.time()) + " s (step " +
                              std::to_string(solver.step_count()) + "): checkpoint written; continue with: demlab resume " + shell_word(o.out_dir));
        }
        if (o.checkpoint_every > 0 && solver.step_count() % 10 == 0) {
            const auto now = std::chrono::steady_clock::now();
            if (std::chrono::duration<double>(now - last_checkpoint).count() >= o.checkpoint_every) {
                parts.write_checkpoint();
                last_checkpoint = now;
            }
        }
    }
    progress.finish();
    if (o.on_progress) o.on_progress(solver.time(), s.stop.t_max, steps_per_second());
    if (!sampled_now) parts.sample();
    return stop;
}

}  // namespace demlab
