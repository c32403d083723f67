// Settling through the run loop (setups/settle_loop.h): the rule's checks come every chunk of
// steps and at the time limit, a settled mass stops at once, an unsettled one at t_end, and an
// interrupt ends the generation with the rule's message.
#include <gtest/gtest.h>

#include <csignal>
#include <memory>
#include <utility>
#include <string>

#include "core/binary_io.h"
#include "core/interrupt.h"
#include "dem/world.h"
#include "helpers.h"
#include "scenario/scenario.h"
#include "setups/settle_loop.h"

using namespace demlab;
using namespace demlab::test;

namespace {

// 30 discs dropped into a box 6 cm wide, rotation locked, damped as the release settles
void fill_box(World& w) {
    const int m = w.add_material(material(0.3));
    for (int i = 0; i < 6; ++i)
        for (int j = 0; j < 5; ++j) w.add_disc({Vec2(0.005 + 0.01 * i, 0.005 + 0.011 * j), 0.0045, Vec2::Zero(), 0, 0, m});
    w.add_wall(segment(w, Vec2(0.0, 0.0), Vec2(0.06, 0.0), 0.3));
    w.add_wall(segment(w, Vec2(0.0, 0.0), Vec2(0.0, 0.2), 0.3));
    w.add_wall(segment(w, Vec2(0.06, 0.0), Vec2(0.06, 0.2), 0.3));
    w.finalize();
}

WorldDef settling_def() {
    WorldDef def;
    def.rotation.model = 1;
    def.damping.local_alpha = 0.7;
    def.damping.dp_mode = DashpotMode::NoTension;
    return def;
}

}  // namespace

TEST(SettleLoop, StopsWhenSettledAtACheck) {
    World w(settling_def());
    fill_box(w);
    SettleRule rule;
    rule.t_end = 2.0;
    rule.ratio = 1e-3;
    long checks = 0;
    rule.on_check = [&](double, long steps, double) {
        ++checks;
        EXPECT_EQ(steps % rule.chunk, 0);  // (t_end is far: every chunk is whole)
    };
    const SettleResult r = settle_through_loop(w, Scenario{}, rule);
    EXPECT_TRUE(r.settled);
    EXPECT_LT(r.ratio, rule.ratio);
    EXPECT_GT(w.time(), rule.min_time);
    EXPECT_LT(w.time(), rule.t_end);
    EXPECT_EQ(w.step_count(), checks * rule.chunk);
    EXPECT_DOUBLE_EQ(r.ratio, w.unbalanced_force_ratio());
}

TEST(SettleLoop, StopsAtTheTimeLimitUnsettled) {
    World w(settling_def());
    fill_box(w);
    SettleRule rule;
    rule.t_end = 0.01;
    rule.ratio = 1e-12;
    const SettleResult r = settle_through_loop(w, Scenario{}, rule);
    EXPECT_FALSE(r.settled);
    EXPECT_GE(w.time(), rule.t_end);
    EXPECT_LT(w.time() - rule.t_end, 1.5 * w.dt());  // the last chunk no longer than t_end asks
}

TEST(SettleLoop, AnInterruptEndsTheGenerationWithTheRulesMessage) {
    World w(settling_def());
    fill_box(w);
    SettleRule rule;
    rule.t_end = 1.0;
    rule.ratio = 1e-12;
    rule.interrupted = "stopped while the test settled";
    rule.on_check = [&](double, long, double) { request_interrupt(SIGINT); };
    try {
        settle_through_loop(w, Scenario{}, rule);
        clear_interrupt();
        FAIL() << "no Interrupted";
    } catch (const Interrupted& e) {
        clear_interrupt();
        EXPECT_EQ(std::string(e.what()), rule.interrupted);
        EXPECT_EQ(w.step_count(), rule.chunk);  // seen at the end of the check's step
    }
}

// World::scale_stiffness, as the release's smooth ramp uses it between two checks: a mass
// settled at stiffness k whose stiffness is then multiplied by 4 goes on bit for bit as the
// same state loaded into a world built at 4 k: the pair tables (discs' and walls') and the
// touching contacts' dashpots follow. Left at k, it goes on otherwise.
TEST(SettleLoop, ScaledStiffnessActsAsAWorldBuiltWithIt) {
    auto box = [](double k) {
        auto w = std::make_unique<World>(settling_def());
        const int m = w->add_material(material(0.3, k));
        for (int i = 0; i < 6; ++i)
            for (int j = 0; j < 5; ++j) w->add_disc({Vec2(0.005 + 0.01 * i, 0.005 + 0.011 * j), 0.0045, Vec2::Zero(), 0, 0, m});
        for (const auto& [p0, p1] : {std::pair{Vec2(0.0, 0.0), Vec2(0.06, 0.0)}, std::pair{Vec2(0.0, 0.0), Vec2(0.0, 0.2)},
                                     std::pair{Vec2(0.06, 0.0), Vec2(0.06, 0.2)}}) {
            WallDef wall = segment(p0, p1);
            wall.material = wall_material(*w, 0.3, k);
            w->add_wall(wall);
        }
        w->set_dt(5e-6);  // the same steps in both (the automatic one follows the stiffness)
        w->finalize();
        return w;
    };
    const double k = 1e8;
    auto scaled = box(k), unscaled = box(k), built = box(4.0 * k);
    scaled->run(20000);  // 0.1 s: the discs have fallen onto the floor and each other
    unscaled->run(20000);
    ASSERT_GT(scaled->touching_wall_pairs() + scaled->touching_disc_pairs(), 20);
    BinaryWriter state;
    scaled->save_state(state);
    BinaryReader in(state.bytes(), "scaled");
    built->load_state(in);
    built->refresh_dashpots();  // the restored contacts carry the saved world's dashpots
    scaled->scale_stiffness(4.0);
    scaled->run(2000);
    unscaled->run(2000);
    built->run(2000);
    EXPECT_EQ(scaled->positions(), built->positions());
    EXPECT_EQ(scaled->velocities(), built->velocities());
    EXPECT_NE(unscaled->positions(), built->positions());
}
