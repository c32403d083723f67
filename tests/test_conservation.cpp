// Balances: energy of an undamped, frictionless system; momentum and angular momentum of free
// collisions; the energy ledger of a damped, frictional collapse; determinism.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <atomic>
#include <cmath>
#include <random>
#include <thread>

#include "setups/db9k.h"
#include "core/error.h"
#include "dem/range_balance.h"
#include "helpers.h"

using namespace demlab;
using namespace demlab::test;

namespace {
// DB-9k's world (or these discs of it) on this many threads, finalized, after `steps` steps:
// its state hash; `look` sees the world then.
template <typename Look>
uint64_t db9k_hash_after(const std::vector<XyrDisc>& discs, int threads, long steps, Look&& look,
                         DashpotScheme dashpots = DashpotScheme::Lagged) {
    WorldDef def = db9k_world_def();
    def.threads = threads;
    def.timestep.dashpots = dashpots;  // DB-9k's own is lagged (the benchmark's peer's scheme)
    World w(def);
    // the ranges the thread count gives, even when the tests beside it keep the cores busy
    w.set_busy_fallback(false);
    build_db9k(w, discs);
    w.finalize();
    w.run(steps);
    look(w);
    return state_hash(w);
}
uint64_t db9k_hash_after(const std::vector<XyrDisc>& discs, int threads, long steps) {
    return db9k_hash_after(discs, threads, steps, [](const World&) {});
}
double uniform(std::mt19937_64& rng, double lo, double hi) { return lo + (hi - lo) * double(rng() >> 11) * 0x1.0p-53; }

// n discs with random velocities in a closed box of walls (0.2 m x 0.2 m).
World box_of_discs(int n, double beta, double mu, unsigned seed, bool gravity, bool walls, int model) {
    WorldDef def;
    def.damping.beta_n = beta;
    def.damping.beta_s = beta;
    def.rotation.model = model;
    def.rotation.u_rr = 0.0;
    def.rotation.mu_br = 1.0;
    if (!gravity) def.gravity = Vec2::Zero();
    def.timestep.automatic = false;
    World w(def);
    const int m = w.add_material(material(mu));
    std::mt19937_64 rng(seed);
    std::vector<Vec2> placed;
    std::vector<double> radii;
    while (int(placed.size()) < n) {
        const double r = uniform(rng, 0.004, 0.008);
        const Vec2 p(uniform(rng, r, 0.2 - r), uniform(rng, r, 0.2 - r));
        bool free = true;
        for (size_t k = 0; k < placed.size(); ++k)
            if ((placed[k] - p).norm() < r + radii[k]) free = false;
        if (!free) continue;
        placed.push_back(p);
        radii.push_back(r);
        w.add_disc({p, r, Vec2(uniform(rng, -1, 1), uniform(rng, -1, 1)), uniform(rng, -50, 50), 0.0, m});
    }
    if (walls) {
        w.add_wall(segment(w, Vec2(0, 0), Vec2(0.2, 0), mu, SegmentSolid::Right));
        w.add_wall(segment(w, Vec2(0.2, 0), Vec2(0.2, 0.2), mu, SegmentSolid::Right));
        w.add_wall(segment(w, Vec2(0.2, 0.2), Vec2(0, 0.2), mu, SegmentSolid::Right));
        w.add_wall(segment(w, Vec2(0, 0.2), Vec2(0, 0), mu, SegmentSolid::Right));
    }
    w.set_dt(2e-6);
    w.finalize();
    return w;
}

double mechanical_energy(const World& w) {
    const EnergyReport e = w.energy();
    return e.kinetic_translation + e.kinetic_rotation + e.potential + e.elastic;
}
}  // namespace

TEST(Conservation, UndampedFrictionlessDiscsInABoxKeepTheirEnergy) {
    World w = box_of_discs(30, 0.0, 0.0, 7, true, true, 2);
    const double e0 = mechanical_energy(w);
    long contacts_seen = 0;
    double worst = 0.0;
    for (int k = 0; k < 100; ++k) {
        w.run(1000);  // 100,000 steps in all
        contacts_seen += w.touching_disc_pairs() + w.touching_wall_pairs();
        worst = std::max(worst, std::abs(mechanical_energy(w) - e0) / e0);
    }
    EXPECT_LT(worst, 1e-3);
    const EnergyReport e = w.energy();
    EXPECT_EQ(e.dissipated_contacts, 0.0);
    EXPECT_GT(contacts_seen, 0);  // the discs did collide
}

