// The energy ledger's state terms (World::energy): kinetic, potential and elastic energy now,
// beside the dissipation and the walls' work that the steps add up as they go.
#include <algorithm>

#include "core/thread_pool.h"
#include "dem/world.h"

namespace demlab {

// The sums run over fixed blocks (kEnergyBlock discs or contacts), each added up in order,
// then the blocks in order, with the blocks shared out among the pool's threads: the same
// bits for any thread count. The run's blow-up watch calls this every 100 steps, and on the
// calling thread alone it was 1.4 % of a 2-thread flume run with the other thread waiting.
EnergyReport World::energy() const {
    return with_contact_law(def_.law, [&](auto law) { return energy_with<decltype(law)>(); });
}

template <typename Law>
EnergyReport World::energy_with() const {
    const size_t nd = pos_.size(), nc = dd_.size();
    const size_t disc_blocks = (nd + kEnergyBlock - 1) / kEnergyBlock;
    const size_t blocks = disc_blocks + (nc + kEnergyBlock - 1) / kEnergyBlock;
    energy_blocks_.assign(blocks, EnergyBlock{});
    const Vec2 g = def_.gravity;
    const size_t nm = disc_materials_, nw = walls_.size();
    // Where the contacts' elastic energy is taken. The kinetic energy is that of v(t - dt/2);
    // U at x(t) differs from U at t - dt/2 by (dt/2) dU/dt, first order in the step: the
    // undamped DEBRIS box of Debris.ConservesEnergy with fixed steps of 2e-4 and 1e-4 s drifted
    // 0.50 % and 0.30 % measured at x(t), 0.23 % and 0.032 % at t - dt/2. A wall that moved
    // in the last step is taken back with it: the disc is shifted by the relative velocity.
    // The linear law keeps x(t), where its dashpots' and sliding's work is booked, and its
    // regression figures with it.
    auto at_kinetic_time = [&](size_t i, Vec2 frame_velocity = Vec2::Zero()) -> Vec2 {
        if constexpr (Law::kElasticAtHalfStep) return pos_[i] - 0.5 * last_dt_ * (vel_[i] - frame_velocity);
        else return pos_[i];
    };
    auto block = [&](size_t b) {
        EnergyBlock& s = energy_blocks_[b];
        if (b < disc_blocks) {
            for (size_t i = b * kEnergyBlock, end = std::min(nd, (b + 1) * kEnergyBlock); i < end; ++i) {
                s.kinetic_translation += 0.5 * mass_[i] * vel_[i].squaredNorm();
                s.kinetic_rotation += 0.5 * inertia_[i] * omega_[i] * omega_[i];
                // at t - dt/2: the mean of x(t) and x(t - dt) = x(t) - v(t - dt/2) dt
                s.potential -= mass_[i] * g.dot(pos_[i] - 0.5 * last_dt_ * vel_[i]);
                // a constant force's potential, -F . x, at the same time level
                if (any_external_force_) s.potential -= external_force_[i].dot(pos_[i] - 0.5 * last_dt_ * vel_[i]);
            }
            return;
        }
        const size_t c0 = (b - disc_blocks) * kEnergyBlock;
        for (size_t k = c0, end = std::min(nc, c0 + kEnergyBlock); k < end; ++k) {
            const DiscContact& c = dd_[k];
            const size_t i = size_t(c.i), j = size_t(c.j);
            const double overlap = radius_[i] + radius_[j] - (at_kinetic_time(j) - at_kinetic_time(i)).norm();
            if (overlap <= 0.0) continue;
            const typename Law::Params& pm = tables<Law>().disc_disc[size_t(material_[i]) * nm + size_t(material_[j])];
            s.elastic += Law::elastic_energy(pm, overlap, c, radius_[i], radius_[j]);
        }
    };
    const int threads = pool_->size();
    if (pool_->shares(nd + nc))
        pool_->for_each_thread([&](int t) {
            for (size_t b = blocks * size_t(t) / size_t(threads); b < blocks * size_t(t + 1) / size_t(threads); ++b) block(b);
        });
    else
        for (size_t b = 0; b < blocks; ++b) block(b);
    EnergyReport e;
    for (const EnergyBlock& s : energy_blocks_) {
        e.kinetic_translation += s.kinetic_translation;
        e.kinetic_rotation += s.kinetic_rotation;
        e.potential += s.potential;
        e.elastic += s.elastic;
    }
    for (const WallContact& c : dw_) {
        const size_t i = size_t(c.disc), w = size_t(c.wall);
        if (!wall_active_[w]) continue;
        const Vec2 wall_velocity = wall_moving_[w] ? walls_[w].velocity : Vec2::Zero();
        e.elastic += wall_contact_elastic_energy<Law>(geom_[w], at_kinetic_time(i, wall_velocity), radius_[i], tables<Law>().disc_wall[size_t(material_[i]) * nw + w], c);
    }
    e.dissipated_contacts = diss_contacts_;
    e.dissipated_local = diss_local_;
    e.dissipated_rotation = diss_rotation_;
    e.work_by_walls = work_walls_;
    e.removed_with_walls = removed_walls_;
    e.lost_with_discs = lost_energy_;
    e.lost_potential = lost_potential_;
    if (bonds_at_start_ > 0) {
        e.bond_elastic = bond_elastic_energy();
        e.bond_break_loss = bond_break_loss_;
    }
    return e;
}

}  // namespace demlab
