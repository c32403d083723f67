// Checkpoints of the world: what a step needs from the previous one.
//
// Saved: disc positions, velocities, angles and spins; the contact forces and stiffness sums
// of the last step (read by outputs between steps); time, step count, this and the last time
// step; each wall's geometry (moving walls have moved), activity, force, moment and impulse;
// every candidate contact with its history (shear spring force, dashpot coefficients, last
// dashpot forces); the energy ledger's sums; the discs' order, once they were renumbered in
// space order (space_order.cpp).
//
// Not saved: the broad phase. Restoring rebuilds the b2DynamicTree from the current positions,
// so its fat boxes, and so its candidate lists, differ from the uninterrupted run's. That
// changes no bit of the physics, because
//  - every fat box contains its disc's tight box in both runs, so every touching pair is a
//    candidate in both, and pairs that do not touch carry no history (the force pass zeroes
//    it) and add nothing: the force pass and the ledger skip them or add an exact 0.0;
//  - the lists are sorted by key, so the touching contacts are visited in the same relative
//    order, and every per-disc sum adds the same terms in the same order;
//  - the time step depends only on touching contacts.
// The one history a non-touching contact carries is the last dashpot force of a contact that
// opened in the last step (its second half-step of work, see compute_forces). Such a pair was
// touching one step ago, far inside any margin: load_state checks that the rebuilt lists hold
// every contact with a history and refuses the checkpoint otherwise.
#include <algorithm>

#include "core/binary_io.h"
#include "dem/world.h"

