// Renumbering the discs in space order as they flow (world.space_order, dem/space_order.cpp):
// the same physics (the renumbered run follows the unrenumbered one by id to round-off), the
// same bits on any thread count, a checkpoint after a renumbering resuming to the same bits,
// and the inputs it refuses.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "core/binary_io.h"
#include "core/error.h"
#include "dem/space_order.h"
#include "helpers.h"
#include "scenario/scenario.h"
#include "setups/db9k.h"

using namespace demlab;
using namespace demlab::test;

namespace {
// DB-9k's discs in a random order: what a long flow does to a mass numbered in space order,
// at its worst
std::vector<XyrDisc> shuffled_db9k() {
    auto discs = read_xyr(default_db9k_path());
    std::mt19937_64 rng(7);
    std::shuffle(discs.begin(), discs.end(), rng);
    return discs;
}

World db9k_world(const std::vector<XyrDisc>& discs, SpaceOrder order, int every, int threads = 1) {
    WorldDef def = db9k_world_def();
    def.threads = threads;
    def.timestep.dashpots = DashpotScheme::Centred;
    def.space_order = order;
    def.space_order_steps = every;
    World w(def);
    w.set_cross_share_limit(1.0);  // keep the ranges whatever crosses
    w.set_busy_fallback(false);    // and on a busy machine
    build_db9k(w, discs);
    w.finalize();
    return w;
}

// the mean of j - i over the touching pairs: how far apart in the arrays a contact's discs are
double mean_number_gap(const World& w) {
    double sum = 0.0;
    long count = 0;
    for (const DiscContact& c : w.disc_contacts()) {
        const size_t i = size_t(c.i), j = size_t(c.j);
        const double rsum = w.radii()[i] + w.radii()[j];
        if ((w.positions()[j] - w.positions()[i]).squaredNorm() >= rsum * rsum) continue;
        sum += double(c.j - c.i);
        ++count;
    }
    return count > 0 ? sum / double(count) : 0.0;
}
}  // namespace

TEST(SpaceOrder, OrdersStripsAcrossXThenUp) {
    const std::vector<Vec2> pos{{0.25, 0.0}, {0.05, 0.3}, {0.15, 0.1}, {0.05, 0.1}, {0.25, -0.1}};
    // strips 0.2 m wide from the leftmost centre: [0.05, 0.25) and [0.25, 0.45); discs 2 and 3
    // are level in the first: the tie keeps their old order
    EXPECT_EQ(space_order(pos, 0.2), (std::vector<size_t>{2, 3, 1, 4, 0}));
    EXPECT_TRUE(space_order(pos, 0.0).empty());
    EXPECT_TRUE(space_order({}, 0.2).empty());
}

TEST(SpaceOrder, RenumberedFlowFollowsTheSameDiscsToRoundOff) {
    const auto discs = shuffled_db9k();
    World off = db9k_world(discs, SpaceOrder::Off, 200);
    World on = db9k_world(discs, SpaceOrder::On, 200);
    const double gap_before = mean_number_gap(on);
    off.run(600);
    on.run(600);
    EXPECT_EQ(off.space_orderings(), 0);
    EXPECT_EQ(on.space_orderings(), 2);  // before steps 201 and 401
    // the shuffled numbers put a contact's discs thousands apart; in strips, tens
    EXPECT_GT(gap_before, 1000.0);
    EXPECT_LT(mean_number_gap(on), 0.05 * gap_before);
    // every disc is still there, found by its id, where the unrenumbered run has it
    const size_t n = off.disc_count();
    ASSERT_EQ(on.disc_count(), n);
    std::vector<int32_t> ids = on.disc_ids();
    EXPECT_FALSE(std::is_sorted(ids.begin(), ids.end()));
    std::sort(ids.begin(), ids.end());
    for (size_t k = 0; k < n; ++k) ASSERT_EQ(ids[k], int32_t(k));
    double worst = 0.0, moved = 0.0;
    for (size_t i = 0; i < n; ++i) {
        const long k = on.disc_index(off.disc_ids()[i]);
        ASSERT_GE(k, 0);
        ASSERT_EQ(on.disc_ids()[size_t(k)], off.disc_ids()[i]);
        worst = std::max(worst, (on.positions()[size_t(k)] - off.positions()[i]).norm());
        worst = std::max(worst, 1e-3 * (on.velocities()[size_t(k)] - off.velocities()[i]).norm());
        moved = std::max(moved, (off.positions()[i] - Vec2(discs[i].x, discs[i].y)).norm());
    }
    // the column has started to collapse (moved), and the two runs agree to the sums' order
    EXPECT_GT(moved, 1e-6);
    EXPECT_LT(worst, 1e-12);
    const EnergyReport a = off.energy(), b = on.energy();
    EXPECT_GT(a.dissipated_contacts, 0.0);
    EXPECT_NEAR(b.dissipated_contacts, a.dissipated_contacts, 1e-9 * a.dissipated_contacts);
    EXPECT_NEAR(b.balance(), a.balance(), 1e-9 * std::abs(a.balance()));
}

