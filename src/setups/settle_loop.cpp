#include "setups/settle_loop.h"

#include <cmath>
#include <limits>

#include "core/error.h"
#include "core/interrupt.h"
#include "run/run_loop.h"
#include "run/solver.h"
#include "setups/settle_chunk.h"

namespace demlab {

std::string step_through_loop(World& w, const Scenario& s, const std::string& interrupted,
                              const std::function<std::string()>& after_step) {
    // the loop's own stops out of the way: no rest watch, no step limit, no series; its t_max a
    // billion of the present steps ahead (the caller's rule stops it)
    Scenario loop_s = s;
    loop_s.stop.t_max = w.time() + 1e9 * w.dt();
    loop_s.stop.max_steps = 0;
    loop_s.stop.rest_ke_fraction = 0.0;
    loop_s.output.series_interval = std::numeric_limits<double>::infinity();
    RunOptions o;
    o.handle_signals = true;
    RunParts parts;
    parts.sample = [] {};
    parts.after_step = after_step;
    parts.write_checkpoint = [&] { throw Interrupted(interrupted); };
    parts.watch_steps = 200;
    parts.show_progress = false;  // the generator shows its own
    double next_series = std::numeric_limits<double>::infinity(), next_snap = next_series, peak_ke = 0.0, rest_since = -1.0;
    DemSolver solver(w);
    return run_loop(solver, parts, loop_s, o, LoopClock{next_series, next_snap, peak_ke, rest_since});
}

SettleResult settle_through_loop(World& w, const Scenario& s, const SettleRule& rule) {
    SettleResult result;
    if (!(w.time() < rule.t_end)) return result;
    long check_at = w.step_count() + settle_chunk(w, rule.t_end, rule.chunk);
    step_through_loop(w, s, rule.interrupted, [&]() -> std::string {
        if (w.step_count() != check_at) return "";
        result.ratio = w.unbalanced_force_ratio();
        if (rule.on_check) rule.on_check(w.time(), w.step_count(), result.ratio);
        if (w.time() > rule.min_time && w.step_count() >= rule.min_steps && result.ratio < rule.ratio) {
            result.settled = true;
            return "settled";
        }
        if (!(w.time() < rule.t_end)) return "t_end";
        check_at = w.step_count() + settle_chunk(w, rule.t_end, rule.chunk);
        return "";
    });
    return result;
}

}  // namespace demlab
