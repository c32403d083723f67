// The broad phase finds every touching pair: its contact set equals a brute-force search.
#include <gtest/gtest.h>

#include <memory>
#include <random>
#include <set>
#include <utility>

#include "helpers.h"

using namespace demlab;
using namespace demlab::test;

namespace {
double uniform(std::mt19937_64& rng, double lo, double hi) { return lo + (hi - lo) * double(rng() >> 11) * 0x1.0p-53; }

using PairSet = std::set<std::pair<int, int>>;

PairSet brute_force_discs(const World& w) {
    PairSet s;
    const auto& p = w.positions();
    const auto& r = w.radii();
    for (size_t i = 0; i < p.size(); ++i)
        for (size_t j = i + 1; j < p.size(); ++j)
            if ((p[j] - p[i]).squaredNorm() < (r[i] + r[j]) * (r[i] + r[j])) s.insert({int(i), int(j)});
    return s;
}

PairSet engine_discs(const World& w) {
    PairSet s;
    const auto& p = w.positions();
    const auto& r = w.radii();
    for (const DiscContact& c : w.disc_contacts()) {
        const size_t i = size_t(c.i), j = size_t(c.j);
        if ((p[j] - p[i]).squaredNorm() < (r[i] + r[j]) * (r[i] + r[j])) s.insert({c.i, c.j});
    }
    return s;
}

PairSet brute_force_walls(const World& w) {
    PairSet s;
    for (size_t i = 0; i < w.disc_count(); ++i)
        for (int k = 0; k < int(w.wall_count()); ++k) {
            WallHit hit;
            if (w.wall_active(k) && disc_wall_contact(w.wall_geom(k), w.positions()[i], w.radii()[i], hit))
                s.insert({int(i), k});
        }
    return s;
}

// A box of dense, random, not overlapping discs (rejection sampling) flying in all
// directions at up to v_max, with a floor, a curved wall and a side wall; finalized.
std::unique_ptr<World> random_flying_world(unsigned seed, size_t count, double r_max, double v_max, int threads = 1,
                                           double r_min = 0.001) {
    WorldDef def;
    def.rotation.model = 2;
    def.rotation.u_rr = 0.0;
    def.threads = threads;
    auto w = std::make_unique<World>(def);
    const int m = w->add_material(material(0.3));
    std::mt19937_64 rng(seed);
    std::vector<Vec2> placed;
    std::vector<double> radii;
    while (placed.size() < count) {
        const double r = uniform(rng, r_min, r_max);
        const Vec2 p(uniform(rng, 0.02, 0.13), uniform(rng, 0.03, 0.15));
        bool free = true;
        for (size_t k = 0; k < placed.size() && free; ++k) free = (placed[k] - p).norm() >= r + radii[k];
        if (!free) continue;
        placed.push_back(p);
        radii.push_back(r);
        w->add_disc({p, r, Vec2(uniform(rng, -v_max, v_max), uniform(rng, -v_max, v_max)), 0, 0, m});
    }
    w->add_wall(segment(*w, Vec2(-0.05, 0.02), Vec2(0.3, 0.0), 0.3, SegmentSolid::Right));
    w->add_wall(arc(*w, Vec2(0.075, 0.35), 0.34, 200, 340, ArcSolid::Outside, 0.3));
    w->add_wall(segment(*w, Vec2(0.0, 0.3), Vec2(0.0, -0.1), 0.3, SegmentSolid::Right));
    w->finalize();
    return w;
}

// The candidate lists, disc-disc pairs then disc-wall ones (discs as -1 - index), in order.
std::vector<std::pair<int, int>> candidate_keys(const World& w) {
    std::vector<std::pair<int, int>> k;
    for (const DiscContact& c : w.disc_contacts()) k.push_back({c.i, c.j});
    for (const WallContact& c : w.wall_contacts()) k.push_back({-1 - c.disc, c.wall});
    return k;
}

PairSet engine_walls(const World& w) {
    PairSet s;
    for (const WallContact& c : w.wall_contacts()) {
        WallHit hit;
        if (w.wall_active(c.wall) &&
            disc_wall_contact(w.wall_geom(c.wall), w.positions()[size_t(c.disc)], w.radii()[size_t(c.disc)], hit))
            s.insert({c.disc, c.wall});
    }
    return s;
}
}  // namespace

