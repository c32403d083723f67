// What a contact law owns beyond its force, with the defaults a law inherits when it has
// nothing of its own to say (LinearLaw takes them all). The engine asks the chosen law
// (contact_laws.h's dispatch) and never branches on which law it is.
//
//   kName, kSummary  its contact.law name and the key's text for it (every law says its own)
//   Def              the law's own keys' values ([kSection] of a scenario; WorldDef::law_def)
//   kSection         the scenario section of its keys ("" : none)
//   keys(add)        its keys, with unit, default (Def's), range and text, added to the
//                    registry through add.real / add.choice (scenario/key_registry.cpp)
//   kUnusedKeys      the shared keys it does not read (a prefix ends in '.' or '_'): set
//                    away from their defaults they are refused, naming kUnusedWhy
//   validate         its checks of a world definition (programmatic worlds too)
//   fill_tables      its parameters that come from Def rather than from the materials
//   kTranslationOnly no rotation and no dashpots: the step rule's damping factors are 1
//   kCentredDashpots whether timestep.dashpots = "centred" applies (centred_dashpots.cpp)
//   first_dt         the step the first force pass assumes (0: none)
//   step_from_rule   the step from the rule's smallest squared critical step (timestep.h)
#pragma once
#include <algorithm>
#include <array>
#include <cmath>

#include "core/vec2.h"

namespace demlab {

struct LawDefaults {
    struct Def {};
    static constexpr const char* kSection = "";
    template <typename Add>
    static void keys(Add&) {}
    static constexpr std::array<const char*, 0> kUnusedKeys{};
    static constexpr const char* kUnusedWhy = "";
    template <typename Own, typename WorldDefT>
    static void validate(const Own&, const WorldDefT&) {}
    template <typename Tables, typename Own>
    static void fill_tables(Tables&, const Own&) {}
    static constexpr bool kTranslationOnly = false;
    static constexpr bool kCentredDashpots = false;
    template <typename Own>
    static double first_dt(const Own&) {
        return 0.0;
    }
    // PFC's rule: safety times the smallest critical step; `fixed` when there are no discs
    template <typename Own>
    static double step_from_rule(const Own&, double safety, double fixed, double best_sq, double /*last_dt*/) {
        if (!std::isfinite(best_sq)) return fixed;
        return safety * std::sqrt(best_sq);
    }
};

// For a law whose stiffness grows with the overlap (DebrisLaw, HertzLaw): the rule capped by a
// ceiling, which a disc without contacts takes, shrinking at once and growing by at most
// `growth` a step (a step that follows the stiffness of the moment breaks the leapfrog's
// symplectic structure; debris_law.h measures it).
inline double capped_growing_step(double ceiling, double growth, double safety, double best_sq, double last_dt) {
    const double rule = std::isfinite(best_sq) ? safety * std::sqrt(best_sq) : INFINITY;
    return std::min({ceiling, rule, last_dt > 0.0 ? growth * last_dt : INFINITY});
}

// For a law whose open contacts closing in count for the step (kStepAhead): an open pair's
// stiffness ahead from its squared distance. Most open candidates are farther apart than they
// can close in Law::kAheadSteps steps, which a bound without a square root or a division
// shows (|vn| <= |vrel| <= |vx| + |vy|); they have k = 0 without the normal.
template <typename Law>
double closing_pair_stiffness(const typename Law::Params& p, double dist2, double rsum, const Vec2& dx, const Vec2& vrel,
                              double dt, double ri, double rj) {
    const double reach = rsum + Law::kAheadSteps * dt * (std::abs(vrel.x()) + std::abs(vrel.y()));
    if (dist2 >= reach * reach) return 0.0;
    const double dist = std::sqrt(dist2);
    return Law::k_ahead(p, dist - rsum, vrel.dot(dx) / dist, dt, ri, rj);
}

}  // namespace demlab
