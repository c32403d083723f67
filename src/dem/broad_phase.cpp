#include "dem/broad_phase.h"

#include <algorithm>
#include <cmath>

#include "core/thread_pool.h"

namespace demlab {

namespace {
// user data of a tree proxy: (index << 1) | kind, kind 0 = disc, 1 = wall piece
inline void* encode(int32_t index, int kind) { return reinterpret_cast<void*>((uintptr_t(index) << 1) | uintptr_t(kind)); }

// float bound no greater (lower) / no smaller (upper) than the double value
inline float round_down(double v) {
    float f = float(v);
    return double(f) > v ? std::nextafter(f, -INFINITY) : f;
}
inline float round_up(double v) {
    float f = float(v);
    return double(f) < v ? std::nextafter(f, INFINITY) : f;
}

struct Collector {
    std::vector<int32_t>* hits;
    const b2DynamicTree* tree;
    bool QueryCallback(int32 proxy) {
        hits->push_back(int32_t(reinterpret_cast<uintptr_t>(tree->GetUserData(proxy))));
        return true;
    }
};

inline bool contains(const Vec2& flo, const Vec2& fhi, const Vec2& lo, const Vec2& hi) {
    return flo.x() <= lo.x() && flo.y() <= lo.y() && hi.x() <= fhi.x() && hi.y() <= fhi.y();
}
}  // namespace

b2AABB BroadPhase::to_tree(const Vec2& lo, const Vec2& hi) const {
    b2AABB box;
    box.lowerBound.Set(round_down(lo.x() * scale_), round_down(lo.y() * scale_));
    box.upperBound.Set(round_up(hi.x() * scale_), round_up(hi.y() * scale_));
    return box;
}

void BroadPhase::read_fat(const b2DynamicTree& tree, int32_t proxy, Vec2& lo, Vec2& hi) const {
    const b2AABB& f = tree.GetFatAABB(proxy);
    // scale_ is a power of two: these divisions are exact
    lo = Vec2(double(f.lowerBound.x) / scale_, double(f.lowerBound.y) / scale_);
    hi = Vec2(double(f.upperBound.x) / scale_, double(f.upperBound.y) / scale_);
}

void BroadPhase::query(const Vec2& lo, const Vec2& hi, std::vector<int32_t>& hits) const {
    hits.clear();
    // the stored fat boxes are exactly representable in tree units
    b2AABB box;
    box.lowerBound.Set(float(lo.x() * scale_), float(lo.y() * scale_));
    box.upperBound.Set(float(hi.x() * scale_), float(hi.y() * scale_));
    for (size_t t = 0; t < tree_count_; ++t) {
        const b2DynamicTree& tree = trees_[t].tree;
        Collector c{&hits, &tree};
        tree.Query(&c, box);
    }
}

// Read-only on the tree and the boxes (the re-insertions are done), so the threads can share
// the escaped discs. A pair of two escaped discs is taken from the lower index. The discs are
// queried in groups (kQueryGroup): one walk for the group's union box, then each disc keeps
// the hits whose fat box overlaps its own, tested as b2TestOverlap does (the boxes are the
// tree's float boxes over a power of two, exact in doubles, and comparisons are exact), so
// each disc gets the leaves its own walk would have reported.
void BroadPhase::query_escaped(size_t begin, size_t end, QueryChunk& out) const {
    out.dd.clear();
    out.dw.clear();
    out.walks = 0;
    for (size_t e = begin; e < end;) {
        const int32_t first = escaped_list_[e];
        Vec2 ulo = fat_lo_[size_t(first)], uhi = fat_hi_[size_t(first)];
        const Vec2 span = kQueryGroupSpan * (uhi - ulo);
        size_t g = e + 1;
        for (; g < end && g - e < query_group_; ++g) {
            const size_t i = size_t(escaped_list_[g]);
            const Vec2 lo = ulo.cwiseMin(fat_lo_[i]), hi = uhi.cwiseMax(fat_hi_[i]);
            if (hi.x() - lo.x() > span.x() || hi.y() - lo.y() > span.y()) break;
            ulo = lo;
            uhi = hi;
        }
        query(ulo, uhi, out.hits);
        ++out.walks;
        for (size_t k = e; k < g; ++k) {
            const int32_t i = escaped_list_[k];
            const Vec2 lo = fat_lo_[size_t(i)], hi = fat_hi_[size_t(i)];
            for (int32_t code : out.hits) {
                const int32_t idx = code >> 1;
                const Vec2& hlo = (code & 1) ? pieces_[size_t(idx)].fat_lo : fat_lo_[size_t(idx)];
                const Vec2& hhi = (code & 1) ? pieces_[size_t(idx)].fat_hi : fat_hi_[size_t(idx)];
                // b2TestOverlap(hit, box): apart if one lies beyond the other in x or y
                if (lo.x() > hhi.x() || lo.y() > hhi.y() || hlo.x() > hi.x() || hlo.y() > hi.y()) continue;
                if (code & 1) {
                    out.dw.push_back(pair_key(i, pieces_[size_t(idx)].wall));
                } else if (idx != i && !(escaped_[size_t(idx)] && idx < i) && may_touch(i, idx)) {
                    out.dd.push_back(idx < i ? pair_key(idx, i) : pair_key(i, idx));
                }
            }
        }
        e = g;
    }
    out.queries = long(end - begin);
    std::sort(out.dd.begin(), out.dd.end());
}

// Can discs i and j touch while each stays inside its fat box? The fat boxes of a dense pack
// overlap for many pairs that cannot: two discs side by side diagonally have overlapping
// boxes with a gap between the discs (in the flume's flow 45 % of the candidates never touch
// with the box test alone; docs/performance.md). While disc i is inside its fat box (World
// re-inserts it when it is not), its centre lies in the box shrunk by its radius, C_i. The
// discs can touch only if the distance between C_i and C_j is below r_i + r_j. Dropping the
// other pairs changes no bit of the run: a candidate that does not touch adds nothing, and
// the kernel resets its history just as a new candidate starts with none. The slack (1e-9
// relative, 1e-12 m) covers the rounding of the boxes and of p - r in the containment test.
bool BroadPhase::may_touch(int32_t i, int32_t j) const {
    const double ri = box_radius_[size_t(i)], rj = box_radius_[size_t(j)];
    const Vec2 lo_i = fat_lo_[size_t(i)] + Vec2(ri, ri), hi_i = fat_hi_[size_t(i)] - Vec2(ri, ri);
    const Vec2 lo_j = fat_lo_[size_t(j)] + Vec2(rj, rj), hi_j = fat_hi_[size_t(j)] - Vec2(rj, rj);
    const double gx = std::max({0.0, lo_j.x() - hi_i.x(), lo_i.x() - hi_j.x()});
    const double gy = std::max({0.0, lo_j.y() - hi_i.y(), lo_i.y() - hi_j.y()});
    const double reach = (ri + rj) * (1.0 + 1e-9) + 1e-12;
    return gx * gx + gy * gy < reach * reach;
}

bool BroadPhase::pad_too_wide(size_t i, const Vec2& v, double dt) const {
    return 2.0 * half_pad_[i] > kShrinkPadRatio * pad_for(v, dt);
}

double BroadPhase::pad_for(const Vec2& v, double dt) const {
    const double wanted = std::sqrt(v.norm() * dt * reach_length_);
    return wanted > margin_ ? std::min(wanted, kMaxMarginFactor * margin_) : margin_;  // NaN: the margin
}

void BroadPhase::init(double margin_target, double wall_piece_length, const std::vector<Vec2>& pos,
                      const std::vector<double>& radius, const std::vector<WallGeom>& walls,
                      const std::vector<uint8_t>& wall_active) {
    // b2_aabbExtension (0.1 tree units) = margin in metres  =>  scale = 0.1 / margin
    // a second init (a restored checkpoint) starts from an empty tree
    for (size_t i = 0; i < disc_proxy_.size(); ++i) tree_of(i).DestroyProxy(disc_proxy_[i]);
    for (const Piece& pc : pieces_)
        if (pc.proxy >= 0) trees_[0].tree.DestroyProxy(pc.proxy);
    const int k = int(std::lround(std::log2(0.1 / margin_target)));
    scale_ = std::ldexp(1.0, k);
    margin_ = double(0.1f) / scale_;

    const size_t n = pos.size();
    tree_count_ = pool_ && pool_->shares(n) ? std::min(kMaxTrees, kTreesPerThread * size_t(pool_->size())) : 1;
    tree_size_ = std::max<size_t>(1, (n + tree_count_ - 1) / tree_count_);
    disc_proxy_.resize(n);
    fat_lo_.resize(n);
    fat_hi_.resize(n);
    box_radius_.assign(radius.begin(), radius.end());
    half_pad_.assign(n, 0.5 * margin_);
    reach_length_ = n > 0 ? kReachRadii * *std::min_element(radius.begin(), radius.end()) : 0.0;
    escaped_.assign(n, 1);  // every disc is new: query them all
    escaped_list_.clear();
    for (size_t i = 0; i < n; ++i) {
        const Vec2 rr(radius[i], radius[i]);
        disc_proxy_[i] = tree_of(i).CreateProxy(to_tree(pos[i] - rr, pos[i] + rr), encode(int32_t(i), 0));
        read_fat(tree_of(i), disc_proxy_[i], fat_lo_[i], fat_hi_[i]);
        escaped_list_.push_back(int32_t(i));
    }
    pieces_.clear();
    wall_first_piece_.assign(walls.size() + 1, 0);
    for (size_t w = 0; w < walls.size(); ++w) {
        wall_first_piece_[w] = pieces_.size();
        const int np = std::max(1, int(std::ceil(wall_length(walls[w]) / wall_piece_length)));
        for (int p = 0; p < np; ++p) {
            Piece pc{int32_t(w), double(p) / np, double(p + 1) / np, -1, Vec2::Zero(), Vec2::Zero()};
            if (wall_active[w]) {
                Vec2 lo, hi;
                wall_piece_bounds(walls[w], pc.f0, pc.f1, lo, hi);
                pc.proxy = trees_[0].tree.CreateProxy(to_tree(lo, hi), encode(int32_t(pieces_.size()), 1));
                read_fat(trees_[0].tree, pc.proxy, pc.fat_lo, pc.fat_hi);
            }
            pieces_.push_back(pc);
        }
    }
    wall_first_piece_[walls.size()] = pieces_.size();
    dd_.clear();
    dw_.clear();
    // every disc is escaped: the query part of update() finds every pair
    scratch_dd_.clear();
    scratch_dw_.clear();
    query_all_escaped();
    std::sort(scratch_dw_.begin(), scratch_dw_.end());
    scratch_dw_.erase(std::unique(scratch_dw_.begin(), scratch_dw_.end()), scratch_dw_.end());
    dd_.swap(scratch_dd_);
    dw_.swap(scratch_dw_);
    std::fill(escaped_.begin(), escaped_.end(), 0);
    escaped_list_.clear();
    ++stats_.updates;
}

// The escaped discs' candidates, appended to scratch_dd_ (kept in key order: what it held
// must be sorted) and scratch_dw_ (unsorted). Each thread takes a contiguous part of
// escaped_list_ and sorts its pairs; the parts are merged in key order, so the list does not
// depend on the number of threads.
void BroadPhase::query_all_escaped() {
    const size_t n = escaped_list_.size();
    const int threads = pool_ && n >= kMinSharedQueries ? pool_->size() : 1;
    if (chunks_.size() < size_t(threads)) chunks_.resize(size_t(threads));
    auto part = [&](int k) {
        query_escaped(n * size_t(k) / size_t(threads), n * size_t(k + 1) / size_t(threads), chunks_[size_t(k)]);
    };
    if (threads == 1)
        part(0);
    else
        pool_->for_each_thread(part);
    for (int k = 0; k < threads; ++k) {
        const QueryChunk& c = chunks_[size_t(k)];
        // into a kept buffer: std::inplace_merge takes a temporary buffer from the heap each
        // time (a few hundred kB: fresh pages from the kernel at every update)
        merge_buffer_.resize(scratch_dd_.size() + c.dd.size());
        std::merge(scratch_dd_.begin(), scratch_dd_.end(), c.dd.begin(), c.dd.end(), merge_buffer_.begin());
        scratch_dd_.swap(merge_buffer_);
        scratch_dw_.insert(scratch_dw_.end(), c.dw.begin(), c.dw.end());
        stats_.queries += c.queries;
        stats_.tree_walks += c.walks;
        if (threads > 1) stats_.shared_queries += c.queries;
    }
}

void BroadPhase::reinsert_escaped(size_t begin, size_t end, const std::vector<Vec2>& pos,
                                  const std::vector<double>& radius, const std::vector<Vec2>* vel, double dt) {
    for (size_t e = begin; e < end; ++e) {
        const size_t i = size_t(escaped_list_[e]);
        b2DynamicTree& tree = tree_of(i);
        const Vec2 rr(radius[i], radius[i]);
        // the pad from the disc's speed: the box grows by `extra`, the tree adds the margin
        const double pad = pad_for(vel ? (*vel)[i] : Vec2::Zero(), dt);
        const double extra = pad - margin_;
        half_pad_[i] = 0.5 * pad;
        const Vec2 lo = pos[i] - rr - Vec2(extra, extra), hi = pos[i] + rr + Vec2(extra, extra);
        // MoveProxy keeps the old fat box of a disc that has not left it yet: re-create those
        if (contains(fat_lo_[i], fat_hi_[i], pos[i] - rr, pos[i] + rr)) {
            tree.DestroyProxy(disc_proxy_[i]);
            disc_proxy_[i] = tree.CreateProxy(to_tree(lo, hi), encode(int32_t(i), 0));
        } else {
            tree.MoveProxy(disc_proxy_[i], to_tree(lo, hi), b2Vec2(0.0f, 0.0f));
        }
        read_fat(tree, disc_proxy_[i], fat_lo_[i], fat_hi_[i]);
        box_radius_[i] = radius[i];
        escaped_[i] = 1;
    }
}

// escaped_list_ is in index order, so each tree's escaped discs are a stretch of it. Thread k
// takes the trees from thread_first_tree_[k] on: the tree boundary nearest to k / threads of
// the escaped discs.
void BroadPhase::reinsert_all_escaped(const std::vector<Vec2>& pos, const std::vector<double>& radius,
                                      const std::vector<Vec2>* vel, double dt) {
    const size_t total = escaped_list_.size();
    const size_t threads = pool_ && tree_count_ > 1 ? size_t(pool_->size()) : 1;
    if (threads == 1 || total < kMinSharedReinserts * threads) {
        reinsert_escaped(0, total, pos, radius, vel, dt);
        return;
    }
    tree_escapes_.resize(tree_count_ + 1);
    tree_escapes_[0] = 0;
    for (size_t t = 1; t <= tree_count_; ++t)
        tree_escapes_[t] = size_t(std::lower_bound(escaped_list_.begin() + ptrdiff_t(tree_escapes_[t - 1]), escaped_list_.end(),
                                                   int32_t(std::min(t * tree_size_, disc_proxy_.size()))) -
                                  escaped_list_.begin());
    thread_first_tree_.assign(threads + 1, tree_count_);
    thread_first_tree_[0] = 0;
    size_t b = 0;
    for (size_t k = 1; k < threads; ++k) {
        const size_t target = total * k / threads;
        const auto off = [&](size_t tree) {
            const size_t at = tree_escapes_[tree];
            return at > target ? at - target : target - at;
        };
        while (b < tree_count_ && off(b + 1) <= off(b)) ++b;  // the boundaries' escapes only grow
        thread_first_tree_[k] = b;
    }
    pool_->for_each_thread([&](int k) {
        const size_t first = thread_first_tree_[size_t(k)], last = thread_first_tree_[size_t(k) + 1];
        reinsert_escaped(tree_escapes_[first], tree_escapes_[last], pos, radius, vel, dt);
    });
    size_t most = 0;
    for (size_t k = 0; k < threads; ++k)
        most = std::max(most, tree_escapes_[thread_first_tree_[k + 1]] - tree_escapes_[thread_first_tree_[k]]);
    stats_.shared_reinserts += long(total);
    stats_.shared_reinserts_most += long(most);
}

bool BroadPhase::update(const std::vector<Vec2>& pos, const std::vector<double>& radius,
                        const std::vector<WallGeom>& walls, const std::vector<uint8_t>& wall_active,
                        const std::vector<uint8_t>& wall_moving, bool discs_may_have_escaped,
                        const std::vector<Vec2>* vel, double dt, bool check_pads) {
    // walls: removed ones leave the tree; moving ones are re-inserted whole when any of
    // their pieces leaves its fat box
    std::vector<uint8_t>& changed = wall_changed_;  // kept between steps: no allocation in the step
    changed.assign(walls.size(), 0);
    bool any_wall = false;
    // only the pieces of walls removed or moving (a flume has hundreds of pieces, all still);
    // a wall's pieces are all in the tree or none
    for (size_t w = 0; w < walls.size(); ++w) {
        if (pieces_[wall_first_piece_[w]].proxy < 0 || (wall_active[w] && !wall_moving[w])) continue;
        for (size_t p = wall_first_piece_[w]; p < wall_first_piece_[w + 1]; ++p) {
            Piece& pc = pieces_[p];
            if (!wall_active[w]) {  // removed: out of the tree
                trees_[0].tree.DestroyProxy(pc.proxy);
                pc.proxy = -1;
                changed[w] = 1;
                any_wall = true;
                continue;
            }
            Vec2 lo, hi;  // moving: a piece that left its fat box
            wall_piece_bounds(walls[w], pc.f0, pc.f1, lo, hi);
            if (!contains(pc.fat_lo, pc.fat_hi, lo, hi)) {
                changed[w] = 1;
                any_wall = true;
            }
        }
    }

    escaped_list_.clear();
    const size_t n = pos.size();
    if (half_pad_.size() != n) half_pad_.assign(n, 0.5 * margin_);  // discs added since init
    if (discs_may_have_escaped || check_pads)
        for (size_t i = 0; i < n; ++i)
            // a changed radius (World::set_radius) needs a new box and new candidates too
            if (!inside_fat_box(i, pos[i], radius[i]) || radius[i] != box_radius_[i] ||
                (check_pads && pad_too_wide(i, vel ? (*vel)[i] : Vec2::Zero(), dt)))
                escaped_list_.push_back(int32_t(i));
    if (escaped_list_.empty() && !any_wall) return false;
    // An update costs a pass over the candidate list whatever the number of escapes, so batch
    // them: with the escaped discs also re-insert every disc that has used up more than
    // kBatchPadUsed of its pad. The next update then waits until a disc moves the rest of its
    // pad, instead of coming on the next step for the next-fastest disc.
    if (!escaped_list_.empty()) {
        // So is a disc whose pad is more than kShrinkPadRatio times what its speed now asks
        // for (it has slowed down; its box would keep candidates that cost a pass each step).
        for (size_t i = 0; i < n; ++i) {
            const Vec2 rr(radius[i], radius[i]);
            // the fat box less the unused part of the pad a disc may keep: (1 - used) * pad
            const double keep = 2.0 * (1.0 - kBatchPadUsed) * half_pad_[i];
            const Vec2 pad(keep, keep);
            if (!contains(fat_lo_[i] + pad, fat_hi_[i] - pad, pos[i] - rr, pos[i] + rr) ||
                pad_too_wide(i, vel ? (*vel)[i] : Vec2::Zero(), dt))
                escaped_list_.push_back(int32_t(i));
        }
        std::sort(escaped_list_.begin(), escaped_list_.end());
        escaped_list_.erase(std::unique(escaped_list_.begin(), escaped_list_.end()), escaped_list_.end());
    }

    reinsert_all_escaped(pos, radius, vel, dt);
    stats_.disc_reinserts += long(escaped_list_.size());
    for (Piece& pc : pieces_) {
        if (pc.proxy >= 0 && changed[pc.wall]) {
            Vec2 lo, hi;
            wall_piece_bounds(walls[pc.wall], pc.f0, pc.f1, lo, hi);
            trees_[0].tree.MoveProxy(pc.proxy, to_tree(lo, hi), b2Vec2(0.0f, 0.0f));
            read_fat(trees_[0].tree, pc.proxy, pc.fat_lo, pc.fat_hi);
        }
    }

    // keep the pairs whose fat boxes did not change
    scratch_dd_.clear();
    for (uint64_t key : dd_)
        if (!escaped_[key_first(key)] && !escaped_[key_second(key)]) scratch_dd_.push_back(key);
    scratch_dw_.clear();
    for (uint64_t key : dw_)
        if (!escaped_[key_first(key)] && !changed[key_second(key)]) scratch_dw_.push_back(key);

    // query the escaped discs
    query_all_escaped();
    // query the moved walls' pieces for the discs around them
    for (const Piece& pc : pieces_) {
        if (pc.proxy < 0 || !changed[pc.wall]) continue;
        query(pc.fat_lo, pc.fat_hi, hits_);
        ++stats_.queries;
        ++stats_.tree_walks;
        for (int32_t code : hits_)
            if (!(code & 1)) scratch_dw_.push_back(pair_key(code >> 1, pc.wall));
    }

    std::sort(scratch_dw_.begin(), scratch_dw_.end());
    scratch_dw_.erase(std::unique(scratch_dw_.begin(), scratch_dw_.end()), scratch_dw_.end());
    dd_.swap(scratch_dd_);
    dw_.swap(scratch_dw_);

    for (int32_t i : escaped_list_) escaped_[i] = 0;
    ++stats_.updates;
    return true;
}

}  // namespace demlab