TEST(Conservation, FreeCollisionsConserveMomentumAndAngularMomentum) {
    // damped, frictional, rotating: internal forces only
    World w = box_of_discs(40, 0.5, 0.5, 11, false, false, 2);
    const auto momenta = [&](Vec2& p, double& l) {
        p = Vec2::Zero();
        l = 0.0;
        for (size_t i = 0; i < w.disc_count(); ++i) {
            const double m = w.masses()[i], r = w.radii()[i];
            p += m * w.velocities()[i];
            l += m * cross(w.positions()[i], w.velocities()[i]) + 0.5 * m * r * r * w.omegas()[i];
        }
    };
    Vec2 p0;
    double l0;
    momenta(p0, l0);
    long touching = 0;
    for (int k = 0; k < 50; ++k) {
        w.run(200);
        touching += w.touching_disc_pairs();
        // every pair's forces are equal and opposite: they sum to zero
        Vec2 sum = Vec2::Zero();
        double scale = 0.0;
        for (size_t i = 0; i < w.disc_count(); ++i) {
            const Vec2 f = w.force(i);
            sum += f;
            scale += f.norm();
        }
        EXPECT_LE(sum.norm(), 1e-12 * std::max(scale, 1.0));
    }
    EXPECT_GT(touching, 0);
    Vec2 p1;
    double l1;
    momenta(p1, l1);
    double pscale = 0, lscale = 0;
    for (size_t i = 0; i < w.disc_count(); ++i) {
        pscale += w.masses()[i] * 1.0;
        lscale += w.masses()[i] * 0.2 * 1.0;
    }
    EXPECT_LT((p1 - p0).norm(), 1e-12 * pscale);
    EXPECT_LT(std::abs(l1 - l0), 1e-11 * lscale);
}

TEST(Conservation, EnergyLedgerOfADampedFrictionalCollapseCloses) {
    for (int model : {1, 2, 3}) {
        World w = box_of_discs(60, 0.5, 0.4, 3, true, true, model);
        const double b0 = w.energy().balance();
        w.run(50000);
        const EnergyReport e = w.energy();
        const double dissipated = e.dissipated_contacts + e.dissipated_rotation;
        EXPECT_GT(dissipated, 0.0);
        // the ledger closes to 1 % of what moved through it
        EXPECT_LT(std::abs(e.balance() - b0), 0.01 * dissipated) << "model " << model;
    }
}

TEST(Determinism, OneAndTwoThreadsGiveTheSameBits) {
    DEMLAB_RELEASE_PASS_ONLY("Determinism.ShuffledDiscsOnThreeThreadsGiveTheSameBits (DB-9k shared by threads)");
    // DB-9k, the whole column, 20,000 steps (0.1 s: the densest phase)
    const auto discs = read_xyr(default_db9k_path());
    uint64_t h[2];
    for (int threads : {1, 2})
        h[threads - 1] = db9k_hash_after(discs, threads, 20000, [threads](const World& w) {
            // the shared passes' accounting: none on 1 thread; on 2 a share of the threads'
            // time worked, below 1 (a pass has a hand-over and a join)
            if (threads == 1) {
                EXPECT_EQ(w.force_pass_shared_seconds(), 0.0);
                EXPECT_EQ(w.force_pass_busy_share(), 1.0);
            } else {
                EXPECT_GT(w.force_pass_shared_seconds(), 0.0);
                EXPECT_LT(w.force_pass_busy_share(), 1.0);
                EXPECT_GT(w.force_pass_busy_share(), 0.0);
            }
        }, DashpotScheme::Centred);  // the default scheme
    EXPECT_EQ(h[0], h[1]);
    // The bits of this build (docs/performance.md): a change meant only to be faster must keep
    // them. One that changes the arithmetic on purpose updates this value and the flume
    // references (test_regression.cpp) and says so. The centred dashpots (the default since
    // they replaced the lagged ones) gave this value.
    EXPECT_EQ(h[0], 0x45695244ab7ea556ull);
}

