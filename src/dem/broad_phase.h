// Broad phase: Box2D's b2DynamicTree holds one proxy per disc and a few per wall (long walls
// are cut into pieces so that a slope's bounding box does not cover the whole mass). The tree
// only answers "which fat boxes overlap"; the physics is ours. With 2 threads or more the
// discs are held in several trees, a range of indices each, so that the re-insertions are
// shared (trees_ below).
//
// Fat boxes: the tree pads every box by b2_aabbExtension = 0.1 tree units. We choose the
// units: tree coordinate = metres * scale with scale a power of two, so the pad is
// 0.1 / scale metres (the margin) and converting the tree's float boxes back to metres is
// exact. A disc is re-inserted only when its tight box leaves its fat box.
//
// Margins from the discs' speeds: a disc is inserted with its box grown by an extra pad
// before the tree adds the margin, so that its whole pad is
//     m_i = clamp(sqrt(|v_i| dt L), margin, kMaxMarginFactor margin),  L = kReachRadii r_min.
// Why the square root: a disc re-inserted costs c_r (remove, insert, query: about 1.5 us),
// and it escapes after m / (|v| dt) steps, so c_r |v| dt / m per step; its pad adds
// candidates in proportion to m, each costing c_p per step (the kernel's first pass: a few
// ns). The sum is least for m^2 = (c_r / c_p) (|v| dt) (r / beta), beta the candidates per
// disc a pad of one radius adds; L = kReachRadii r_min stands for (c_r / c_p) (r / beta),
// measured on DB-9k (docs/performance.md). A still disc keeps the margin; a fast
// one waits longer before it escapes. The candidates do not change any result (may_touch).
// The pad is held to kMaxMarginFactor = 2 margins. c_p is not the same everywhere: once the
// step's arrays outgrow the caches (the real sand size, 145,615 discs) a candidate costs a
// miss. There the flow's fast discs (1 m/s) asked for pads that held 740,000-760,000
// candidate pairs at 5 margins against 497,000 at 2 (168,000 of them touching; geometry A at
// scale 1, t = 0.85 s), while the list updates took 7 % of the step at 5 margins and 10 % at
// 2. At 2 margins that step ran faster, and DB-9k and the scale-4 flow no slower
// (docs/performance.md).
// A disc whose pad is more than kShrinkPadRatio times what its speed asks for is re-inserted
// with the narrower pad at the next update (or the next pad check, World::step), so that a
// mass come to rest goes back to the margin.
//
// Candidate pairs: every pair of discs (and disc-wall) whose fat boxes overlap, less the disc
// pairs that cannot touch while both discs stay in their fat boxes (may_touch). The set is
// kept between updates: pairs of two discs that did not escape stay as they are (their fat
// boxes did not change), and only the escaped discs are queried. The lists are sorted by
// key, so the contact loop's order does not depend on the tree's internal layout.
#pragma once
#include <memory>
#include <box2d/b2_dynamic_tree.h>

#include <algorithm>
#include <cstdint>
#include <vector>

#include "core/vec2.h"
#include "geometry/wall.h"

namespace demlab {

class ThreadPool;

inline uint64_t pair_key(int32_t a, int32_t b) { return (uint64_t(uint32_t(a)) << 32) | uint32_t(b); }
inline int32_t key_first(uint64_t k) { return int32_t(k >> 32); }
inline int32_t key_second(uint64_t k) { return int32_t(k & 0xffffffffu); }

struct BroadPhaseStats {
    long updates = 0;          // calls to update() that changed the candidate lists
    long disc_reinserts = 0;   // discs re-inserted after leaving their fat box
    long queries = 0;          // escaped discs (and moved wall pieces) whose candidates were queried
    long shared_queries = 0;   // of these, queries shared out among the pool's threads
    long shared_reinserts = 0; // re-insertions shared out among the pool's threads, whole trees each
    long shared_reinserts_most = 0;  // of these, the busiest thread's, summed over the updates
    long tree_walks = 0;       // walks of the tree for them (a group of escaped discs walks once)
};

class BroadPhase {
public:
    // margin_target: desired pad around each disc, m (> 0). The actual margin is the nearest
    // 0.1 / 2^k (see margin()). wall_piece_length: the longest wall piece, m.
    void init(double margin_target, double wall_piece_length, const std::vector<Vec2>& pos,
              const std::vector<double>& radius, const std::vector<WallGeom>& walls,
              const std::vector<uint8_t>& wall_active);