TEST(BroadPhase, ContactSetEqualsBruteForceOnRandomConfigurations) {
    for (unsigned seed : {1u, 2u, 3u}) {
        const auto world = random_flying_world(seed, 600, 0.003, 2.0);
        World& w = *world;
        long touching_seen = 0;
        for (int round = 0; round < 10; ++round) {
            w.run(round == 0 ? 1 : 300);
            const PairSet expect_dd = brute_force_discs(w), got_dd = engine_discs(w);
            EXPECT_EQ(got_dd, expect_dd) << "seed " << seed << " round " << round;
            EXPECT_EQ(engine_walls(w), brute_force_walls(w)) << "seed " << seed << " round " << round;
            touching_seen += long(expect_dd.size());
        }
        EXPECT_GT(touching_seen, 50);  // the case has contacts to compare
        EXPECT_GT(w.broad_phase_stats().disc_reinserts, 0);  // discs did leave their fat boxes
    }
}

// The escaped discs' queries are shared among the threads (BroadPhase::query_all_escaped);
// the candidate lists must be the same, pair for pair and in the same order.
TEST(BroadPhase, SharedQueriesGiveTheSameCandidateLists) {
    auto build = [](int threads) { return random_flying_world(7, 700, 0.002, 3.0, threads); };
    auto one = build(1), two = build(2);
    for (int round = 0; round < 8; ++round) {
        ASSERT_EQ(candidate_keys(*one), candidate_keys(*two)) << "round " << round;
        one->run(50);
        two->run(50);
    }
    EXPECT_EQ(one->broad_phase_stats().queries, two->broad_phase_stats().queries);
    EXPECT_EQ(one->broad_phase_stats().shared_queries, 0);
    // beyond the first build's 700 queries, updates were shared too
    EXPECT_GT(two->broad_phase_stats().shared_queries, 700 + long(BroadPhase::kMinSharedQueries));
    EXPECT_EQ(one->positions(), two->positions());
}

// From 4,096 discs on, with 2 threads, the discs are in several trees (a range of indices
// each) and each thread re-inserts the escaped discs of whole trees; and the contact list is
// merged by both threads, each from a binary search into the old list. The contacts must
// still be every touching pair, and the lists those of 1 thread, pair for pair.
TEST(BroadPhase, SeveralTreesGiveTheSameCandidateListsAsOne) {
    auto build = [](int threads) { return random_flying_world(11, 5000, 0.0008, 3.0, threads, 0.0004); };
    auto one = build(1), two = build(2);
    long touching_seen = 0;
    for (int round = 0; round < 6; ++round) {
        ASSERT_EQ(candidate_keys(*one), candidate_keys(*two)) << "round " << round;
        const PairSet expect_dd = brute_force_discs(*two);
        EXPECT_EQ(engine_discs(*two), expect_dd) << "round " << round;
        EXPECT_EQ(engine_walls(*two), brute_force_walls(*two)) << "round " << round;
        touching_seen += long(expect_dd.size());
        one->run(60);
        two->run(60);
    }
    EXPECT_GT(touching_seen, 1000);
    EXPECT_EQ(one->broad_phase_stats().shared_reinserts, 0);
    EXPECT_GT(two->broad_phase_stats().shared_reinserts, 2 * long(BroadPhase::kMinSharedReinserts));
    EXPECT_EQ(one->positions(), two->positions());
    EXPECT_EQ(one->velocities(), two->velocities());
}