TEST(Determinism, LaggedDashpotsGiveTheEarlierBuildsBits) {
    DEMLAB_RELEASE_PASS_ONLY("the release's settling (lagged dashpots) and the Dashpots tests");
    // timestep.dashpots = "lagged", DB-9k's own (the benchmark): the bits every build gave from
    // the first engine until the centred dashpots became the default (on 2 threads: the same
    // bits as 1, as above)
    WorldDef def = db9k_world_def();
    def.threads = 2;
    def.timestep.dashpots = DashpotScheme::Lagged;
    World w(def);
    w.set_busy_fallback(false);
    build_db9k(w, read_xyr(default_db9k_path()));
    w.finalize();
    w.run(20000);
    EXPECT_EQ(state_hash(w), 0x2a84955e5ff8ddd2ull);
}

TEST(Determinism, ShuffledDiscsOnThreeThreadsGiveTheSameBits) {
    // DB-9k with its discs in a random order: nearly every pair then crosses from one thread's
    // disc range to another's, and with 3 ranges a pair can skip one (range 0 to range 2).
    // That exercises the cross-contact slots and their order (World::compute_forces).
    auto discs = read_xyr(default_db9k_path());
    // The 3 ranges are cut unevenly halfway (as the measured balancing may cut them): the
    // bits, the energy ledger's included, must not depend on where the cut falls.
    std::mt19937_64 rng(42);
    std::shuffle(discs.begin(), discs.end(), rng);
    uint64_t h[2];
    size_t cross[2];
    EnergyReport e[2];
    std::vector<DiscContact> contacts[2];
    long skipped[2];
    long touching_walls[2];
    std::vector<double> wall_loads[2];  // per wall: force x, y and moment
    for (int k = 0; k < 2; ++k) {
        WorldDef def = db9k_world_def();
        def.threads = k == 0 ? 1 : 3;
        def.timestep.dashpots = DashpotScheme::Centred;
        World w(def);
        w.set_cross_share_limit(1.0);  // keep the 3 ranges whatever crosses
        w.set_busy_fallback(false);    // and on 2 cores (3 threads: the machine is busy)
        build_db9k(w, discs);
        w.finalize();
        w.run(700);
        if (k == 1) w.cut_force_pass({0.6, 0.1, 0.3});
        w.run(800);
        h[k] = state_hash(w);
        cross[k] = w.cross_contacts();
        e[k] = w.energy();
        contacts[k] = w.disc_contacts();
        skipped[k] = w.pairs_skipped();
        touching_walls[k] = w.touching_wall_pairs();
        for (size_t n = 0; n < w.wall_count(); ++n)
            wall_loads[k].insert(wall_loads[k].end(), {w.wall_force(int(n)).x(), w.wall_force(int(n)).y(), w.wall_moment(int(n))});
    }
    EXPECT_EQ(h[0], h[1]);
    EXPECT_EQ(cross[0], 0u);
    EXPECT_GT(cross[1], 1000u);
    EXPECT_GT(e[0].dissipated_contacts, 0.0);
    EXPECT_EQ(e[0].dissipated_contacts, e[1].dissipated_contacts);
    EXPECT_EQ(e[0].dissipated_local, e[1].dissipated_local);
    EXPECT_EQ(e[0].dissipated_rotation, e[1].dissipated_rotation);
    EXPECT_EQ(e[0].elastic, e[1].elastic);
    // The walls' loads: each range hands over its touching wall contacts in list order, and
    // they are added range by range (World::WallSum): the 1-thread sums, bit for bit.
    EXPECT_GT(touching_walls[0], 50);
    EXPECT_EQ(touching_walls[0], touching_walls[1]);
    ASSERT_EQ(wall_loads[0].size(), wall_loads[1].size());
    size_t loaded = 0;
    for (size_t n = 0; n < wall_loads[0].size(); ++n) {
        loaded += wall_loads[0][n] != 0.0;
        EXPECT_EQ(std::bit_cast<uint64_t>(wall_loads[0][n]), std::bit_cast<uint64_t>(wall_loads[1][n])) << "wall load " << n;
    }
    EXPECT_GE(loaded, 3u);  // the floor's force and moment at least
    // The ranges compute the cross contacts on copies (World::cross_dd_), and the range that
    // owns a contact's first disc copies its history back: after the passes every history in
    // the list is the 1-thread run's, bit for bit.
    ASSERT_EQ(contacts[0].size(), contacts[1].size());
    size_t with_history = 0, differ = 0;
    for (size_t c = 0; c < contacts[0].size(); ++c) {
        const DiscContact &a = contacts[0][c], &b = contacts[1][c];
        ASSERT_TRUE(a.i == b.i && a.j == b.j) << "contact " << c;
        with_history += a.fs != 0.0 || a.damp_n != 0.0f;
        differ += std::bit_cast<uint64_t>(a.fs) != std::bit_cast<uint64_t>(b.fs) ||
                  std::bit_cast<uint32_t>(a.damp_n) != std::bit_cast<uint32_t>(b.damp_n) ||
                  std::bit_cast<uint32_t>(a.damp_s) != std::bit_cast<uint32_t>(b.damp_s);
    }
    EXPECT_GT(with_history, 1000u);
    EXPECT_EQ(differ, 0u);
    // And the cross contacts go through the clearance test as the others do: nearly every
    // pair crosses here, and 3 threads skip most of the clear pairs 1 thread skips: 81 %
    // (the rest fall between cross contacts in groups too short for the SIMD pass). With the
    // law run on every cross contact, they skipped 17 %.
    EXPECT_GT(skipped[0], 0);
    EXPECT_GT(double(skipped[1]), 0.7 * double(skipped[0]));
}