namespace demlab {

namespace {
constexpr uint32_t kWorldStateVersion = 2;  // 2: the lost discs
// A world whose discs were renumbered in space order writes 3: the discs' ids in their present
// order follow the lost discs (ORDR). One never renumbered writes 2, the layout before.
constexpr uint32_t kWorldStateVersionOrdered = 3;

// A contact's history: the law's fields (LinearLaw::for_each_history_field).
template <typename Fn, typename... Contact>
void for_each_history_field(Fn fn, Contact&... c) {
    LinearLaw::for_each_history_field(fn, c...);
}

template <typename Contact>
void put_history(BinaryWriter& out, const Contact& c) {
    for_each_history_field([&](const auto& v) { out.put(v); }, c);
}

template <typename Contact>
void get_history(BinaryReader& in, Contact& c) {
    for_each_history_field([&](auto& v) { in.get(v); }, c);
}

template <typename Contact>
void copy_history(const Contact& from, Contact& to) {
    for_each_history_field([](const auto& f, auto& t) { t = f; }, from, to);
}
}  // namespace

void World::save_state(BinaryWriter& out) const {
    out.tag("WRLD");
    out.put(ids_in_order_ ? kWorldStateVersion : kWorldStateVersionOrdered);
    // the discs taken out so far first: a world built from the set-up takes them out before
    // the rest is read (load_state)
    out.tag("LOST");
    out.put(uint64_t(lost_.size()));
    for (const LostDiscEvent& e : lost_) {
        out.put(e.t);
        out.put(e.id);
        out.put(e.pos);
        out.put(e.vel);
        out.put(e.omega);
        out.put(e.mass);
        out.put(e.energy);
    }
    out.put(uint64_t(bonds_lost_));
    out.put(lost_energy_);
    out.put(lost_potential_);
    if (!ids_in_order_) {
        out.tag("ORDR");
        out.put(int64_t(space_orderings_));
        out.put(id_);
    }
    out.put(uint64_t(pos_.size()));
    out.put(uint64_t(walls_.size()));
    out.put(time_);
    out.put(dt_);
    out.put(last_dt_);
    out.put(int64_t(steps_));
    out.tag("DISC");
    out.put(pos_);
    out.put(vel_);
    out.put(angle_);
    out.put(omega_);
    out.put(radius_);
    // the last step's loads, field by field (the file's layout predates DiscLoad)
    auto put_field = [&](auto member) {
        std::vector<std::remove_cv_t<std::remove_reference_t<decltype(load_[0].*member)>>> v;
        v.reserve(load_.size());
        for (const DiscLoad& l : load_) v.push_back(l.*member);
        out.put(v);
    };
    put_field(&DiscLoad::force);
    put_field(&DiscLoad::torque);
    put_field(&DiscLoad::k_tran);
    put_field(&DiscLoad::k_rot);
    put_field(&DiscLoad::wall_normal);
    put_field(&DiscLoad::n_wall);
    put_field(&DiscLoad::n_disc);
    out.tag("WALL");
    for (size_t w = 0; w < walls_.size(); ++w) {
        const WallGeom& g = geom_[w];
        out.put(g.p0);
        out.put(g.p1);
        out.put(g.centre);
        out.put(wall_active_[w]);
        out.put(wall_moving_[w]);
        out.put(wall_force_[w]);
        out.put(wall_moment_[w]);
        out.put(wall_impulse_[w]);
    }
    out.tag("CONT");
    out.put(uint64_t(dd_.size()));
    for (const DiscContact& c : dd_) {
        out.put(c.i);
        out.put(c.j);
        put_history(out, c);
    }
    out.put(uint64_t(dw_.size()));
    for (const WallContact& c : dw_) {
        out.put(c.disc);
        out.put(c.wall);
        put_history(out, c);
    }
    out.put(int64_t(touching_dd_));
    out.put(int64_t(touching_dw_));
    out.tag("LEDG");
    out.put(diss_contacts_);
    out.put(diss_local_);
    out.put(diss_rotation_);
    out.put(work_walls_);
    out.put(removed_walls_);
    // the bonds (a world without them writes nothing more: its checkpoints keep their layout)
    if (bonds_at_start_ > 0) {
        out.tag("BOND");
        out.put(uint64_t(bonds_.size()));
        for (const Bond& b : bonds_) {
            out.put(b.k);
            out.put(b.l);
            out.put(b.rest_length);
            out.put(b.broken);
        }
        // the predicted bonds' last dashpot forces (their history)
        if (def_.bond.predict)
            for (const Vec2& f : bond_dashpot_last_) {
                out.put(f.x());
                out.put(f.y());
            }
        out.put(bond_break_loss_);
        out.put(uint64_t(bond_breaks_.size()));
        for (const BondBreakEvent& e : bond_breaks_) {
            out.put(e.t);
            out.put(e.k);
            out.put(e.l);
            out.put(e.strain);
            out.put(e.energy);
        }
    }
}

namespace {
// Copies the histories of `saved` into `fresh` (both sorted by key); a saved contact with a
// history that the rebuilt list lacks makes the checkpoint unusable.
template <typename Contact, typename Key>
void merge_histories(const std::vector<Contact>& saved, std::vector<Contact>& fresh, Key key, const char* what) {
    size_t o = 0;
    for (const Contact& s : saved) {
        const uint64_t k = key(s);
        while (o < fresh.size() && key(fresh[o]) < k) ++o;
        if (o < fresh.size() && key(fresh[o]) == k) {
            copy_history(s, fresh[o]);
        } else if (s.fs != 0.0 || s.damp_n != 0.0f || s.damp_s != 0.0f) {
            throw RunError(std::string("checkpoint: a ") + what +
                           " contact with a history is not a candidate of the rebuilt broad phase (the checkpoint "
                           "does not belong to this set-up)");
        }
    }
}
}  // namespace

void World::load_state(BinaryReader& in) {
    if (!finalized_) finalize();
    in.expect_tag("WRLD");
    const uint32_t version = in.get<uint32_t>();
    if (version != kWorldStateVersion && version != kWorldStateVersionOrdered)
        throw InputError("checkpoint: written by another version of demlab");
    in.expect_tag("LOST");
    const uint64_t lost = in.get<uint64_t>();
    if (lost > pos_.size()) throw InputError("checkpoint: corrupt list of lost discs");
    std::vector<LostDiscEvent> events(static_cast<size_t>(lost));
    std::vector<size_t> gone;
    for (LostDiscEvent& e : events) {
        in.get(e.t);
        in.get(e.id);
        in.get(e.pos);
        in.get(e.vel);
        in.get(e.omega);
        in.get(e.mass);
        in.get(e.energy);
        const long i = disc_index(e.id);
        if (i < 0) throw InputError("checkpoint: its lost disc " + std::to_string(e.id) + " is not a disc of this set-up");
        gone.push_back(size_t(i));
    }
    std::sort(gone.begin(), gone.end());
    if (std::adjacent_find(gone.begin(), gone.end()) != gone.end()) throw InputError("checkpoint: corrupt list of lost discs");
    if (!gone.empty()) compact_discs(gone);
    lost_ = std::move(events);
    bonds_lost_ = size_t(in.get<uint64_t>());
    in.get(lost_energy_);
    in.get(lost_potential_);
    if (version == kWorldStateVersionOrdered) {
        // the discs in the order they had (World::order_discs_in_space), by id
        in.expect_tag("ORDR");
        space_orderings_ = long(in.get<int64_t>());
        std::vector<int32_t> ids;
        in.get(ids, pos_.size());
        std::vector<int32_t> from(ids.size());
        std::vector<uint8_t> seen(ids.size(), 0);
        for (size_t k = 0; k < ids.size(); ++k) {
            const long i = disc_index(ids[k]);
            if (i < 0 || seen[size_t(i)]) throw InputError("checkpoint: corrupt order of the discs");
            seen[size_t(i)] = 1;
            from[k] = int32_t(i);
        }
        remap_discs(from);
    }
    const size_t n = pos_.size(), nw = walls_.size();
    if (in.get<uint64_t>() != n || in.get<uint64_t>() != nw)
        throw InputError("checkpoint: its disc or wall count differs from the scenario's");
    in.get(time_);
    in.get(dt_);
    in.get(last_dt_);
    steps_ = long(in.get<int64_t>());
    in.expect_tag("DISC");
    in.get(pos_, n);
    in.get(vel_, n);
    in.get(angle_, n);
    in.get(omega_, n);
    std::vector<double> radius;
    in.get(radius, n);
    if (radius != radius_) throw InputError("checkpoint: its disc radii differ from the scenario's");
    load_.assign(n, DiscLoad{});
    auto get_field = [&](auto member) {
        std::vector<std::remove_cv_t<std::remove_reference_t<decltype(load_[0].*member)>>> v;
        in.get(v, n);
        for (size_t i = 0; i < n; ++i) load_[i].*member = v[i];
    };
    get_field(&DiscLoad::force);
    get_field(&DiscLoad::torque);
    get_field(&DiscLoad::k_tran);
    get_field(&DiscLoad::k_rot);
    get_field(&DiscLoad::wall_normal);
    get_field(&DiscLoad::n_wall);
    get_field(&DiscLoad::n_disc);
    in.expect_tag("WALL");
    for (size_t w = 0; w < nw; ++w) {
        WallGeom& g = geom_[w];
        const Vec2 p0 = in.get<Vec2>(), p1 = in.get<Vec2>(), centre = in.get<Vec2>();
        // a moving wall has been translated: apply the same translation to the whole geometry
        translate(g, (g.shape == WallShape::Segment ? p0 - g.p0 : centre - g.centre));
        g.p0 = p0;
        g.p1 = p1;
        g.centre = centre;
        in.get(wall_active_[w]);
        in.get(wall_moving_[w]);
        in.get(wall_force_[w]);
        in.get(wall_moment_[w]);
        in.get(wall_impulse_[w]);
    }
    in.expect_tag("CONT");
    std::vector<DiscContact> dd(in.get<uint64_t>());
    for (DiscContact& c : dd) {
        in.get(c.i);
        in.get(c.j);
        get_history(in, c);
        if (c.i < 0 || c.j <= c.i || size_t(c.j) >= n) throw InputError("checkpoint: corrupt contact list");
    }
    std::vector<WallContact> dw(in.get<uint64_t>());
    for (WallContact& c : dw) {
        in.get(c.disc);
        in.get(c.wall);
        get_history(in, c);
        if (c.disc < 0 || size_t(c.disc) >= n || c.wall < 0 || size_t(c.wall) >= nw)
            throw InputError("checkpoint: corrupt contact list");
    }
    touching_dd_ = long(in.get<int64_t>());
    touching_dw_ = long(in.get<int64_t>());
    in.expect_tag("LEDG");
    in.get(diss_contacts_);
    in.get(diss_local_);
    in.get(diss_rotation_);
    in.get(work_walls_);
    in.get(removed_walls_);
    if (bonds_at_start_ > 0) {
        // the same bonds as this world's (built from the same set-up), with their state
        in.expect_tag("BOND");
        if (in.get<uint64_t>() != bonds_.size()) throw InputError("checkpoint: its bonds are not this set-up's");
        for (Bond& b : bonds_) {
            Bond s{};
            in.get(s.k);
            in.get(s.l);
            in.get(s.rest_length);
            in.get(s.broken);
            if (s.k != b.k || s.l != b.l) throw InputError("checkpoint: its bonds are not this set-up's");
            b.rest_length = s.rest_length;
            b.broken = s.broken;
        }
        if (def_.bond.predict)
            for (Vec2& f : bond_dashpot_last_) {
                in.get(f.x());
                in.get(f.y());
            }
        in.get(bond_break_loss_);
        const uint64_t breaks = in.get<uint64_t>();
        if (breaks > bonds_.size()) throw InputError("checkpoint: corrupt bond list");
        bond_breaks_.resize(size_t(breaks));
        for (BondBreakEvent& e : bond_breaks_) {
            in.get(e.t);
            in.get(e.k);
            in.get(e.l);
            in.get(e.strain);
            in.get(e.energy);
        }
    }

    rebuild_lists(dd, dw);
}

// The broad phase from the present positions, then the histories (a restored checkpoint, or
// the discs left after some were lost).
void World::rebuild_lists(const std::vector<DiscContact>& dd, const std::vector<WallContact>& dw) {
    broad_.init(margin_target(), wall_piece_target(), pos_, radius_, geom_, wall_active_);
    dd_.clear();
    dw_.clear();
    refresh_contacts();
    discs_may_have_escaped_ = true;
    merge_histories(dd, dd_, [](const DiscContact& c) { return pair_key(c.i, c.j); }, "disc-disc");
    merge_histories(dw, dw_, [](const WallContact& c) { return pair_key(c.disc, c.wall); }, "disc-wall");
    forget_clearances();  // the restored histories are not what the clearances were found on
}

}  // namespace demlab