// The trees are shared out by their escaped discs, not by halves of the indices: when only
// the last quarter of the discs move (a lattice without contacts or gravity, discs numbered
// row by row), one thread must not re-insert them all. With two trees, one per half of the
// indices, the second thread did all of them; on 4 threads each must get about a quarter.
TEST(BroadPhase, ReinsertionsAreSharedWhereTheDiscsEscape) {
    auto build = [](int threads) {
        WorldDef def;
        def.gravity = Vec2::Zero();
        def.threads = threads;
        auto w = std::make_unique<World>(def);
        const int m = w->add_material(material(0.3));
        const int columns = 80, rows = 64;
        for (int row = 0; row < rows; ++row)
            for (int col = 0; col < columns; ++col) {
                const bool moving = row >= 3 * rows / 4;
                const Vec2 v = moving ? Vec2(0.5 * std::cos(0.1 * col), 0.5 * std::sin(0.1 * col)) : Vec2::Zero();
                w->add_disc({Vec2(0.01 * col, 0.01 * row), 0.002, v, 0, 0, m});
            }
        w->finalize();
        return w;
    };
    auto one = build(1);
    one->run(400);
    // 2 threads: the busiest at most 60 %; 4 threads, 16 trees: the moving quarter is 4 trees,
    // one for each thread, so the busiest at most 35 %
    for (const auto& [threads, most_share] : {std::pair{2, 0.6}, std::pair{4, 0.35}}) {
        auto w = build(threads);
        w->run(400);
        const BroadPhaseStats& s = w->broad_phase_stats();
        EXPECT_EQ(s.disc_reinserts, one->broad_phase_stats().disc_reinserts) << threads << " threads";
        EXPECT_GT(s.shared_reinserts, 4 * long(BroadPhase::kMinSharedReinserts)) << threads << " threads";
        EXPECT_LE(double(s.shared_reinserts_most), most_share * double(s.shared_reinserts)) << threads << " threads";
        EXPECT_GE(s.shared_reinserts_most * threads, s.shared_reinserts) << threads << " threads";
        EXPECT_EQ(one->positions(), w->positions()) << threads << " threads";
    }
}

// Walls are cut into pieces for the tree; by default three disc diameters long. A layer of
// discs sliding down a 29-degree slope: with 5 cm pieces (the old default) the pieces' boxes
// held 5.5 times as many discs as touch the slope, with the default 2.4 times (geometry A's
// flow: 5.5 and 2.1 times).
// The pieces change no candidate that touches, so the run is the same bits.
TEST(BroadPhase, WallPiecesOfThreeDiametersKeepFewDiscWallCandidates) {
    auto build = [](double piece_length) {
        WorldDef def;
        def.wall_piece_length = piece_length;
        auto w = std::make_unique<World>(def);
        const int m = w->add_material(material(0.3));
        const double slope = 29.0 * M_PI / 180.0, r = 0.0015;
        const Vec2 down(std::cos(slope), -std::sin(slope)), up(std::sin(slope), std::cos(slope));
        w->add_wall(segment(*w, Vec2(0, 0), 2.0 * down, 0.3, SegmentSolid::Right));
        for (int row = 0; row < 6; ++row)
            for (int k = 0; k < 200; ++k)
                w->add_disc({(0.1 + 0.0031 * k) * down + (r + 0.0031 * row) * up, r, Vec2::Zero(), 0, 0, m});
        w->finalize();
        return w;
    };
    auto auto_pieces = build(0.0), long_pieces = build(0.05);
    double candidates_auto = 0, candidates_long = 0, touching = 0;
    for (int round = 0; round < 10; ++round) {
        auto_pieces->run(200);
        long_pieces->run(200);
        EXPECT_EQ(engine_walls(*auto_pieces), brute_force_walls(*auto_pieces)) << "round " << round;
        candidates_auto += double(auto_pieces->wall_contacts().size());
        candidates_long += double(long_pieces->wall_contacts().size());
        touching += double(auto_pieces->touching_wall_pairs());
    }
    EXPECT_GT(touching, 10 * 150);  // the bottom row stays on the slope
    EXPECT_LT(candidates_auto, 3.0 * touching);  // measured 2.4 times
    EXPECT_GT(candidates_long, 5.0 * touching);  // measured 5.5 times
    EXPECT_EQ(auto_pieces->positions(), long_pieces->positions());
    EXPECT_EQ(auto_pieces->velocities(), long_pieces->velocities());
}

TEST(BroadPhase, MarginIsAPowerOfTwoFractionOfTheTreePad) {
    WorldDef def;
    def.broadphase_margin = 0.0005;
    World w(def);
    const int m = w.add_material(material(0.3));
    w.add_disc({Vec2(0, 0), 0.001, Vec2::Zero(), 0, 0, m});
    w.finalize();
    // 0.1 / 2^k nearest to 0.5 mm: 2^8 -> 0.39 mm
    EXPECT_NEAR(w.broad_phase_margin(), 0.1 / 256.0, 1e-9);
}

