// Renumbering the discs in space order (WorldDef::reorder_every, disc_order.cpp): the physics
// is the same (a pack renumbered mid-run follows the one never renumbered to rounding), a
// contact whose discs swap roles keeps its forces, the bits are the same for any thread count,
// and a checkpoint written after a renumbering resumes to the same bits.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>

#include "core/binary_io.h"
#include "dem/space_order.h"
#include "dem/world.h"
#include "helpers.h"
#include "scenario/scenario.h"

using namespace demlab;

namespace {

MaterialDef sand() { return test::material(0.4, 1e6, 2650.0); }

// A pack of discs dropped into a box 0.3 m wide, added in a shuffled order (so the space order
// is not the order they were added in), with model 3 rotation; with `bonds`, every disc bonded
// to the next one added, with predicted bonds (their dashpot history changes sign on a swap).
World falling_pack(int threads, int reorder_every, bool bonds = false, int reorder_min_discs = 0) {
    WorldDef def;
    def.threads = threads;
    def.reorder_every = reorder_every;
    def.reorder_min_discs = reorder_min_discs;
    def.bond.predict = bonds;
    def.bond.modulus = 2e4;
    World w(def);
    const int m = w.add_material(sand());
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> jitter(-0.0005, 0.0005), radius(0.003, 0.0045);
    std::vector<Vec2> spots;
    for (int row = 0; row < 16; ++row)
        for (int col = 0; col < 30; ++col) spots.emplace_back(0.01 + 0.0095 * col + jitter(rng), 0.006 + 0.0095 * row);
    std::shuffle(spots.begin(), spots.end(), rng);
    for (const Vec2& p : spots) w.add_disc({p, radius(rng), Vec2(jitter(rng) * 400.0, 0.0), 0, 0, m});
    if (bonds)
        for (int k = 0; k + 1 < int(spots.size()); k += 2) w.add_bond(k, k + 1);
    for (const auto& [a, b] : {std::pair{Vec2(0, 0), Vec2(0.3, 0)}, std::pair{Vec2(0, 0), Vec2(0, 0.4)}, std::pair{Vec2(0.3, 0), Vec2(0.3, 0.4)}}) {
        WallDef wall;
        wall.p0 = a;
        wall.p1 = b;
        wall.material = m;
        w.add_wall(wall);
    }
    w.finalize();
    return w;
}

// the largest distance between the two worlds' discs of the same id, m
double largest_gap(const World& a, const World& b) {
    double gap = 0.0;
    for (size_t i = 0; i < a.disc_count(); ++i) {
        const long j = b.disc_index(a.disc_ids()[i]);
        EXPECT_GE(j, 0);
        if (j < 0) return INFINITY;
        gap = std::max(gap, (a.positions()[i] - b.positions()[size_t(j)]).norm());
    }
    return gap;
}

bool in_space_order(const World& w) {
    const std::vector<size_t> order = space_order(w.positions(), 4.0 * *std::max_element(w.radii().begin(), w.radii().end()));
    for (size_t k = 0; k < order.size(); ++k)
        if (order[k] != k) return false;
    return true;
}

}  // namespace

TEST(DiscOrder, SpaceOrderIsStripsLeftToRightThenBottomUp) {
    const std::vector<Vec2> pos{{0.5, 0.0}, {0.05, 0.2}, {0.15, 0.1}, {0.02, 0.1}, {0.5, -1.0}};
    // strips 0.1 wide from x = 0.02: [0.02, 0.12) holds discs 1 and 3, [0.12, 0.22) disc 2, the last discs 0 and 4
    EXPECT_EQ(space_order(pos, 0.1), (std::vector<size_t>{3, 1, 2, 4, 0}));
    EXPECT_EQ(space_order(pos, 0.0), (std::vector<size_t>{0, 1, 2, 3, 4}));
}

// A pack renumbered every 200 steps while it falls and settles follows the one never
// renumbered: the same forces summed in another order differ by rounding, which a dense pack
// amplifies slowly; after 3,000 steps every disc is within a millionth of its radius.
TEST(DiscOrder, RenumberedPackFollowsTheOneNeverRenumbered) {
    World kept = falling_pack(1, 0), renumbered = falling_pack(1, 200);
    const double e0 = renumbered.energy().balance();
    for (World* w : {&kept, &renumbered}) w->run(3000);
    EXPECT_EQ(kept.reorders(), 0);
    EXPECT_EQ(renumbered.reorders(), 15);
    EXPECT_TRUE(in_space_order(renumbered));
    EXPECT_FALSE(in_space_order(kept));
    EXPECT_NE(kept.disc_ids(), renumbered.disc_ids());
    EXPECT_LT(largest_gap(kept, renumbered), 1e-6 * 0.003);
    EXPECT_GT(renumbered.touching_disc_pairs(), 400);
    EXPECT_EQ(renumbered.touching_disc_pairs(), kept.touching_disc_pairs());
    const EnergyReport a = kept.energy(), b = renumbered.energy();
    EXPECT_NEAR(b.dissipated_contacts, a.dissipated_contacts, 1e-9 * std::abs(a.dissipated_contacts));
    // the ledger's rounding (the centred work terms) is the same in both
    EXPECT_NEAR(b.balance() - e0, a.balance() - e0, 1e-6 * std::abs(e0));
}