TEST(ForcePassBalance, DiscsOutOfSpaceOrderRunAsOneRange) {
    // In space order (DB-9k as stored) 1 % of the candidates cross between 2 ranges and the
    // pass is shared; shuffled, half of them cross and the pass runs as one range (the
    // release generator's world before its mass is ordered: 2 ranges were 1.5x slower than
    // one there). Either way the same bits as 1 thread.
    auto discs = read_xyr(default_db9k_path());
    discs.resize(5000);  // the pool shares from 4,096 discs on
    for (bool shuffled : {false, true}) {
        if (shuffled) {
            std::mt19937_64 rng(7);
            std::shuffle(discs.begin(), discs.end(), rng);
        }
        const uint64_t one = db9k_hash_after(discs, 1, 300);
        const uint64_t two = db9k_hash_after(discs, 2, 300, [&](const World& w) {
            EXPECT_EQ(w.force_pass_ranges(), shuffled ? 1 : 2) << "shuffled " << shuffled;
            EXPECT_EQ(w.force_pass_one_range_cuts() > 0, shuffled);
            EXPECT_EQ(w.cross_contacts() == 0, shuffled);
        });
        EXPECT_EQ(one, two) << "shuffled " << shuffled;
    }
    WorldDef def = db9k_world_def();
    World w(def);
    EXPECT_THROW(w.set_cross_share_limit(1.5), InputError);
    EXPECT_THROW(w.set_cross_share_limit(NAN), InputError);
}

TEST(ForcePassBalance, SharesMoveHalfwayTowardsTheMeasuredSpeeds) {
    // range 0 took 3 s for half the work, range 1 took 1 s: speeds 1/6 and 1/2, i.e. the
    // shares 0.25 and 0.75 would have equalised the times; halfway there: 0.375 and 0.625
    double share[2] = {0.5, 0.5};
    const double slow_first[2] = {3.0, 1.0};
    EXPECT_TRUE(rebalance_shares(share, [&](size_t t) { return slow_first[t]; }, 2, 0.03));
    EXPECT_DOUBLE_EQ(share[0], 0.375);
    EXPECT_DOUBLE_EQ(share[1], 0.625);
    EXPECT_DOUBLE_EQ(share[0] + share[1], 1.0);
    // within the tolerance (2 % over the mean), and with no time measured: left alone
    const double close[2] = {1.02, 0.98};
    EXPECT_FALSE(rebalance_shares(share, [&](size_t t) { return close[t]; }, 2, 0.03));
    EXPECT_FALSE(rebalance_shares(share, [](size_t) { return 0.0; }, 2, 0.03));
    EXPECT_DOUBLE_EQ(share[0], 0.375);
    // three ranges, repeated: converges to equal times for ranges of constant speed
    double s3[3] = {1.0 / 3, 1.0 / 3, 1.0 / 3};
    const double cost[3] = {1.0, 2.0, 1.0};  // seconds per unit share
    for (int k = 0; k < 60; ++k) rebalance_shares(s3, [&](size_t t) { return cost[t] * s3[t]; }, 3, 1e-9);
    EXPECT_NEAR(s3[0], 0.4, 1e-6);
    EXPECT_NEAR(s3[1], 0.2, 1e-6);
    EXPECT_NEAR(s3[2], 0.4, 1e-6);
}