// The candidates are the pairs that can touch while both discs stay in their fat boxes, not
// every pair of overlapping boxes: on a square lattice (r = 1 mm, pitch 2.5 mm, margin
// 0.39 mm) the boxes of diagonal neighbours overlap (the pitch is below 2 r + 2 margin) but
// their centres, each held within 0.39 mm of where it was boxed, stay 2.43 mm > 2 r apart.
TEST(BroadPhase, DiagonalNeighboursWhoseBoxesOverlapAreNotCandidates) {
    WorldDef def;
    def.broadphase_margin = 0.0005;
    def.gravity = Vec2::Zero();
    World w(def);
    const int m = w.add_material(material(0.3));
    const int n = 10;
    for (int a = 0; a < n; ++a)
        for (int b = 0; b < n; ++b) w.add_disc({Vec2(0.0025 * a, 0.0025 * b), 0.001, Vec2::Zero(), 0, 0, m});
    w.finalize();
    ASSERT_NEAR(w.broad_phase_margin(), 0.1 / 256.0, 1e-9);
    // the orthogonal neighbours only: n (n - 1) per direction
    EXPECT_EQ(w.disc_contacts().size(), size_t(2 * n * (n - 1)));
    for (const DiscContact& c : w.disc_contacts()) EXPECT_TRUE(c.j == c.i + 1 || c.j == c.i + n) << c.i << "-" << c.j;
}

// A disc that shrinks keeps its fat box, but its centre may then roam a larger part of it: the
// pairs dropped for its old radius must be looked at again. Disc 0 (r 1 mm at the origin) and
// disc 1 (r 1 mm at 2.2, 2.2 mm) cannot touch from within their boxes (centre boxes 2.008 mm
// apart); after disc 0 shrinks to 0.5 mm both can move inside their boxes to 1.41 mm apart,
// below the new sum of radii, 1.5 mm.
TEST(BroadPhase, AShrunkDiscGetsItsCandidatesAgain) {
    WorldDef def;
    def.broadphase_margin = 0.0005;
    def.gravity = Vec2::Zero();
    World w(def);
    const int m = w.add_material(material(0.3));
    w.add_disc({Vec2(0.0, 0.0), 0.001, Vec2::Zero(), 0, 0, m});
    w.add_disc({Vec2(0.0022, 0.0022), 0.001, Vec2::Zero(), 0, 0, m});
    w.finalize();
    ASSERT_NEAR(w.broad_phase_margin(), 0.1 / 256.0, 1e-9);
    EXPECT_TRUE(w.disc_contacts().empty());
    w.set_radius(0, 0.0005);
    w.refresh_dashpots();
    // both still inside their fat boxes (0.39 mm pad), so neither is re-inserted for moving
    w.set_position(0, Vec2(0.00085, 0.00085));
    w.set_position(1, Vec2(0.00185, 0.00185));
    w.step();
    ASSERT_EQ(w.disc_contacts().size(), 1u);
    EXPECT_EQ(w.touching_disc_pairs(), 1);
}

// The pads from the discs' speeds (broad_phase.h): r = 1 mm, margin 0.39 mm, L = 400 r_min =
// 0.4 m, dt = 1 us. A still disc keeps the margin; one at 0.5 m/s gets sqrt(0.5e-6 * 0.4) =
// 0.447 mm; one at 100 m/s would get 6.3 mm and is held to 2 margins. When they stop, the
// pad check (World: every kPadCheckSteps steps) gives a pad more than 1.5 margins the margin
// again.
TEST(BroadPhase, PadsFollowTheDiscsSpeeds) {
    const double r = 0.001, dt = 1e-6;
    std::vector<Vec2> pos = {Vec2(0.0, 0.0), Vec2(0.1, 0.0), Vec2(0.2, 0.0)};
    std::vector<Vec2> vel = {Vec2(0.0, 0.0), Vec2(0.3, -0.4), Vec2(0.0, 100.0)};
    const std::vector<double> radius(3, r);
    BroadPhase bp;
    bp.init(0.0005, 1.0, pos, radius, {}, {});
    const double margin = bp.margin();
    ASSERT_NEAR(margin, 0.1 / 256.0, 1e-9);
    auto pad = [&](size_t i) {  // the pad on each side, from the fat box (both axes)
        const double px = 0.5 * (bp.fat_hi(i).x() - bp.fat_lo(i).x()) - r;
        const double py = 0.5 * (bp.fat_hi(i).y() - bp.fat_lo(i).y()) - r;
        EXPECT_NEAR(px, py, 1e-7);
        return px;
    };
    for (size_t i = 0; i < 3; ++i) EXPECT_NEAR(pad(i), margin, 1e-7) << i;  // no speeds at init
    // every disc out of its box: all re-inserted, with the pads their speeds ask for
    for (Vec2& p : pos) p += Vec2(0.002, 0.0);
    ASSERT_TRUE(bp.update(pos, radius, {}, {}, {}, true, &vel, dt));
    EXPECT_NEAR(pad(0), margin, 1e-7);
    EXPECT_NEAR(pad(1), std::sqrt(0.5 * dt * 0.4), 1e-7);
    EXPECT_NEAR(pad(2), BroadPhase::kMaxMarginFactor * margin, 1e-7);
    for (size_t i = 0; i < 3; ++i) EXPECT_TRUE(bp.inside_fat_box(i, pos[i], r)) << i;
    // all stop where they are: nothing escaped, so an update without the pad check does nothing;
    // with it, disc 2, whose pad is more than 1.5 times what it now needs, gets the margin
    // (disc 1's pad is within 1.5 margins)
    for (Vec2& v : vel) v = Vec2::Zero();
    EXPECT_FALSE(bp.update(pos, radius, {}, {}, {}, true, &vel, dt, false));
    EXPECT_NEAR(pad(2), BroadPhase::kMaxMarginFactor * margin, 1e-7);
    ASSERT_TRUE(bp.update(pos, radius, {}, {}, {}, false, &vel, dt, true));
    EXPECT_NEAR(pad(0), margin, 1e-7);
    EXPECT_NEAR(pad(1), std::sqrt(0.5 * dt * 0.4), 1e-7);
    EXPECT_NEAR(pad(2), margin, 1e-7);
    EXPECT_EQ(bp.stats().disc_reinserts, 3 + 1);
    EXPECT_FALSE(bp.update(pos, radius, {}, {}, {}, false, &vel, dt, true));  // nothing more to do
}