// The same with bonds whose dashpots carry a history: renumbered, swapped and sorted, the
// bonds act as before.
TEST(DiscOrder, BondsFollowTheRenumbering) {
    World kept = falling_pack(1, 0, true), renumbered = falling_pack(1, 250, true);
    for (World* w : {&kept, &renumbered}) w->run(2000);
    EXPECT_EQ(renumbered.reorders(), 8);
    ASSERT_EQ(kept.bonds().size(), renumbered.bonds().size());
    size_t broken_a = 0, broken_b = 0;
    for (const Bond& b : kept.bonds()) broken_a += b.broken;
    for (const Bond& b : renumbered.bonds()) {
        broken_b += b.broken;
        EXPECT_LT(b.k, b.l);
    }
    EXPECT_EQ(broken_a, broken_b);
    EXPECT_LT(largest_gap(kept, renumbered), 1e-6 * 0.003);
    const EnergyReport a = kept.energy(), b = renumbered.energy();
    EXPECT_NEAR(b.bond_elastic, a.bond_elastic, 1e-6 * a.bond_elastic);
    // the bonds' dashpot work is booked from their last forces too (their history)
    EXPECT_NEAR(b.dissipated_contacts, a.dissipated_contacts, 1e-9 * a.dissipated_contacts);
    EXPECT_NEAR(b.balance(), a.balance(), 1e-9 * std::abs(a.balance()));
}

// Two discs pressed together with a shear history: numbered the other way round, the pair's
// first disc becomes its second (n and t reversed); the forces on each disc stay the same.
TEST(DiscOrder, SwappedPairKeepsItsForces) {
    auto pair = [] {
        WorldDef def;
        def.gravity = Vec2::Zero();
        World w(def);
        const int m = w.add_material(sand());
        w.add_disc({Vec2(0.0, 0.0), 0.01, Vec2(0.0, 0.05), 0, 3.0, m});
        w.add_disc({Vec2(0.0195, 0.001), 0.01, Vec2(-0.01, -0.05), 0, -2.0, m});
        w.finalize();
        w.set_dt(1e-6);
        return w;
    };
    World a = pair(), b = pair();
    a.run(40);
    b.run(40);
    b.reorder_discs({1, 0});
    EXPECT_EQ(b.disc_ids(), (std::vector<int32_t>{1, 0}));
    EXPECT_EQ(b.disc_index(0), 1);
    a.run(40);
    b.run(40);
    for (size_t i = 0; i < 2; ++i) {
        const size_t j = 1 - i;
        EXPECT_NEAR(a.force(i).x(), b.force(j).x(), 1e-9 * a.force(i).norm()) << i;
        EXPECT_NEAR(a.force(i).y(), b.force(j).y(), 1e-9 * a.force(i).norm()) << i;
        EXPECT_NEAR(a.torque(i), b.torque(j), 1e-9 * std::abs(a.torque(i))) << i;
        EXPECT_NEAR(a.positions()[i].x(), b.positions()[j].x(), 1e-15) << i;
    }
    EXPECT_GT(std::abs(a.torque(0)), 0.0);  // the shear spring is loaded
    EXPECT_NEAR(a.energy().balance(), b.energy().balance(), 1e-12);
}

// The renumbering depends on positions and the step count alone: one and two threads give the
// same bits.
TEST(DiscOrder, SameBitsOnAnyThreadCount) {
    World one = falling_pack(1, 150), two = falling_pack(2, 150);
    one.run(1500);
    two.run(1500);
    EXPECT_EQ(one.reorders(), 10);
    EXPECT_EQ(two.reorders(), 10);
    EXPECT_EQ(one.disc_ids(), two.disc_ids());
    EXPECT_EQ(one.positions(), two.positions());
    EXPECT_EQ(one.energy().balance(), two.energy().balance());
}

// A checkpoint written between renumberings restores into a world built from the set-up (in
// the order the discs were added) and continues, across more renumberings, to the same bits.
TEST(DiscOrder, CheckpointResumesToTheSameBits) {
    for (const bool bonds : {false, true}) {
        World a = falling_pack(1, 100, bonds);
        a.run(450);
        BinaryWriter out;
        a.save_state(out);
        World b = falling_pack(2, 100, bonds);
        BinaryReader in(out.bytes(), "state");
        b.load_state(in);
        EXPECT_EQ(b.disc_ids(), a.disc_ids());
        a.run(600);
        b.run(600);
        EXPECT_EQ(a.positions(), b.positions()) << bonds;
        EXPECT_EQ(a.velocities(), b.velocities()) << bonds;
        EXPECT_EQ(a.energy().balance(), b.energy().balance()) << bonds;
        EXPECT_EQ(a.disc_ids(), b.disc_ids()) << bonds;
    }
}

// Small worlds keep their order (and every bit they had): below the threshold nothing is
// renumbered, at it the world is.
TEST(DiscOrder, WorldsBelowTheThresholdAreNotRenumbered) {
    EXPECT_EQ(WorldDef{}.reorder_min_discs, 50000);
    EXPECT_EQ(WorldDef{}.reorder_every, 0);  // the engine's worlds keep their order
    EXPECT_EQ(scenario_world().reorder_every, 10000);  // a scenario's large world renumbers
    World below = falling_pack(1, 10, false, 481), at = falling_pack(1, 10, false, 480), never = falling_pack(1, 0);
    for (World* w : {&below, &at, &never}) w->run(100);
    EXPECT_EQ(below.reorders(), 0);
    EXPECT_EQ(at.reorders(), 10);
    EXPECT_EQ(below.positions(), never.positions());
}

TEST(DiscOrder, RefusesAnOrderThatIsNotAPermutation) {
    World w = falling_pack(1, 0);
    std::vector<size_t> order(w.disc_count());
    std::iota(order.begin(), order.end(), size_t(0));
    order[3] = 4;
    EXPECT_THROW(w.reorder_discs(order), std::exception);
    order.pop_back();
    EXPECT_THROW(w.reorder_discs(order), std::exception);
}