TEST(ForcePassBalance, OneRangeWhenRangesWorkLessThanTheirShare) {
    // 2 ranges, 1 s of passes: 2 thread-seconds. Working 0.95 s each (an idle machine), 2
    // ranges are faster; 0.5 s each is break-even; 0.1 s each (one thread stopped by the
    // operating system most of the time) is slower than 1 range.
    EXPECT_FALSE(one_range_would_be_faster(1.9, 1.0, 2));
    EXPECT_FALSE(one_range_would_be_faster(1.0, 1.0, 2));
    EXPECT_TRUE(one_range_would_be_faster(0.99, 1.0, 2));
    EXPECT_TRUE(one_range_would_be_faster(0.2, 1.0, 2));
    // 4 ranges: below a quarter of the threads' time
    EXPECT_FALSE(one_range_would_be_faster(1.2, 1.0, 4));
    EXPECT_TRUE(one_range_would_be_faster(0.8, 1.0, 4));
    // one range, or nothing measured: no decision
    EXPECT_FALSE(one_range_would_be_faster(0.1, 1.0, 1));
    EXPECT_FALSE(one_range_would_be_faster(0.0, 0.0, 2));
}

TEST(ForcePassBalance, BusyWatchFallsBackAfterThreeSlowWindowsInARow) {
    // 2 ranges, windows of 10 ms of passes: slow = 5 ms worked in all, good = 19 ms
    BusyWatch watch;
    const double slow = 0.005, good = 0.019, wall = 0.010;
    // a slow window now and then (a core stopped for a few ms on an idle machine): never
    for (int k = 0; k < 10; ++k) {
        EXPECT_FALSE(watch.window(slow, wall, 2));
        EXPECT_FALSE(watch.window(slow, wall, 2));
        EXPECT_FALSE(watch.window(good, wall, 2));
    }
    // a core taken by another process: the third slow window in a row, then counting again
    EXPECT_FALSE(watch.window(slow, wall, 2));
    EXPECT_FALSE(watch.window(slow, wall, 2));
    EXPECT_TRUE(watch.window(slow, wall, 2));
    EXPECT_FALSE(watch.window(slow, wall, 2));
    EXPECT_FALSE(watch.window(slow, wall, 2));
    EXPECT_TRUE(watch.window(slow, wall, 2));
}

TEST(ForcePassBalance, OneRangeForAWhileThenTheRangesAgain) {
    // The fallback for a busy machine (run_as_one_range_for), as the step takes it: one range
    // for its steps, across a list update, then the pool's ranges again; the same bits as
    // 1 thread throughout.
    auto discs = read_xyr(default_db9k_path());
    discs.resize(5000);
    const uint64_t one = db9k_hash_after(discs, 1, 2300);
    WorldDef def = db9k_world_def();
    def.threads = 2;
    World w(def);
    w.set_busy_fallback(false);  // only the one-range period asked for (tests run side by side)
    build_db9k(w, discs);
    w.finalize();
    w.run(100);
    EXPECT_EQ(w.force_pass_ranges(), 2);
    const long updates = w.broad_phase_stats().updates;
    w.run_as_one_range_for(2000);
    for (int k = 0; k < 1999; ++k) {
        w.step();
        ASSERT_EQ(w.force_pass_ranges(), 1) << "step " << k;
    }
    EXPECT_GT(w.broad_phase_stats().updates, updates);  // a list update re-cuts: still one range
    w.step();
    EXPECT_EQ(w.force_pass_ranges(), 2);
    EXPECT_EQ(w.force_pass_one_range_steps(), 2000);
    EXPECT_EQ(w.force_pass_busy_fallbacks(), 0);  // asked for, not fallen back to
    w.run(200);
    EXPECT_EQ(state_hash(w), one);
    EXPECT_THROW(w.run_as_one_range_for(-1), InputError);
}

