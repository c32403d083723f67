// The world's bonds (elastic_bond.h): a persistent list beside the contact lists. Each step,
// before the force pass' ranges start, every intact bond's force goes into its own slot (the
// positions are read before any range integrates); each range then adds its discs' bond terms
// after their contact terms, in bond-list order, so the sums are the same bits for any thread
// count; after the pass the bonds that broke are marked in list order and their energy is
// booked (C12).
#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "core/thread_pool.h"
#include "core/validate.h"
#include "dem/world.h"

namespace demlab {

int World::add_bond(int k, int l) {
    const std::string where = "bond[" + std::to_string(bonds_.size()) + "]";
    if (finalized_) throw InputError(where + ": bonds must be added before finalize()");
    const long n = long(pos_.size());
    if (k < 0 || l < 0 || k >= n || l >= n)
        throw InputError(where + " = [" + std::to_string(k) + ", " + std::to_string(l) + "]: no such disc (" +
                         std::to_string(n) + " discs)");
    if (k == l) throw InputError(where + " = [" + std::to_string(k) + ", " + std::to_string(l) + "]: a bond joins two discs");
    bonds_.push_back({std::min(k, l), std::max(k, l), 0.0, 0});
    return int(bonds_.size()) - 1;
}

void World::prepare_bonds() {
    if (bonds_.empty()) return;
    const BondDef& d = def_.bond;
    require_range("world.bond.modulus", d.modulus, 0.0, 1e12, false, "Pa");
    if (!(d.modulus > 0.0)) throw InputError("world.bond.modulus = " + format_number(d.modulus) + " Pa: must be > 0");
    if (!(d.max_strain > 0.0 && d.max_strain <= 0.5))
        throw InputError("world.bond.max_strain = " + format_number(d.max_strain) + ": must be in (0, 0.5]");
    require_range("world.bond.min_distance", d.min_distance, 0.0, 1.0, false, "m");
    std::sort(bonds_.begin(), bonds_.end(), [](const Bond& a, const Bond& b) { return a.k != b.k ? a.k < b.k : a.l < b.l; });
    for (size_t b = 1; b < bonds_.size(); ++b)
        if (bonds_[b].k == bonds_[b - 1].k && bonds_[b].l == bonds_[b - 1].l)
            throw InputError("bond [" + std::to_string(bonds_[b].k) + ", " + std::to_string(bonds_[b].l) + "] is given twice");
    for (Bond& b : bonds_) {
        b.rest_length = (pos_[size_t(b.l)] - pos_[size_t(b.k)]).norm();
        if (!(b.rest_length > d.min_distance))
            throw InputError("bond [" + std::to_string(b.k) + ", " + std::to_string(b.l) + "]: its discs are " +
                             format_number(b.rest_length) + " m apart, not more than world.bond.min_distance = " +
                             format_number(d.min_distance) + " m");
    }
    bond_k0_ = ElasticBond::k0(d);
    bond_k_max_ = ElasticBond::max_stiffness(d, bond_k0_);
    bonds_at_start_ = bonds_.size();
    index_bonds();
}

// Each disc's bonds and the bonds' buffers, for the present discs and bonds (again after a
// disc was lost).
void World::index_bonds() {
    const BondDef& d = def_.bond;
    // each disc's bonds in list order (CSR)
    const size_t n = pos_.size();
    bond_disc_start_.assign(n + 1, 0);
    for (const Bond& b : bonds_) {
        ++bond_disc_start_[size_t(b.k) + 1];
        ++bond_disc_start_[size_t(b.l) + 1];
    }
    for (size_t i = 0; i < n; ++i) bond_disc_start_[i + 1] += bond_disc_start_[i];
    bond_disc_.resize(2 * bonds_.size());
    std::vector<uint32_t> fill(bond_disc_start_.begin(), bond_disc_start_.end() - 1);
    for (size_t b = 0; b < bonds_.size(); ++b) {
        bond_disc_[fill[size_t(bonds_[b].k)]++] = uint32_t(2 * b);
        bond_disc_[fill[size_t(bonds_[b].l)]++] = uint32_t(2 * b + 1);
    }
    bond_out_.assign(bonds_.size(), BondOut{0.0, 0.0, 0.0, 0.0, 0});
    if (d.predict) {
        bond_dashpot_.assign(bonds_.size(), Vec2::Zero());
        bond_dashpot_last_.assign(bonds_.size(), Vec2::Zero());
        bond_dissipated_.assign(bonds_.size(), 0.0);
    }
    bond_inv_rest_.resize(bonds_.size());
    for (size_t b = 0; b < bonds_.size(); ++b) bond_inv_rest_[b] = 1.0 / bonds_[b].rest_length;
}

void World::compute_bond_forces() {
    if (def_.bond.predict) bond_pass<true>();
    else bond_pass<false>();
}

// Every intact bond's force into its slot, and whether it breaks; with Predict (C5) the
// bond's length, strain, force and break come from the positions predicted one step, x + dt v
// with v = v(t - dt/2), as AvaFrame's code does. The force is then the spring's at the
// current length plus a dashpot's, F(d + dt v_kl) - F(d) ~ k_b dt v_kl (C11), whose work is
// booked as the contacts' dashpots' is, centred on v(t - dt/2): this step's force over the
// first half of the velocity interval, the last step's over the second half.
template <bool Predict>
void World::bond_pass() {
    const BondDef& def = def_.bond;
    const double k0 = bond_k0_, k_max = bond_k_max_, dt = dt_, last_dt = last_dt_;
    bond_chunk_broke_.assign(size_t(pool_->size()), 0);
    pool_->parallel_for(bonds_.size(), [&](size_t begin, size_t end, int chunk) {
        uint8_t broke = 0;
        for (size_t b = begin; b < end; ++b) {
            const Bond& bond = bonds_[b];
            BondOut& o = bond_out_[b];
            o.fx = o.fy = 0.0;
            o.breaks = 0;
            o.k_tran = bond.broken ? 0.0 : k_max;
            [[maybe_unused]] const Vec2 v_kl = Predict ? Vec2(vel_[size_t(bond.l)] - vel_[size_t(bond.k)]) : Vec2::Zero();
            [[maybe_unused]] Vec2 dashpot = Vec2::Zero();
            if (!bond.broken) {
                const Vec2 d = pos_[size_t(bond.l)] - pos_[size_t(bond.k)];
                const Vec2 at = Predict ? Vec2(d + dt * v_kl) : d;
                const ElasticBond::Eval e = ElasticBond::evaluate(def, k0, bond.rest_length, bond_inv_rest_[b], at);
                o.strain = e.strain;
                if (e.breaks) {
                    o.breaks = 1;
                    broke = 1;
                }
                if (!e.skipped && !e.breaks) {
                    o.fx = e.f * at.x();
                    o.fy = e.f * at.y();
                    if constexpr (Predict) {
                        const ElasticBond::Eval now = ElasticBond::evaluate(def, k0, bond.rest_length, bond_inv_rest_[b], d);
                        const Vec2 spring = now.skipped || now.breaks ? Vec2::Zero() : Vec2(now.f * d.x(), now.f * d.y());
                        dashpot = Vec2(o.fx, o.fy) - spring;
                    }
                }
            }
            if constexpr (Predict) {
                // the energy the dashpot took (on k: +dashpot, on l: -dashpot; power -dashpot . v_kl)
                bond_dissipated_[b] = 0.5 * (dt * dashpot + last_dt * bond_dashpot_last_[b]).dot(v_kl);
                bond_dashpot_[b] = dashpot;
            }
        }
        if (broke) bond_chunk_broke_[size_t(chunk)] = 1;
    });
}

// After the pass: the predicted bonds' dashpot work into the ledger, in list order, and this
// step's dashpot forces become the last ones.
void World::book_bond_dashpots() {
    if (!def_.bond.predict) return;
    double sum = 0.0;
    for (const double d : bond_dissipated_) sum += d;
    diss_contacts_ += sum;
    bond_dashpot_last_.swap(bond_dashpot_);
}

// The bond terms of discs [d0, d1), after their contact terms: the force, and the bond's
// largest stiffness for the automatic step (C10; bonds carry no shear, so no k_rot).
void World::add_bond_terms(size_t d0, size_t d1) {
    DiscLoad* const load = load_.data();
    const BondOut* const out = bond_out_.data();
    const uint32_t* const start = bond_disc_start_.data();
    const uint32_t* const entries = bond_disc_.data();
    for (size_t i = d0; i < d1; ++i) {
        const uint32_t e0 = start[i], e1 = start[i + 1];
        if (e0 == e1) continue;
        // the disc's bond terms summed in list order, then added to its contact sums once (in
        // registers: the sums' record may alias the slots, so adding term by term went through
        // memory each time)
        double fx = 0.0, fy = 0.0, k = 0.0;
        for (uint32_t e = e0; e < e1; ++e) {
            const uint32_t entry = entries[e];
            const BondOut& o = out[entry >> 1];
            // k gets +f, l gets -f: the sign from the entry's low bit, without a branch
            const double sign = 1.0 - 2.0 * double(entry & 1u);
            fx += sign * o.fx;
            fy += sign * o.fy;
            k += o.k_tran;
        }
        DiscLoad& l = load[i];
        l.force.x() += fx;
        l.force.y() += fy;
        l.k_tran += k;
    }
}

// Constant forces on discs (DiscDef::force), after the contact and bond terms.
void World::add_external_forces(size_t d0, size_t d1) {
    DiscLoad* const load = load_.data();
    for (size_t i = d0; i < d1; ++i) load[i].force += external_force_[i];
}

void World::settle_bond_breaks() {
    // (a scan of every bond only in a step where one broke)
    if (std::find(bond_chunk_broke_.begin(), bond_chunk_broke_.end(), uint8_t(1)) == bond_chunk_broke_.end()) return;
    for (size_t b = 0; b < bonds_.size(); ++b) {
        if (!bond_out_[b].breaks || bonds_[b].broken) continue;
        Bond& bond = bonds_[b];
        bond.broken = 1;
        const double u = ElasticBond::energy(def_.bond, bond_k0_, bond.rest_length, bond_out_[b].strain);
        bond_break_loss_ += u;
        bond_breaks_.push_back({time_, id_[size_t(bond.k)], id_[size_t(bond.l)], bond_out_[b].strain, u});
    }
}

// The intact bonds' energy at the current positions, in list order (C7).
double World::bond_elastic_energy() const {
    double u = 0.0;
    for (size_t k = 0; k < bonds_.size(); ++k) {
        const Bond& b = bonds_[k];
        if (b.broken) continue;
        const double length_sq = (pos_[size_t(b.l)] - pos_[size_t(b.k)]).squaredNorm();
        if (length_sq <= def_.bond.min_distance * def_.bond.min_distance) continue;
        u += ElasticBond::energy(def_.bond, bond_k0_, b.rest_length, ElasticBond::strain(std::sqrt(length_sq), bond_inv_rest_[k]));
    }
    return u;
}

}  // namespace demlab
