#include "setups/settle_loop.h"

#include <cmath>
#include <limits>

#include "core/error.h"
#include "core/interrupt.h"
#include "run/run_loop.h"
#include "run/solver.h"
#include "setups/settle_chunk.h"

namespace demlab {

SettleResult settle_through_loop(World& w, const Scenario& s, const SettleRule& rule) {
    // the loop's own stops out of the way: no rest watch, no step limit, no series; its t_max
    // beyond anything a chunk can reach (the rule's t_end stops it, at a check)
    Scenario loop_s = s;
    loop_s.stop.t_max = 2.0 * rule.t_end + 1.0;
    loop_s.stop.max_steps = 0;
    loop_s.stop.rest_ke_fraction = 0.0;
    loop_s.output.series_interval = std::numeric_limits<double>::infinity();
    RunOptions o;
    o.handle_signals = true;
    SettleResult result;
    long check_at = w.step_count() + settle_chunk(w, rule.t_end, rule.chunk);
    RunParts parts;
    parts.sample = [] {};
    parts.after_step = [&]() -> std::string {
        if (w.step_count() != check_at) return "";
        result.ratio = w.unbalanced_force_ratio();
        if (rule.on_check) rule.on_check(w.time(), w.step_count(), result.ratio);
        if (w.time() > rule.min_time && result.ratio < rule.ratio) {
            result.settled = true;
            return "settled";
        }
        if (!(w.time() < rule.t_end)) return "t_end";
        check_at = w.step_count() + settle_chunk(w, rule.t_end, rule.chunk);
        return "";
    };
    parts.write_checkpoint = [&] { throw Interrupted(rule.interrupted); };
    parts.watch_steps = int(rule.chunk);
    parts.show_progress = false;  // the generator shows its own (on_check)
    double next_series = std::numeric_limits<double>::infinity(), next_snap = next_series, peak_ke = 0.0, rest_since = -1.0;
    DemSolver solver(w);
    if (w.time() < rule.t_end) run_loop(solver, parts, loop_s, o, LoopClock{next_series, next_snap, peak_ke, rest_since});
    return result;
}

}  // namespace demlab
