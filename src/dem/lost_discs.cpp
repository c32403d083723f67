// Discs that leave the domain (WorldDef::lost_discs = Remove): a disc thrown over a barrier's
// free end, or off the end of a terrain profile, flies on with nothing to meet; it is taken out
// at the end of the step in which its centre left the domain, so that one stray disc does not
// end a run of thousands.
//
// Taking a disc out squeezes it out of every per-disc array, renumbers the contacts and bonds
// of the others (the order of the discs is kept, so every list stays sorted and every sum
// keeps its order) and rebuilds the candidate lists as a restored checkpoint does
// (world_state.cpp says why that changes no bit). What the disc had (its kinetic and
// potential energy, its contacts' and intact bonds' elastic energy) leaves the ledger as
// EnergyReport::lost_with_discs: the difference of the balance before and after, so the
// balance stays where it was. Its record keeps the index it was added with (disc_ids()).
// The renumbering in space order (space_order.cpp) goes through the same remap_discs, with a
// new order instead of a squeeze.
#include <algorithm>

#include "dem/world.h"

namespace demlab {

long World::disc_index(long id) const {
    if (!ids_in_order_) return id >= 0 && size_t(id) < index_of_id_.size() ? index_of_id_[size_t(id)] : -1;
    const auto it = std::lower_bound(id_.begin(), id_.end(), int32_t(id));
    return it != id_.end() && *it == id ? long(it - id_.begin()) : -1;
}

void World::take_out_lost_discs() {
    std::vector<size_t> gone;
    gone.swap(lost_pending_);  // ascending: the scan's order (integrate_finish)
    r_min_stale_ = true;
    const EnergyReport before = energy();
    for (size_t i : gone) {
        const double kinetic = 0.5 * mass_[i] * vel_[i].squaredNorm() + 0.5 * inertia_[i] * omega_[i] * omega_[i];
        lost_.push_back({time_, id_[i], pos_[i], vel_[i], omega_[i], mass_[i], kinetic});
    }
    compact_discs(gone);
    const EnergyReport after = energy();
    // (both balances hold the same lost_with_discs so far: the difference is these discs')
    lost_energy_ += before.balance() - after.balance();
    lost_potential_ += before.potential - after.potential;
    // the rest watch's kinetic energy without them (the next step sums it afresh)
    kinetic_ = after.kinetic_translation + after.kinetic_rotation;
}

void World::compact_discs(const std::vector<size_t>& gone) {
    const size_t n = pos_.size();
    std::vector<uint8_t> lost(n, 0);
    for (size_t i : gone) lost[i] = 1;
    std::vector<int32_t> from;
    from.reserve(n - gone.size());
    for (size_t i = 0; i < n; ++i)
        if (!lost[i]) from.push_back(int32_t(i));
    remap_discs(from);
}

void World::remap_discs(const std::vector<int32_t>& from) {
    const size_t n = pos_.size();
    std::vector<int32_t> to(n, -1);
    for (size_t k = 0; k < from.size(); ++k) to[size_t(from[k])] = int32_t(k);
    // each array rewritten in its own buffer (a copy read, the array written): Python's views of
    // the arrays (python/demlab_module.cpp) keep pointing at live memory, its first rows the
    // new ones, where a moved-from array freed it under them
    auto remap = [&](auto& v) {
        const auto old = v;
        v.resize(from.size());
        for (size_t k = 0; k < from.size(); ++k) v[k] = old[size_t(from[k])];
    };
    remap(pos_);
    remap(vel_);
    remap(radius_);
    remap(mass_);
    remap(inv_mass_);
    remap(inertia_);
    remap(inv_inertia_);
    remap(angle_);
    remap(omega_);
    remap(material_);
    remap(id_);
    remap(rr_factor_);
    remap(load_);
    remap(external_force_);
    remap(wall_reaction_);
    any_external_force_ = std::any_of(external_force_.begin(), external_force_.end(),
                                      [](const Vec2& f) { return f.squaredNorm() > 0.0; });
    ids_in_order_ = std::is_sorted(id_.begin(), id_.end());
    if (!ids_in_order_) {
        index_of_id_.assign(id_.empty() ? 0 : size_t(*std::max_element(id_.begin(), id_.end())) + 1, -1);
        for (size_t k = 0; k < id_.size(); ++k) index_of_id_[size_t(id_[k])] = int32_t(k);
    } else {
        index_of_id_.clear();
    }

    // The others' contacts, renumbered. A pair whose numbers change places keeps its history as it is: the law sees the pair
    // from the other disc with n, t and the relative velocity all reversed, so the shear
    // spring force along t, the dashpot forces and coefficients are the same numbers
    // (pair_kernel.h). Taking discs out keeps the order and the lists stay sorted; a new order
    // sorts them again by key, as the rebuilt candidate lists are.
    std::vector<DiscContact> dd;
    dd.reserve(dd_.size());
    for (DiscContact c : dd_) {
        if (to[size_t(c.i)] < 0 || to[size_t(c.j)] < 0) continue;
        c.i = to[size_t(c.i)];
        c.j = to[size_t(c.j)];
        if (c.i > c.j) std::swap(c.i, c.j);
        dd.push_back(c);
    }
    auto dd_key = [](const DiscContact& a, const DiscContact& b) { return pair_key(a.i, a.j) < pair_key(b.i, b.j); };
    if (!std::is_sorted(dd.begin(), dd.end(), dd_key)) std::sort(dd.begin(), dd.end(), dd_key);
    std::vector<WallContact> dw;
    dw.reserve(dw_.size());
    for (WallContact c : dw_) {
        if (to[size_t(c.disc)] < 0) continue;
        c.disc = to[size_t(c.disc)];
        dw.push_back(c);
    }
    auto dw_key = [](const WallContact& a, const WallContact& b) { return pair_key(a.disc, a.wall) < pair_key(b.disc, b.wall); };
    if (!std::is_sorted(dw.begin(), dw.end(), dw_key)) std::sort(dw.begin(), dw.end(), dw_key);

    // the others' bonds; an intact bond of a lost disc goes with it (counted, its energy in the
    // difference the caller books). Only discs taken out change a bonded world's numbers
    // (finalize refuses world.space_order = on with bonds), so every bond keeps k < l.
    if (!bonds_.empty()) {
        std::vector<Bond> bonds;
        std::vector<Vec2> dashpot_last;
        for (size_t b = 0; b < bonds_.size(); ++b) {
            Bond bond = bonds_[b];
            if (to[size_t(bond.k)] < 0 || to[size_t(bond.l)] < 0) {
                if (!bond.broken) ++bonds_lost_;
                continue;
            }
            bond.k = to[size_t(bond.k)];
            bond.l = to[size_t(bond.l)];
            bonds.push_back(bond);
            if (def_.bond.predict) dashpot_last.push_back(bond_dashpot_last_[b]);
        }
        bonds_.swap(bonds);
        index_bonds();
        if (def_.bond.predict) bond_dashpot_last_.swap(dashpot_last);
    }
    // the last step's wall records (wall_loads), renumbered; a lost disc's own are dropped
    for (size_t t = 0; t < wall_sums_.size() && t < range_clock_.size(); ++t)
        for (size_t e = 0, m = range_clock_[t].wall_sums; e < m; ++e) {
            WallSum& o = wall_sums_[t][e];
            if (o.disc >= 0) o.disc = to[size_t(o.disc)];
        }
    rebuild_lists(dd, dw);
}

}  // namespace demlab
