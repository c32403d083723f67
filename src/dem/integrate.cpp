// The integration of the discs (PFC's central differences, thesis eq. 2.39-2.43) with the
// rotation models, local damping and the automatic time step (timestep.h), called by the
// force pass block by block; the AVX2 and AVX-512 forms are integrate_avx2.cpp and
// integrate_avx512.cpp, the same bits.
#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "core/validate.h"
#include "core/thread_pool.h"
#include "dem/timestep.h"
#include "dem/world.h"
#include "dem/world_messages.h"

namespace demlab {

World::DtFactors World::dt_factors() const {
    const bool corr = def_.timestep.damping_correction;
    // local damping (a force along the spring force, not a dashpot) keeps its factor in
    // either scheme; the dashpots' factors belong to the lagged scheme alone: centred
    // dashpots are stable at PFC's rule as printed (centred_dashpots.cpp)
    const double local = corr ? local_damping_factor(def_.damping.local_alpha) : 1.0;
    const bool lagged = corr && !centred_dashpots();
    const double phi = local * (lagged ? rotational_damping_factor(def_.damping.beta_s) : 1.0);
    const double phi_t = local * (lagged ? translational_damping_factor(def_.damping.beta_n) : 1.0);
    // a law without dashpots or rotation (DEBRIS): translation only, no factors
    if (with_contact_law(def_.law, [](auto law) { return decltype(law)::kTranslationOnly; })) return {false, 1.0, 1.0};
    return {def_.rotation.model != 1, phi * phi, phi_t * phi_t};
}

// One disc's squared critical step from its loads (the PFC rule, timestep.h): a disc
// without contacts uses its own stiffnesses. Inlined by force: out of line it was a call per
// disc and step, 7 % of geometry A's time (perf); inlined, its two divisions overlap the
// integration's other work.
[[gnu::always_inline]] inline double World::critical_step_squared_at(const DiscLoad& l, double own_k_tran,
                                                                     double own_k_rot, double mass, double inertia,
                                                                     double radius, const DtFactors& f) {
    const double kt = l.k_tran > 0.0 ? l.k_tran : own_k_tran;
    const double kr = l.k_rot > 0.0 ? l.k_rot : own_k_rot;
    return critical_step_squared(mass, inertia, radius, kt, kr, f.rotation_free, f.phi_sq, f.phi_t_sq);
}

double World::critical_step_squared_of(size_t i, const DtFactors& f) const {
    const size_t m = size_t(material_[i]);
    return critical_step_squared_at(load_[i], default_k_tran_[m], default_k_rot_[m], mass_[i], inertia_[i], radius_[i], f);
}

double World::step_from_critical_squared(double best_sq) const {
    // the law's: PFC's rule, or (DEBRIS) capped by a ceiling and growing slowly (law_part.h)
    return with_contact_law(def_.law, [&](auto law) {
        using Law = decltype(law);
        return Law::step_from_rule(def_.law_def<Law>(), def_.timestep.safety, def_.timestep.fixed, best_sq, dt_);
    });
}

double World::automatic_dt() const {
    const DtFactors f = dt_factors();
    double best = INFINITY;
    for (size_t i = 0; i < pos_.size(); ++i) best = std::min(best, critical_step_squared_of(i, f));
    return step_from_critical_squared(best);
}

// PFC's central differences: v(t + dt/2) = v(t - dt/2) + (F(t)/m + g) dt, x(t + dt) = x(t) + v(t + dt/2) dt.
// The force pass calls integrate_discs for each range as soon as the range's sums are
// complete (compute_forces): integrate_prepare before, integrate_finish after.
World::IntegrateConsts World::integrate_prepare() {
    const size_t chunks = size_t(pool_->size());
    chunk_note_.assign(chunks, ChunkNote{});  // no allocation after the first step
    // the AVX2 loop's inputs: a disc without contacts uses its material's stiffnesses for its
    // step bound; each range's ledger terms, per disc
    return {dt_, def_.gravity, def_.damping.local_alpha, def_.gravity.norm(), def_.timestep.automatic, dt_factors()};
}

bool World::avx2_integration() const {
    return avx2_ && !disc_friction() &&
           !(def_.rotation.model == 3 && def_.rotation.damping_per != RotDampingPer::Disc);
}

void World::integrate_discs(size_t begin, size_t end, int chunk, const IntegrateConsts& k) {
    if (disc_friction()) return integrate_discs_debris(begin, end, chunk, k);
    // four (AVX2) or eight (AVX-512) discs at a time where those loops have every rule the run
    // uses (per-disc rotational damping; local damping or none), the same bits
    if (avx2_integration()) {
        const IntegrateArrays arrays{pos_.data(),      vel_.data(),          omega_.data(),       angle_.data(),
                                     mass_.data(),     inv_mass_.data(),     inertia_.data(),     inv_inertia_.data(),
                                     radius_.data(),   rr_factor_.data(),    material_.data(),    load_.data(),
                                     broad_.fat_lo_data(), broad_.fat_hi_data(), default_k_tran_.data(),
                                     default_k_rot_.data(), disc_materials_};
        const RotationDef& rot = def_.rotation;
        const IntegrateParams params{k.dt,          k.g,          k.alpha,      k.g_abs,         rot.model, rot.rolling_form == RollingForm::Literal,
                                     rot.mu_br,     k.auto_dt,    k.dtf.rotation_free, k.dtf.phi_sq, k.dtf.phi_t_sq,
                                     def_.domain_lo, def_.domain_hi, chunk_note_[size_t(chunk)].dt_sq};
        const IntegrateOut out = avx512_ ? integrate_avx512(arrays, params, begin, end, ledger_blocks_.data(), kLedgerBlock)
                                         : integrate_avx2(arrays, params, begin, end, ledger_blocks_.data(), kLedgerBlock);
        range_clock_[size_t(chunk)].touching_dd += out.touching_dd;
        integrate_note(chunk, out.fault, k.auto_dt ? out.best_sq : INFINITY, out.any_escaped, out.speed_l1, out.extent_l1);
        return;
    }
    const double dt = k.dt;
    const Vec2 g = k.g;
    const double alpha = k.alpha;
    // copies, like the arrays below: the stores into the discs' arrays may alias anything
    // reached through `this`, and GCC reloaded these every disc
    const RotationDef rot = def_.rotation;
    const DtFactors dtf = k.dtf;
    const bool auto_dt = k.auto_dt;
    const double* const own_k_tran = default_k_tran_.data();
    const double* const own_k_rot = default_k_rot_.data();
    const int32_t* const material = material_.data();
    LedgerBlock* const ledger_blocks = ledger_blocks_.data();
    const Vec2* const fat_lo = broad_.fat_lo_data();
    const Vec2* const fat_hi = broad_.fat_hi_data();
    // The arrays through local pointers, and each new value kept in a register: Eigen stores
    // a Vec2 as an SSE packet, whose type may alias anything, so after `vel_[i] += ...` GCC
    // reloaded the vectors' data pointers and vel_[i] itself before the position update;
    // perf put 40 % of this loop's samples on that reload.
    Vec2* const pos = pos_.data();
    Vec2* const vel = vel_.data();
    double* const omega = omega_.data();
    double* const angle = angle_.data();
    const double* const mass = mass_.data();
    const double* const inv_mass = inv_mass_.data();
    const double* const inertia = inertia_.data();
    const double* const inv_inertia = inv_inertia_.data();
    const double* const radius = radius_.data();
    const double* const rr_factor = rr_factor_.data();
    const DiscLoad* const load = load_.data();
    // the next automatic step from this step's contacts (as automatic_dt(), but in the
    // parallel loop: a minimum does not depend on the order it is taken in)
    double best_sq = INFINITY;
    // whether a disc left its fat box: the broad phase then need not scan them all
    bool any_escaped = false;
    size_t fault = SIZE_MAX;
    double speed_l1 = 0.0, extent_l1 = 0.0;  // the clearance test's bound (integrate_finish)
    const Vec2 lo = def_.domain_lo, hi = def_.domain_hi;
    // the ledger's shares per block of discs (see compute_forces' ledger)
    double block_local = 0.0, block_rot = 0.0;
    double kinetic_lanes[4] = {0.0, 0.0, 0.0, 0.0};  // disc i in lane i % 4, as the AVX2 loop sums it
    for (size_t i = begin; i < end; ++i) {
        if (auto_dt)
            best_sq = std::min(best_sq, critical_step_squared_at(load[i], own_k_tran[size_t(material[i])],
                                                                 own_k_rot[size_t(material[i])], mass[i], inertia[i],
                                                                 radius[i], dtf));
        double diss_local = 0.0, diss_rot = 0.0;
        const DiscLoad& l = load[i];
        const Vec2 v_old = vel[i];
        Vec2 f = l.force + mass[i] * g;
        Vec2 fd = Vec2::Zero();
        if (alpha > 0.0) {
            // eq. 2.51: F_d = -alpha |F| sign(v) per degree of freedom
            for (int c = 0; c < 2; ++c) {
                const double v = v_old[c];
                fd[c] = v > 0.0 ? -alpha * std::abs(f[c]) : (v < 0.0 ? alpha * std::abs(f[c]) : 0.0);
            }
            f += fd;
        }
        const Vec2 v_new = v_old + f * (inv_mass[i] * dt);
        vel[i] = v_new;
        if (alpha > 0.0) diss_local -= 0.5 * fd.dot(v_old + v_new) * dt;  // centred work
        const Vec2 p = pos[i] + v_new * dt;
        pos[i] = p;
        // the kinetic energy after the step (the run's rest and blow-up watch): translation,
        // then rotation below; the AVX2 loop has the same operations
        double kinetic = (0.5 * mass[i]) * (v_new.x() * v_new.x() + v_new.y() * v_new.y());
        speed_l1 = std::max(speed_l1, std::abs(v_new.x()) + std::abs(v_new.y()));
        extent_l1 = std::max(extent_l1, std::abs(p.x()) + std::abs(p.y()));
        if (rot.model != 1) {
            double tq = l.torque;
            double td = 0.0;
            const double w_old = omega[i];
            if (alpha > 0.0) {
                td = w_old > 0.0 ? -alpha * std::abs(tq) : (w_old < 0.0 ? alpha * std::abs(tq) : 0.0);
                tq += td;
            }
            double w = w_old + tq * inv_inertia[i] * dt;
            const double w_free = w;
            if (alpha > 0.0) diss_local -= 0.5 * td * (w_old + w_free) * dt;
            // Model 2/3: Preh-Poisel rolling resistance for a disc touching a wall (eq. 2.71, 2.73)
            if (l.n_wall > 0 && rr_factor[i] > 0.0) {
                const double g_eff = rot.rolling_form == RollingForm::Literal ? k.g_abs : l.wall_normal * inv_mass[i];
                w = reduce_towards_zero(w, g_eff * rr_factor[i] * dt);
            }
            // Model 3: rotational damping at disc-disc contacts (eq. 2.75)
            if (rot.model == 3 && l.n_disc > 0)
                w *= rot.damping_per == RotDampingPer::Disc ? rot.mu_br : std::pow(rot.mu_br, l.n_disc);
            // Energy these velocity rules take out. The contact ledger credits the torque's work
            // over the mean of the old and the *final* omega; the dynamics moved it over the
            // mean of the old and the free one: the difference belongs here.
            diss_rot += 0.5 * inertia[i] * (w_free * w_free - w * w) - 0.5 * l.torque * dt * (w_free - w);
            omega[i] = w;
            angle[i] += w * dt;
            kinetic += (0.5 * inertia[i]) * (w * w);
        }
        block_local += diss_local;
        block_rot += diss_rot;
        kinetic_lanes[i % 4] += kinetic;
        if ((i + 1) % kLedgerBlock == 0 || i + 1 == end) {
            LedgerBlock& b = ledger_blocks[i / kLedgerBlock];
            b.local = block_local;
            b.rotation = block_rot;
            b.kinetic = (kinetic_lanes[0] + kinetic_lanes[1]) + (kinetic_lanes[2] + kinetic_lanes[3]);
            block_local = block_rot = 0.0;
            kinetic_lanes[0] = kinetic_lanes[1] = kinetic_lanes[2] = kinetic_lanes[3] = 0.0;
        }
        // Outside the (finite) domain, or not a number: one test, without branches. A
        // non-finite velocity shows in the position it has just moved (v dt is inf or NaN).
        // (It was a finiteness test of p + v and four branches: a sixth of this loop, perf.)
        const bool inside = (int(p.x() >= lo.x()) & int(p.x() <= hi.x()) & int(p.y() >= lo.y()) & int(p.y() <= hi.y())) != 0;
        const bool bad = !inside;
        if (bad && fault == SIZE_MAX) fault = i;
        // BroadPhase::inside_fat_box, through the local pointers
        const double r = radius[i];
        any_escaped = any_escaped || !(fat_lo[i].x() <= p.x() - r && fat_lo[i].y() <= p.y() - r &&
                                       p.x() + r <= fat_hi[i].x() && p.y() + r <= fat_hi[i].y());
    }
    integrate_note(chunk, fault, best_sq, any_escaped, speed_l1, extent_l1);
}

// A chunk's integration runs block by block (compute_forces): what each block found is added
// to the chunk's slots (reset by integrate_prepare): the first fault, the smallest step, any
// escape, the largest speed and extent.
void World::integrate_note(int chunk, size_t fault, double best_sq, bool any_escaped, double speed_l1, double extent_l1) {
    ChunkNote& note = chunk_note_[size_t(chunk)];
    if (note.fault == SIZE_MAX) note.fault = fault;
    note.dt_sq = std::min(note.dt_sq, best_sq);
    note.escaped = note.escaped || any_escaped;
    note.speed = std::max(note.speed, speed_l1);
    note.extent = std::max(note.extent, extent_l1);
}

void World::integrate_finish() {
    discs_may_have_escaped_ = false;
    for (const ChunkNote& note : chunk_note_) discs_may_have_escaped_ = discs_may_have_escaped_ || note.escaped;
    auto non_finite = [&](size_t i) {
        return !std::isfinite(pos_[i].x() + pos_[i].y() + vel_[i].x() + vel_[i].y());
    };
    auto blow_up = [&](size_t i) {
        return RunError("blow-up: non-finite state of disc " + std::to_string(id_[i]) + " at step " +
                        std::to_string(steps_) + ", t = " + format_number(time_) +
                        " s. Likely cause: a time step too large for the stiffness");
    };
    // the step's largest speed: the clearance test's approach (below), the travel check and
    // the next automatic step's cap (World::capped_by_travel)
    double speed = 0.0, extent = 0.0;
    for (const ChunkNote& note : chunk_note_) {
        speed = std::max(speed, note.speed);
        extent = std::max(extent, note.extent);
    }
    speed_l1_ = speed;
    check_travel();  // before a lost disc is blamed on a wall's free end: it may have crossed one
    bool any_fault = false;
    for (const ChunkNote& note : chunk_note_) {
        const size_t i = note.fault;
        if (i == SIZE_MAX) continue;
        any_fault = true;
        if (non_finite(i)) throw blow_up(i);
        if (def_.lost_discs == LostDiscs::Remove) continue;
        const Vec2& p = pos_[i];
        throw RunError("lost disc: " + where_disc(steps_, time_, id_[i], p) + " left the domain at velocity (" +
                       format_number(vel_[i].x()) + ", " + format_number(vel_[i].y()) +
                       ") m/s: it went over a wall's free end or through a gap between walls (world.lost_discs = "
                       "\"remove\" takes such discs out and goes on)");
    }
    if (any_fault) {
        // Remove: every disc outside the domain goes at the end of the step (a scan only in a
        // step where a chunk met one; the chunks note their first fault alone)
        const Vec2 lo = def_.domain_lo, hi = def_.domain_hi;
        for (size_t i = 0; i < pos_.size(); ++i) {
            if (non_finite(i)) throw blow_up(i);
            const Vec2& p = pos_[i];
            if (!(p.x() >= lo.x() && p.x() <= hi.x() && p.y() >= lo.y() && p.y() <= hi.y())) lost_pending_.push_back(i);
        }
    }
    double kinetic = 0.0;
    for (const LedgerBlock& b : ledger_blocks_) {
        diss_local_ += b.local;
        diss_rotation_ += b.rotation;
        kinetic += b.kinetic;
    }
    kinetic_ = kinetic;
    // The clearance test's approach (PairSkip, pair_kernel.h): no two discs came closer in
    // this step than twice the largest distance a disc moved, and a disc moved
    //     |fl(x + fl(v dt)) - x| <= |v| dt (1 + 2u) + u |x_new|   per coordinate (u = 2^-53),
    // so by at most (|vx| + |vy|) dt (1 + 2u) + u (|x| + |y|) in the plane (|.|_2 <= |.|_1).
    // The factors below are generous against the rounding of this sum. A range that was not
    // integrated met a fault, and the run stops above.
    const double moved = speed * dt_ * (1.0 + 0x1p-40) + 0x1p-50 * extent;
    approach_ += 2.0 * moved;
    // Rebase now and then: clearances are floats, and the slack of PairSkip is a fraction
    // 2^-20 of the approach, so keep it a small length (1024 margins, 0.4 m in DB-9k: every
    // few thousand steps of a fast flow). Not finite: look at every pair again.
    if (!(approach_ <= 1024.0 * broad_.margin())) forget_clearances();
}

}  // namespace demlab