TEST(SpaceOrder, SameBitsOnOneAndThreeThreads) {
    const auto discs = shuffled_db9k();
    World one = db9k_world(discs, SpaceOrder::On, 150, 1);
    World three = db9k_world(discs, SpaceOrder::On, 150, 3);
    one.run(500);
    three.run(500);
    EXPECT_EQ(three.space_orderings(), 3);
    EXPECT_EQ(state_hash(one), state_hash(three));
    EXPECT_EQ(one.disc_ids(), three.disc_ids());
    EXPECT_EQ(one.energy().dissipated_contacts, three.energy().dissipated_contacts);
}

TEST(SpaceOrder, CheckpointAfterARenumberingResumesToTheSameBits) {
    const auto discs = shuffled_db9k();
    World a = db9k_world(discs, SpaceOrder::On, 150);
    a.run(400);  // renumbered before steps 151 and 301
    BinaryWriter out;
    a.save_state(out);
    World b = db9k_world(discs, SpaceOrder::On, 150, 2);
    BinaryReader in(out.bytes(), "state");
    b.load_state(in);
    EXPECT_EQ(b.disc_ids(), a.disc_ids());
    EXPECT_EQ(b.space_orderings(), 2);
    a.run(300);  // and twice more, before steps 451 and 601
    b.run(300);
    EXPECT_EQ(a.space_orderings(), 4);
    EXPECT_EQ(b.space_orderings(), 4);
    EXPECT_EQ(state_hash(a), state_hash(b));
    EXPECT_EQ(a.energy().balance(), b.energy().balance());
    // a world never renumbered writes the layout of the builds before (version 2)
    World c = db9k_world(discs, SpaceOrder::Off, 150);
    c.run(10);
    BinaryWriter plain;
    c.save_state(plain);
    EXPECT_EQ(plain.bytes().substr(4, 4), std::string("\x02\0\0\0", 4));
    EXPECT_EQ(out.bytes().substr(4, 4), std::string("\x03\0\0\0", 4));
}

TEST(SpaceOrder, AutoRenumbersOnlyWorldsAboveItsThreshold) {
    // DB-9k's 9,140 discs are below kSpaceOrderFlowDiscs: its bits stay the benchmark's
    World w = db9k_world(read_xyr(default_db9k_path()), SpaceOrder::Auto, 100);
    w.run(250);
    EXPECT_EQ(w.space_orderings(), 0);
    const std::vector<int32_t>& ids = w.disc_ids();
    EXPECT_TRUE(std::is_sorted(ids.begin(), ids.end()));
    // three columns side by side (27,420 discs) are above it
    WorldDef def = db9k_world_def(3);
    def.space_order = SpaceOrder::Auto;
    def.space_order_steps = 20;
    World big(def);
    build_db9k(big, read_xyr(default_db9k_path()), 3);
    big.finalize();
    ASSERT_GT(big.disc_count(), kSpaceOrderFlowDiscs);
    big.run(30);
    EXPECT_EQ(big.space_orderings(), 1);
}

TEST(SpaceOrder, RefusedWithoutAStepCountAndWithBonds) {
    WorldDef def;
    def.space_order_steps = 0;
    expect_refused([&] { validate(def, "world"); }, {"world.space_order_steps = 0", "at least 1"});
    WorldDef bonded;
    bonded.space_order = SpaceOrder::On;
    World w(bonded);
    const int m = w.add_material(material(0.3, 1e6));
    w.add_disc({Vec2(0.0, 0.0), 0.01, Vec2::Zero(), 0, 0, m});
    w.add_disc({Vec2(0.02, 0.0), 0.01, Vec2::Zero(), 0, 0, m});
    w.add_bond(0, 1);
    expect_refused([&] { w.finalize(); }, {"world.space_order = on", "bonds"});
}

TEST(SpaceOrder, OnWithCohesionIsRefusedNamingTheFile) {
    Scenario s = load_scenario(std::string(DEMLAB_SOURCE_DIR) + "/scenarios/snow-slide-2d.toml");
    apply_override(s, "world.space_order=on");
    expect_refused([&] { finish_scenario(s); }, {"snow-slide-2d.toml", "world.space_order = \"on\"", "cohesion.enabled"});
}