    // Re-inserts escaped discs and moved walls' pieces, drops removed walls, and refreshes
    // the candidate lists. Returns true if the lists changed.
    // discs_may_have_escaped = false skips the scan of the discs (the caller has checked
    // inside_fat_box() for every disc that moved).
    // vel, dt: the discs' velocities (m/s) and the step (s), for the re-inserted discs' pads
    // (nullptr: every pad is the margin). check_pads: also re-insert the discs whose pads are
    // over kShrinkPadRatio times what their speeds ask for, even if none escaped (a pile come
    // to rest would otherwise keep the wide boxes, and their candidates, of its flow).
    bool update(const std::vector<Vec2>& pos, const std::vector<double>& radius,
                const std::vector<WallGeom>& walls, const std::vector<uint8_t>& wall_active,
                const std::vector<uint8_t>& wall_moving, bool discs_may_have_escaped = true,
                const std::vector<Vec2>* vel = nullptr, double dt = 0.0, bool check_pads = false);

    // The speed rule's constants (see the top of this file).
    static constexpr double kReachRadii = 400.0;     // L / r_min
    static constexpr double kMaxMarginFactor = 2.0;  // the largest pad, in margins
    static constexpr double kShrinkPadRatio = 1.5;   // a pad wider than this times the asked one is shrunk

    // Is disc i (centre p, radius r) still inside its fat box? Thread-safe (read-only).
    bool inside_fat_box(size_t i, const Vec2& p, double r) const {
        return fat_lo_[i].x() <= p.x() - r && fat_lo_[i].y() <= p.y() - r && p.x() + r <= fat_hi_[i].x() &&
               p.y() + r <= fat_hi_[i].y();
    }

    // Sorted, unique keys pair_key(i, j) with i < j.
    const std::vector<uint64_t>& disc_pairs() const { return dd_; }
    // Sorted, unique keys pair_key(disc, wall).
    const std::vector<uint64_t>& wall_pairs() const { return dw_; }

    double margin() const { return margin_; }
    // Disc i's fat box, m.
    Vec2 fat_lo(size_t i) const { return fat_lo_[i]; }
    Vec2 fat_hi(size_t i) const { return fat_hi_[i]; }
    // The same as arrays (valid until the next init or update), for the integration's loop.
    const Vec2* fat_lo_data() const { return fat_lo_.data(); }
    const Vec2* fat_hi_data() const { return fat_hi_.data(); }
    const BroadPhaseStats& stats() const { return stats_; }

    // Shares the escaped discs' queries among the pool's threads (nullptr: the caller alone).
    // The lists are the same: each thread's pairs are sorted and merged in key order.
    void set_pool(ThreadPool* pool) { pool_ = pool; }
    // Fewer escaped discs than this are queried by the caller alone: a query costs about a
    // microsecond, the hand-over tens of them when the other thread has gone to sleep.
    static constexpr size_t kMinSharedQueries = 256;
    // Fewer escaped discs than this per thread are re-inserted by the caller alone.
    static constexpr size_t kMinSharedReinserts = 64;
    // Escaped discs per walk of the tree, at most (kQueryGroup below; 1: a walk per disc). For
    // tests and measurements: no candidate depends on it.
    void set_query_group(size_t n) { query_group_ = n < 1 ? 1 : n; }

private:
    struct Piece {
        int32_t wall;
        double f0, f1;
        int32_t proxy;
        Vec2 fat_lo, fat_hi;
    };
    b2AABB to_tree(const Vec2& lo, const Vec2& hi) const;
    void read_fat(const b2DynamicTree& tree, int32_t proxy, Vec2& lo, Vec2& hi) const;
    void query(const Vec2& lo, const Vec2& hi, std::vector<int32_t>& hits) const;
    bool may_touch(int32_t i, int32_t j) const;
    double pad_for(const Vec2& v, double dt) const;  // m, the speed rule's pad
    bool pad_too_wide(size_t i, const Vec2& v, double dt) const;  // pad over kShrinkPadRatio times pad_for
    // the candidates of escaped discs escaped_list_[begin, end) into `out` (pairs sorted)
    struct QueryChunk {
        std::vector<int32_t> hits;
        std::vector<uint64_t> dd, dw;
        long queries = 0, walks = 0;
    };
    // The escaped discs are queried in groups of consecutive ones (in index order, which is
    // space order for a generated mass) whose fat boxes' union stays within kQueryGroupSpan
    // times the first box in x and y, up to kQueryGroup of them: one walk of the tree for the
    // union, then each disc takes the hits that overlap its own box (the tree's own test on
    // the same float boxes, so the candidates are the same). A walk cost about 1.3 us, most of
    // it the descent through a tree of about a megabyte (docs/performance.md).
    static constexpr size_t kQueryGroup = 8;
    // A list update also re-inserts every disc that has used more than this share of its
    // pad. Measured (the candidates do not change, the bits neither): at 0.5,
    // DB-9k made 100 updates with 305k re-insertions in 0.56-0.61 s on 1 thread, at 0.35 55
    // updates with 363k in 0.48-0.50 s; geometry A to t = 0.3 s on 2 threads 3,984 updates in
    // 2.31 s at 0.5, 3,752 in 1.85 / 1.78 / 1.91 / 1.98 s at 0.4 / 0.35 / 0.3 / 0.25.
    static constexpr double kBatchPadUsed = 0.35;
    size_t query_group_ = kQueryGroup;
    static constexpr double kQueryGroupSpan = 4.0;
    void query_escaped(size_t begin, size_t end, QueryChunk& out) const;
    void query_all_escaped();