// The step's own fallback (balance_force_pass with BusyWatch): with more busy threads than
// cores beside it, the 2-thread pass falls back to one range, and the bits stay those of 1
// thread. The other tests turn the fallback off; this one keeps the cores busy on purpose.
TEST(ForcePassBalance, StepFallsBackToOneRangeBesideBusyThreads) {
    const unsigned cores = std::max(1u, std::thread::hardware_concurrency());
    if (cores > 8) GTEST_SKIP() << "too many cores to keep them all busy (" << cores << ")";
    auto discs = read_xyr(default_db9k_path());
    discs.resize(5000);
    WorldDef def = db9k_world_def();
    def.threads = 2;
    World w(def);
    build_db9k(w, discs);
    w.finalize();
    std::atomic<bool> stop{false};
    std::vector<std::thread> hogs;
    for (unsigned k = 0; k < cores; ++k)
        hogs.emplace_back([&stop] {
            volatile double x = 1.0;
            while (!stop.load(std::memory_order_relaxed)) x = x * 1.0000001;
        });
    long steps = 0;
    while (w.force_pass_busy_fallbacks() == 0 && steps < 20000) {
        w.run(64);
        steps += 64;
    }
    stop = true;
    for (std::thread& t : hogs) t.join();
    ASSERT_GT(w.force_pass_busy_fallbacks(), 0) << "no fallback in " << steps << " steps beside " << cores << " busy threads";
    EXPECT_EQ(w.force_pass_ranges(), 1);
    w.run(100);
    EXPECT_GT(w.force_pass_one_range_steps(), 0);
    EXPECT_EQ(state_hash(w), db9k_hash_after(discs, 1, steps + 100));
}

// The lists of a flow are rebuilt every few steps (geometry A at scale 4: every 11 on
// average), each time with a new cut. The balancing window must outlive those cuts: restarted
// at each, it never reached its 64 steps and the shares never moved. Here the pad is small, so
// the collapsing column rebuilds its lists more often than once a window, and a cut far from
// the ranges' speeds (0.85 of the work to the first range) has to move towards them.
TEST(ForcePassBalance, SharesMoveWhenTheListsAreRebuiltEveryFewSteps) {
    auto discs = read_xyr(default_db9k_path());
    WorldDef def = db9k_world_def();
    def.threads = 2;
    def.broadphase_margin = 1e-6;
    World w(def);
    w.set_busy_fallback(false);  // (tests run side by side)
    build_db9k(w, discs);
    w.finalize();
    w.run(200);  // the column starts to fall
    const long updates_before = w.broad_phase_stats().updates;
    w.cut_force_pass({0.85, 0.15});
    w.run(640);
    const long updates = w.broad_phase_stats().updates - updates_before;
    ASSERT_GT(updates, 640 / 32) << "the lists were not rebuilt every few steps: the test tests nothing";
    EXPECT_GT(w.force_pass_rebalances(), 0);
    EXPECT_LT(w.force_pass_shares()[0], 0.75) << "after " << updates << " list rebuilds in 640 steps";
}

TEST(ForcePassBalance, CutSharesAreChecked) {
    auto discs = read_xyr(default_db9k_path());
    WorldDef def = db9k_world_def();
    def.threads = 2;
    World w(def);
    build_db9k(w, discs);
    w.finalize();
    EXPECT_THROW(w.cut_force_pass({1.0}), InputError);             // one share per range
    EXPECT_THROW(w.cut_force_pass({0.7, 0.7}), InputError);        // sum 1
    EXPECT_THROW(w.cut_force_pass({1.2, -0.2}), InputError);       // each >= 0
    EXPECT_THROW(w.cut_force_pass({1.0, NAN}), InputError);        // finite
    EXPECT_NO_THROW(w.cut_force_pass({0.3, 0.7}));
    EXPECT_DOUBLE_EQ(w.force_pass_shares()[0], 0.3);
}

TEST(Determinism, SameSetUpSameStateHash) {
    auto discs = read_xyr(default_db9k_path());
    discs.resize(1500);
    uint64_t h[2];
    for (int k = 0; k < 2; ++k) {
        World w(db9k_world_def());
        build_db9k(w, discs);
        w.finalize();
        w.run(1500);
        h[k] = state_hash(w);
    }
    EXPECT_EQ(h[0], h[1]);
}