// Escaped discs are queried in groups, one walk of the tree for a group's union box
// (BroadPhase::query_escaped): the candidate lists are those of a walk per disc, update after
// update. The discs are numbered in space order (rows of a jittered grid), so groups form.
TEST(BroadPhase, GroupedQueriesGiveTheSameCandidateLists) {
    std::mt19937_64 rng(3);
    const size_t side = 40;
    const double r_max = 0.0015;
    std::vector<Vec2> pos, vel;
    std::vector<double> radius;
    for (size_t k = 0; k < side * side; ++k) {
        pos.emplace_back(0.0035 * double(k % side) + uniform(rng, 0.0, 0.0008), 0.0035 * double(k / side) + uniform(rng, 0.0, 0.0008));
        radius.push_back(uniform(rng, 0.001, r_max));
        vel.emplace_back(uniform(rng, -0.5, 0.5), uniform(rng, -0.5, 0.5));
    }
    const std::vector<WallGeom> walls = {make_geom(segment(Vec2(-0.01, -0.002), Vec2(0.17, -0.002), SegmentSolid::Right))};
    const std::vector<uint8_t> active = {1}, moving = {0};
    BroadPhase one, grouped;
    one.set_query_group(1);
    for (BroadPhase* b : {&one, &grouped}) b->init(0.0005, 0.05, pos, radius, walls, active);
    ASSERT_EQ(one.disc_pairs(), grouped.disc_pairs());
    ASSERT_EQ(one.wall_pairs(), grouped.wall_pairs());
    const double dt = 2e-5;
    int updates = 0;
    for (int step = 0; step < 1500; ++step) {
        for (size_t k = 0; k < pos.size(); ++k) pos[k] += vel[k] * dt;
        const bool a = one.update(pos, radius, walls, active, moving, true, &vel, dt, step % 32 == 0);
        const bool b = grouped.update(pos, radius, walls, active, moving, true, &vel, dt, step % 32 == 0);
        ASSERT_EQ(a, b) << "step " << step;
        if (!a) continue;
        ++updates;
        ASSERT_EQ(one.disc_pairs(), grouped.disc_pairs()) << "step " << step;
        ASSERT_EQ(one.wall_pairs(), grouped.wall_pairs()) << "step " << step;
    }
    EXPECT_GT(updates, 15);
    EXPECT_GT(grouped.disc_pairs().size(), 2 * pos.size());
    EXPECT_FALSE(grouped.wall_pairs().empty());
    // the groups formed: fewer walks than queries (one walk a disc without them)
    EXPECT_EQ(one.stats().tree_walks, one.stats().queries);
    EXPECT_LT(grouped.stats().tree_walks, grouped.stats().queries / 2);
    EXPECT_EQ(grouped.stats().queries, one.stats().queries);
}
