// Generating and settling a mass before t = 0 (the release's radius expansion and its two
// settling phases, the lattice) through the run loop (run/run_loop.h): each is a stop rule
// there, with the loop's stepping and interruption and the generator's progress.
#pragma once
#include <functional>
#include <string>

#include "dem/world.h"
#include "scenario/scenario.h"

namespace demlab {

struct SettleRule {
    double t_end = 0.0;        // s, settling stops here whether settled or not
    double ratio = 0.0;        // settled: the unbalanced force ratio below this ...
    double min_time = 0.02;    // s, ... after this much settling
    long min_steps = 0;        // ... and this many steps
    long chunk = 200;          // steps between two checks (settle_chunk)
    std::string interrupted;   // the Interrupted message (settling is not checkpointed)
    // after each check: the time, the steps and the ratio (progress; may throw to refuse)
    std::function<void(double t, long steps, double ratio)> on_check;
};

struct SettleResult {
    bool settled = false;
    double ratio = 0.0;  // the last check's
};

// Steps w (finalized) through the run loop until after_step, called after every step, names a
// stop; the loop's own stops (time, rest, series) out of the way. An interrupt ends it with
// Interrupted(interrupted): a generation is not checkpointed.
std::string step_through_loop(World& w, const Scenario& s, const std::string& interrupted,
                              const std::function<std::string()>& after_step);

// Steps w through the run loop until the rule's ratio or t_end, checking every chunk of
// steps (settle_chunk: the last chunk no longer than t_end asks), as the generators' own loops
// did: the same steps, so the same bits.
SettleResult settle_through_loop(World& w, const Scenario& s, const SettleRule& rule);

}  // namespace demlab