    // kTreesPerThread trees per thread when the pool shares the discs, one otherwise: tree t
    // holds discs [t tree_size_, (t + 1) tree_size_), the wall pieces are in tree 0. The
    // threads re-insert the escaped discs of whole trees each (reinsert_all_escaped), the
    // trees shared out so that each thread gets about as many escaped discs: on 2 threads the
    // re-insertions were the largest serial part of a list update. With two trees, half the
    // indices each, DB-9k's escapes fell 39/61 % between them; with eight the worse thread gets
    // 51 % (docs/performance.md). A query walks every tree; a tree whose discs lie
    // elsewhere costs it the root's test. Which tree holds a disc changes no candidate: the
    // lists are the overlap tests' answers, sorted.
    //
    // Each tree is alone on its cache lines (PaddedTree): a b2DynamicTree's root, node count
    // and free list sit in a few bytes that every insertion writes, and two trees side by side
    // shared a line between the two threads re-inserting into them. That cost each
    // re-insertion 40-80 % more on 2 threads than on 1 (DB-9k: 0.96 and 0.74 us against
    // 0.52 us).
    static constexpr size_t kTreesPerThread = 4;
    static constexpr size_t kMaxTrees = 64;
    struct alignas(64) PaddedTree {
        b2DynamicTree tree;
    };
    // On the heap, so that moving a World moves the pointer: a b2DynamicTree owns its nodes
    // through a raw pointer and has no move of its own, so a tree moved by value would leave
    // two owners of the same nodes.
    std::unique_ptr<PaddedTree[]> trees_{new PaddedTree[kMaxTrees]};
    size_t tree_count_ = 1;
    size_t tree_size_ = 1;  // discs per tree (the last may hold fewer)
    b2DynamicTree& tree_of(size_t disc) { return trees_[std::min(disc / tree_size_, tree_count_ - 1)].tree; }
    // re-inserts the escaped discs, the trees shared among the pool's threads
    void reinsert_all_escaped(const std::vector<Vec2>& pos, const std::vector<double>& radius,
                              const std::vector<Vec2>* vel, double dt);
    std::vector<size_t> tree_escapes_;  // where each tree's escaped discs begin in escaped_list_, then its end
    std::vector<size_t> thread_first_tree_;
    // re-inserts escaped_list_[begin, end) (discs of one tree)
    void reinsert_escaped(size_t begin, size_t end, const std::vector<Vec2>& pos, const std::vector<double>& radius,
                          const std::vector<Vec2>* vel, double dt);
    double scale_ = 1.0;
    double margin_ = 0.1;
    std::vector<int32_t> disc_proxy_;
    std::vector<Vec2> fat_lo_, fat_hi_;
    std::vector<double> box_radius_;  // the radius each disc's fat box was made for, m
    std::vector<double> half_pad_;    // half the pad each disc's fat box was made with, m
    double reach_length_ = 0.0;       // L of the speed rule, m
    std::vector<Piece> pieces_;                // the walls' pieces, wall by wall
    std::vector<size_t> wall_first_piece_;     // wall w's pieces: [first[w], first[w + 1]), at least one
    std::vector<uint64_t> dd_, dw_, scratch_dd_, scratch_dw_, merge_buffer_;
    std::vector<uint8_t> escaped_;
    std::vector<int32_t> escaped_list_, hits_;
    std::vector<uint8_t> wall_changed_;  // per wall, in update()
    std::vector<QueryChunk> chunks_;     // per thread, kept between updates (no allocation)
    ThreadPool* pool_ = nullptr;
    BroadPhaseStats stats_;
};

}  // namespace demlab
