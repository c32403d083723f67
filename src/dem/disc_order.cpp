// Renumbering the discs in space order (WorldDef::reorder_every, reorder_min_discs).
//
// The release mass starts in space order (space_order.h), so a disc's contacts are near it in
// every per-disc array. The flow scrambles that order: discs shear past each other, and after
// a metre of flume a disc's neighbours lie anywhere in memory. In a world that outgrows the
// cache every contact then waits for its discs' lines; at the real sand size (145,615 discs)
// the step's cost rose from 37 to 56 ns per disc as the flow went on (docs/performance.md).
// Renumbering brings it back; the cost is one sort and a rebuilt broad phase.
//
// What follows a renumbering: every per-disc array, the ids (disc_ids keeps each disc's
// identity for the outputs), the bonds (renumbered, their ends swapped where the new numbers
// invert them, sorted again) and the contacts, whose histories are carried into lists
// rebuilt as a restored checkpoint's are (world_state.cpp). A contact whose discs swap roles
// (i > j after the renumbering) keeps its history as it is: with n and t both reversed, the
// normal and shear velocities, the shear spring force along t and the dashpot forces are the
// same numbers (pair_kernel.h: vn = (vj - vi).n, vs = (vj - vi).t - (wi ri + wj rj)). A
// bond's last dashpot force is on its first disc, so it changes sign when its ends swap.
//
// The physics is the same; the bits are not, because the per-disc sums add the same terms in
// another order. The renumbering depends on the positions and the step count only, so a run
// still gives the same bits for any thread count, and a checkpoint stores the order
// (world_state.cpp).
#include <algorithm>
#include <cmath>
#include <numeric>

#include "dem/space_order.h"
#include "dem/world.h"

namespace demlab {

std::vector<size_t> space_order(const std::vector<Vec2>& pos, double strip) {
    const size_t n = pos.size();
    std::vector<size_t> order(n);
    std::iota(order.begin(), order.end(), size_t(0));
    if (n == 0 || !(strip > 0.0)) return order;
    double x_min = INFINITY;
    for (const Vec2& p : pos) x_min = std::min(x_min, p.x());
    std::vector<long> column(n);
    for (size_t i = 0; i < n; ++i) column[i] = long(std::floor((pos[i].x() - x_min) / strip));
    std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
        if (column[a] != column[b]) return column[a] < column[b];
        return pos[a].y() < pos[b].y();
    });
    return order;
}

void World::index_ids() {
    int32_t top = -1;
    for (int32_t id : id_) top = std::max(top, id);
    // (as long as the largest id ever added: a lost disc's id stays known, as lost)
    index_of_id_.assign(std::max(index_of_id_.size(), size_t(top + 1)), -1);
    for (size_t i = 0; i < id_.size(); ++i) index_of_id_[size_t(id_[i])] = int32_t(i);
}

void World::reorder_in_space() {
    // strips two of the largest diameters wide, as the release's (order_in_space)
    const double r_max = *std::max_element(radius_.begin(), radius_.end());
    const std::vector<size_t> order = space_order(pos_, 4.0 * r_max);
    ++reorders_;
    reorder_discs(order);
}

void World::reorder_discs(const std::vector<size_t>& order) {
    const size_t n = pos_.size();
    if (order.size() != n) throw RunError("reorder_discs: the order has " + std::to_string(order.size()) + " entries for " + std::to_string(n) + " discs");
    std::vector<int32_t> to(n, -1);
    for (size_t k = 0; k < n; ++k) {
        if (order[k] >= n || to[order[k]] >= 0) throw RunError("reorder_discs: the order is not a permutation of the discs");
        to[order[k]] = int32_t(k);
    }
    bool identity = true;
    for (size_t k = 0; k < n && identity; ++k) identity = order[k] == k;
    if (identity) return;
    permute_discs(order);
    // the contacts renumbered, first disc below the second, in key order (rebuild_lists)
    std::vector<DiscContact> dd = dd_;
    for (DiscContact& c : dd) {
        c.i = to[size_t(c.i)];
        c.j = to[size_t(c.j)];
        if (c.i > c.j) std::swap(c.i, c.j);
    }
    std::sort(dd.begin(), dd.end(), [](const DiscContact& a, const DiscContact& b) { return pair_key(a.i, a.j) < pair_key(b.i, b.j); });
    std::vector<WallContact> dw = dw_;
    for (WallContact& c : dw) c.disc = to[size_t(c.disc)];
    std::sort(dw.begin(), dw.end(), [](const WallContact& a, const WallContact& b) { return pair_key(a.disc, a.wall) < pair_key(b.disc, b.wall); });
    rebuild_lists(dd, dw);
}

void World::permute_discs(const std::vector<size_t>& order) {
    const size_t n = pos_.size();
    std::vector<int32_t> to(n);
    for (size_t k = 0; k < n; ++k) to[order[k]] = int32_t(k);
    auto permute = [&](auto& v) {
        if (v.size() != n) return;  // (an array the world does not keep)
        const auto old = v;
        for (size_t k = 0; k < n; ++k) v[k] = old[order[k]];
    };
    permute(pos_);
    permute(vel_);
    permute(radius_);
    permute(mass_);
    permute(inv_mass_);
    permute(inertia_);
    permute(inv_inertia_);
    permute(angle_);
    permute(omega_);
    permute(material_);
    permute(id_);
    permute(rr_factor_);
    permute(load_);
    permute(external_force_);
    permute(wall_reaction_);
    index_ids();
    r_min_stale_ = true;

    if (!bonds_.empty()) {
        struct Entry {
            Bond bond;
            Vec2 dashpot_last;
        };
        std::vector<Entry> entries(bonds_.size());
        for (size_t b = 0; b < bonds_.size(); ++b) {
            Entry& e = entries[b];
            e.bond = bonds_[b];
            e.bond.k = to[size_t(e.bond.k)];
            e.bond.l = to[size_t(e.bond.l)];
            e.dashpot_last = def_.bond.predict ? bond_dashpot_last_[b] : Vec2::Zero();
            if (e.bond.k > e.bond.l) {
                std::swap(e.bond.k, e.bond.l);
                e.dashpot_last = -e.dashpot_last;  // the force on the first disc
            }
        }
        std::sort(entries.begin(), entries.end(), [](const Entry& a, const Entry& b) {
            return a.bond.k != b.bond.k ? a.bond.k < b.bond.k : a.bond.l < b.bond.l;
        });
        for (size_t b = 0; b < bonds_.size(); ++b) bonds_[b] = entries[b].bond;
        index_bonds();
        if (def_.bond.predict)
            for (size_t b = 0; b < bonds_.size(); ++b) bond_dashpot_last_[b] = entries[b].dashpot_last;
    }
    // the last step's wall records (wall_loads)
    for (size_t t = 0; t < wall_sums_.size() && t < range_clock_.size(); ++t)
        for (size_t e = 0, m = range_clock_[t].wall_sums; e < m; ++e) {
            WallSum& o = wall_sums_[t][e];
            if (o.disc >= 0) o.disc = to[size_t(o.disc)];
        }
}

}  // namespace demlab
