// The force pass (World::compute_forces): every candidate contact's law, each disc's sums,
// the walls' loads and the contacts' share of the energy ledger, shared out over the threads
// in ranges of discs (force_pass_ranges.cpp cuts them), each range's discs integrated as soon
// as their sums are complete.
//
// Every disc sums its terms from zero in contact-list order: its disc-disc contacts (sorted
// by (i, j)), then its wall contacts. Each thread owns a range of discs and the contacts
// whose first disc lies in it, so it adds most pairs straight into both discs' sums. A cross
// contact (j in a later range) is computed by the range owning j, into a slot, first thing:
// that range adds it first, which is its place in j's order (every cross contact of j has i
// in an earlier range, so it precedes j's own contacts in the list); the range owning i adds
// it when its loop reaches it. So the bits are the same for any number of threads. With the
// discs numbered in space order (order_in_space), under 2 % of the pairs cross, and the
// threads share no cache lines but those few slots; a design that sent every pair to a slot
// and gathered per disc moved 64 bytes per pair between the cores and gained 1.1-1.4x on 2
// threads against 1.7x now (docs/performance.md).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <thread>
#include <type_traits>

#include "core/error.h"
#include "core/validate.h"
#include "core/machine.h"
#include "dem/laws/wall_kernel.h"
#include "core/thread_pool.h"
#include "dem/world.h"
#include "dem/world_messages.h"

namespace demlab {

// the float nearest a double on the safe side: no greater / no smaller than it
static float round_down_float(double v) {
    const float f = float(v);
    return double(f) > v ? std::nextafter(f, -INFINITY) : f;
}
static float round_up_float(double v) {
    const float f = float(v);
    return double(f) < v ? std::nextafter(f, INFINITY) : f;
}

// Software prefetch in the force pass (WorldDef::prefetch). Once the step's arrays outgrow
// the last-level cache, every step brings them from memory, and the hardware prefetchers do
// not keep up with the pass' 20-odd streams: DB-9k's columns side by side (`bench db9k
// --copies 16`, 146,240 discs) stalled on the first load of each batch's contact records. The
// pass asks for the lines it will need kPrefetchContacts contacts and kPrefetchDiscs discs
// ahead (every disc a pair or the integration reads lies at or after the batch's first disc
// i, and its partners j within a few hundred places in space order), into L2 (the T1 hint):
// 52-61 -> 37-44 ns per particle-step on 1 thread on an AMD EPYC with 32 MB of L3
// (docs/performance.md). Into L1 (T0) it bought nothing: the core's few L1 miss buffers
// filled and the prefetches stalled the loop. With the arrays in the cache it costs 1-2 ns
// per particle-step, so Auto turns it on once the step streams more than half the
// last-level cache (prefetch_threshold_bytes). No prefetch changes a result.
constexpr size_t kPrefetchContacts = 256, kPrefetchDiscs = 256;

// Half of CPU 0's largest cache as Linux lists it (/sys/devices/system/cpu/cpu0/cache,
// machine.h), or 16 MB when it lists none. (glibc's sysconf(_SC_LEVEL3_CACHE_SIZE) can
// report a host's whole cache to a virtual machine: 320 MB where Linux listed 32 MB.)
size_t prefetch_threshold_bytes() {
    const size_t largest = machine_info().largest_cache_bytes;
    return largest > 0 ? largest / 2 : size_t(16) << 20;
}

// The bytes a step streams, the arrays prefetch_ahead asks for: per disc its position and
// velocity, eight doubles (radius, mass, inverse mass, inertia, inverse inertia, angle, spin,
// rolling factor), material, load record and fat box; per disc-disc candidate its record and
// clearance.
size_t World::step_bytes() const {
    constexpr size_t kPerDisc = 2 * sizeof(Vec2) + 8 * sizeof(double) + sizeof(int32_t) + sizeof(DiscLoad) + 2 * sizeof(Vec2);
    return pos_.size() * kPerDisc + dd_.size() * (sizeof(DiscContact) + sizeof(float));
}

bool World::prefetching() const {
    switch (def_.prefetch) {
        case Prefetch::On: return true;
        case Prefetch::Off: return false;
        case Prefetch::Auto: break;
    }
    return step_bytes() > prefetch_threshold_bytes();
}

// Asks for the cache lines of [from, to) into L2 (locality 2: T1), for reading or writing.
template <bool kWrite>
static inline void prefetch_lines(const void* from, const void* to) {
    const uintptr_t end = reinterpret_cast<uintptr_t>(to);
    for (uintptr_t a = reinterpret_cast<uintptr_t>(from) & ~uintptr_t(63); a < end; a += 64)
        __builtin_prefetch(reinterpret_cast<const void*>(a), kWrite ? 1 : 0, 2);
}

// A pair's terms into its first disc i (which gets -f) and into its second disc j.
static inline void add_to_i(DiscLoad* load, size_t i, const PairOut& o) {
    DiscLoad& l = load[i];
    l.dissipated += 0.5 * o.dissipated;  // the ledger: half to each disc (exact)
    if (!o.touching) {
        l.k_tran += o.k_tran;  // +0, but for a law whose closing pairs set the step (kStepAhead)
        return;
    }
    l.force -= o.f;
    l.torque += o.torque_i;
    l.k_tran += o.k_tran;
    l.k_rot += o.k_rot;
    ++l.n_disc;
}
static inline void add_to_j(DiscLoad* load, size_t j, const PairOut& o) {
    DiscLoad& l = load[j];
    l.dissipated += 0.5 * o.dissipated;
    if (!o.touching) {
        l.k_tran += o.k_tran;
        return;
    }
    l.force += o.f;
    l.torque += o.torque_j;
    l.k_tran += o.k_tran;
    l.k_rot += o.k_rot;
    ++l.n_disc;
}

void World::note_disc_fault(size_t k, double overlap, int chunk) {
    if (k >= dd_fault_[size_t(chunk)].index) return;
    const size_t i = size_t(dd_[k].i), j = size_t(dd_[k].j);
    dd_fault_[size_t(chunk)] =
        Fault{k, "blow-up: overlap " + format_number(overlap) + " m between discs " + std::to_string(id_[i]) + " and " +
                     std::to_string(id_[j]) + " exceeds " + format_number(def_.max_overlap_ratio) +
                     " of the smaller radius at " + where_disc(steps_, time_, id_[i], pos_[i]) +
                     ". Likely cause: the time step is too large for the stiffness and speeds (use the automatic "
                     "time step or a smaller safety factor)"};
}

void World::note_wall_fault(size_t kw, double overlap, int chunk) {
    if (kw >= dw_fault_[size_t(chunk)].index) return;
    const size_t i = size_t(dw_[kw].disc), w = size_t(dw_[kw].wall);
    dw_fault_[size_t(chunk)] =
        Fault{kw, "blow-up: overlap " + format_number(overlap) + " m of disc " + std::to_string(id_[i]) + " with wall '" +
                      walls_[w].name + "' exceeds " + format_number(def_.max_overlap_ratio) + " of its radius at " +
                      where_disc(steps_, time_, id_[i], pos_[i]) +
                      ". Likely cause: a time step too large for the stiffness, or a disc crossing the wall"};
}

void World::compute_forces(bool then_integrate) {
    with_contact_law(def_.law, [&](auto law) { compute_forces_with<decltype(law)>(then_integrate); });
}

template <typename Law>
void World::compute_forces_with(bool then_integrate) {
    wall_sums_.resize(size_t(force_ranges_));
    for (size_t t = 0; t < wall_sums_.size(); ++t) wall_sums_[t].resize(wall_split_[t + 1] - wall_split_[t]);
    // one fault record per chunk, kept between steps (no allocation in the step)
    dd_fault_.resize(size_t(pool_->size()));
    dw_fault_.resize(size_t(pool_->size()));
    for (Fault& f : dd_fault_) f.index = SIZE_MAX;
    for (Fault& f : dw_fault_) f.index = SIZE_MAX;
    if (clearances_stale_) {
        std::fill(clearance_.begin(), clearance_.end(), 0.0f);
        approach_ = 0.0;
        clearances_stale_ = false;
    }
    if (cross_copies_stale_) copy_cross_contacts();
    // centred dashpots (centred_dashpots.cpp): the pass sums the forces, the dashpots are
    // moved to the step's centre, then the ranges integrate
    const bool centred = then_integrate && centred_dashpots();
    const bool fused = then_integrate && !centred;
    const PassContext<Law> ctx{DiscArrays{pos_.data(), vel_.data(), radius_.data(), omega_.data(), material_.data()},
                          PairPassParamsT<typename Law::Params>{tables<Law>().disc_disc.data(), disc_materials_,
                                                                def_.damping.dp_mode, dt_, last_dt_, def_.max_overlap_ratio},
                          then_integrate ? integrate_prepare() : IntegrateConsts{},
                          fused,
                          prefetching(),
                          ++cross_pass_,
                          // the clearance test's bound as floats, rounded outwards (PairSkip)
                          round_down_float(approach_),
                          round_up_float(approach_),
                          centred};
    if (centred) prepare_centred_pass();
    if (!bonds_.empty()) compute_bond_forces();
    if (force_ranges_ == 1) {
        range_pass<Law>(0, ctx);
    } else {
        const auto pass_started = std::chrono::steady_clock::now();
        pool_->for_each_thread([&](int t) { range_pass<Law>(t, ctx); });
        const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - pass_started).count();
        shared_pass_seconds_ += wall;
        window_pass_seconds_ += wall;
        for (const RangeClock& c : range_clock_) shared_pass_busy_seconds_ += c.last;
    }
    for (PairBatch& b : pair_batch_) {
        pairs_skipped_ += long(b.skipped);
        b.skipped = 0;
    }
    candidate_passes_ += long(dd_.size());
    for (const auto* faults : {&dd_fault_, &dw_fault_}) {
        const Fault* first = nullptr;
        for (const Fault& f : *faults)
            if (f.index != SIZE_MAX && (!first || f.index < first->index)) first = &f;
        if (first) throw RunError(first->message);
    }
    // (a wall contact without its record would be a bug of the pass: stop, naming it)
    if (centred)
        for (const uint8_t ok : dash_ok_)
            if (!ok) throw RunError("internal: a wall contact's record is missing (centred dashpots)");
    add_up_pass();
    if (!bonds_.empty()) {
        book_bond_dashpots();
        settle_bond_breaks();
    }
}

// The cross contacts' own copies of their records and clearances (cross_dd_, world.h).
void World::copy_cross_contacts() {
    cross_dd_.resize(cross_.size());
    cross_clearance_.resize(cross_.size());
    cross_pos_.resize(cross_.size());
    for (size_t p = 0; p < cross_in_.size(); ++p) {
        const size_t m = size_t(cross_in_[p]), k = size_t(cross_[m]);
        cross_dd_[p] = dd_[k];
        cross_clearance_[p] = clearance_[k];
        cross_pos_[m] = int32_t(p);
    }
    cross_copies_stale_ = false;
}

// The cross contacts (split_force_pass) are computed into their slots by the range that owns
// their second disc, first thing, and it then raises its flag for this pass. The range that
// owns their first disc waits for the flags of all later ranges before its first cross
// contact: it reads the slots there, and from there on it integrates the discs those pairs
// read (its cross contacts are its last, in list order, and a pair's first disc comes no
// earlier). Computed on the calling thread before the ranges started, they cost 4 % of a
// 2-thread flume run.
//
// The computing range works on copies of the cross contacts' records and clearances
// (cross_dd_, cross_clearance_), with the pass' own selection: a pair that is clear skips the
// law and never reads its discs. Run in place in dd_, among the owning range's contacts,
// every history it wrote took a line of dd_ from the other core's cache and handed it back
// when that range came to it: DB-9k's 223 cross contacts a step took 22-44 ns each against
// 14-31 ns with the copies. The owning range copies a history back when it adds the contact,
// so dd_ is whole after every pass (energy(), checkpoints and the lists' merge read it).
template <typename Law>
void World::compute_cross_contacts(size_t t, const PassContext<Law>& ctx) {
    PairBatch* const batch = Law::kWideKernels && avx2_ ? &pair_batch_[t] : nullptr;
    const size_t e0 = size_t(cross_in_start_[t]), e1 = size_t(cross_in_start_[t + 1]);
    // A pair with nothing to do gets no results (it would add +0 and keep its zero history);
    // the rest of a batch (fewer than four, or from a blown-up pair on) goes to the scalar
    // kernel, which reports a blow-up
    PairSkip skip{nullptr, ctx.approach_lo, ctx.approach_hi};
    for (size_t e = e0; e < e1;) {
        const size_t n = std::min(PairBatch::kSize, e1 - e);
        for (size_t p = e; p < e + n; ++p) cross_todo_[size_t(cross_in_[p])] = 0;
        size_t done = 0;
        if constexpr (Law::kWideKernels) if (batch) {
            skip.clearance = cross_clearance_.data() + e;
            done = avx512_ ? disc_pairs_avx512(ctx.discs, ctx.pp, cross_dd_.data() + e, n, *batch, &skip)
                           : disc_pairs_avx2(ctx.discs, ctx.pp, cross_dd_.data() + e, n, *batch, &skip);
            for (size_t b = 0; b < batch->count; ++b) {
                const size_t m = size_t(cross_in_[e + batch->index[b]]);
                PairOut& o = cross_out_[m];
                o.touching = batch->touching[b] != 0;
                o.f = Vec2(batch->fx(b), batch->fy(b));
                o.torque_i = batch->torque_i(b);
                o.torque_j = batch->torque_j(b);
                o.k_tran = batch->k_tran(b);
                o.k_rot = batch->k_rot(b);
                // the pass adds half of it: exactly the half the batch holds
                o.dissipated = 2.0 * batch->half_dissipated(b);
                cross_todo_[m] = 1;
            }
        }
        for (size_t p = e + done; p < e + n; ++p) {
            const size_t m = size_t(cross_in_[p]);
            double overlap = 0.0;
            if (!disc_pair_force<Law>(ctx.discs, ctx.pp, cross_dd_[p], cross_out_[m], overlap))
                note_disc_fault(size_t(cross_[m]), overlap, int(t));
            cross_todo_[m] = 1;
        }
        e += n;
    }
    cross_done_[t].pass.store(ctx.pass, std::memory_order_release);
}

// Returns the seconds it waited: not the range's work, so left out of its measured time (the
// balancing would otherwise move work away from the range that waits). It yields after a
// short spin, as the pool does: with more threads than free cores the range it waits for may
// need this core.
double World::wait_for_cross(size_t t, uint64_t pass) const {
    return wait_for(cross_done_.get(), t + 1, size_t(force_ranges_), pass);
}

double World::wait_for(const CrossDone* flags, size_t u0, size_t u1, uint64_t pass) {
    double waited = 0.0;
    for (size_t u = u0; u < u1; ++u) {
        if (flags[u].pass.load(std::memory_order_acquire) == pass) continue;
        const auto w0 = std::chrono::steady_clock::now();
        for (unsigned polls = 1; flags[u].pass.load(std::memory_order_acquire) != pass; ++polls) {
            if (polls < 2048)
                DEMLAB_CPU_RELAX();
            else
                std::this_thread::yield();
        }
        waited += std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count();
    }
    return waited;
}

// One range's share of the pass, block by block (FuseBlock): the pairs whose first disc is in
// the block, then the block's wall contacts; then the block's sums are complete (a disc's
// pairs with earlier discs came in earlier blocks, its cross terms first) and no later pair
// reads its discs (a pair's second disc comes after its first), so the block is integrated
// while its loads and state are still in the cache. Every disc adds its terms in the order it
// did when the range was one block: the same bits.
template <typename Law>
void World::range_pass(int t, const PassContext<Law>& ctx) {
    const auto started = std::chrono::steady_clock::now();
    const size_t tr = size_t(t);
    const size_t d0 = disc_split_[tr];
    double waited = 0.0;  // s, for the cross contacts of later ranges (wait_for_cross)
    DiscLoad* const load = load_.data();
    float* const clearance = clearance_.data();
    // The loads are zeroed just ahead of the first pair that adds to them (the blocks' reach,
    // split_force_pass), not all at the range's start: by the time the pairs of a range's
    // last discs came, their zeroed lines had left the cache.
    size_t zeroed = d0;
    auto zero_to = [&](size_t e) {
        if (e <= zeroed) return;
        std::fill(load + zeroed, load + e, DiscLoad{});
        zeroed = e;
    };
    // cross contacts into this range's discs: computed here, then added first, in their order
    if (force_ranges_ > 1) compute_cross_contacts<Law>(tr, ctx);
    zero_to(cross_in_reach_[tr]);
    for (int32_t e = cross_in_start_[tr]; e < cross_in_start_[tr + 1]; ++e) {
        const size_t m = size_t(cross_in_[size_t(e)]);
        if (cross_todo_[m]) add_to_j(load, size_t(cross_dd_[size_t(e)].j), cross_out_[m]);
    }
    // this range's own cross contacts, in list order
    size_t next = cross_start_[tr];
    size_t next_k = next < cross_.size() ? size_t(cross_[next]) : SIZE_MAX;
    PairBatch* const batch = Law::kWideKernels && avx2_ ? &pair_batch_[tr] : nullptr;
    PairSkip skip_base{nullptr, ctx.approach_lo, ctx.approach_hi};
    range_clock_[tr].touching_dd = 0;
    uint32_t* const touching_list = ctx.centred ? touching_list_[tr].data() : nullptr;
    size_t n_touching = 0;
    WallSum* const wall_sums = wall_sums_[tr].data();
    size_t n_wall_sums = 0;
    size_t k = contact_split_[tr], kw = wall_split_[tr], b0 = d0;
    // software prefetch (kPrefetchContacts): the contacts and discs asked for so far
    const size_t contact_end = contact_split_[tr + 1], disc_end = disc_split_[tr + 1];
    size_t asked_k = k, asked_d = d0;
    auto prefetch_ahead = [&](size_t at) {
        const size_t k_to = std::min(contact_end, at + kPrefetchContacts);
        if (k_to > asked_k) {
            prefetch_lines<true>(dd_.data() + asked_k, dd_.data() + k_to);
            prefetch_lines<true>(clearance + asked_k, clearance + k_to);
            asked_k = k_to;
        }
        const size_t d_to = std::min(disc_end, size_t(dd_[at].i) + kPrefetchDiscs);
        if (d_to > asked_d) {
            const size_t a = asked_d;
            prefetch_lines<true>(pos_.data() + a, pos_.data() + d_to);
            prefetch_lines<true>(vel_.data() + a, vel_.data() + d_to);
            prefetch_lines<true>(omega_.data() + a, omega_.data() + d_to);
            prefetch_lines<true>(angle_.data() + a, angle_.data() + d_to);
            prefetch_lines<true>(load + a, load + d_to);
            prefetch_lines<false>(radius_.data() + a, radius_.data() + d_to);
            prefetch_lines<false>(mass_.data() + a, mass_.data() + d_to);
            prefetch_lines<false>(inv_mass_.data() + a, inv_mass_.data() + d_to);
            prefetch_lines<false>(inertia_.data() + a, inertia_.data() + d_to);
            prefetch_lines<false>(inv_inertia_.data() + a, inv_inertia_.data() + d_to);
            prefetch_lines<false>(rr_factor_.data() + a, rr_factor_.data() + d_to);
            prefetch_lines<false>(material_.data() + a, material_.data() + d_to);
            prefetch_lines<false>(broad_.fat_lo_data() + a, broad_.fat_lo_data() + d_to);
            prefetch_lines<false>(broad_.fat_hi_data() + a, broad_.fat_hi_data() + d_to);
            asked_d = d_to;
        }
    };
    // Centred dashpots: the range's blocks are packed as their sums complete, centred once
    // every disc their pairs reach is packed, then integrated while their lines are still in
    // the cache (one pass over the step's data, no join between the phases). The discs below
    // the late end get cross shifts from earlier ranges, which come first in their order:
    // their blocks finish last (finish_late_discs).
    const size_t fb_first = fuse_start_[tr], fb_end = fuse_start_[tr + 1];
    const size_t late_end = tr > 0 ? cross_in_reach_[tr] : d0;
    size_t next_centre = fb_first, packed = d0, cross_cursor = cross_start_[tr];
    const size_t first_cross_k = cross_start_[tr] < cross_start_[tr + 1] ? size_t(cross_[cross_start_[tr]]) : SIZE_MAX;
    bool packed_told = !ctx.centred || tr == 0, later_packed = false;
    auto tell_packed = [&]() {
        if (packed_told || packed < late_end) return;
        centre_packed_[tr].pass.store(ctx.pass, std::memory_order_release);
        packed_told = true;
    };
    tell_packed();  // (no earlier range's cross pair reaches this range)
    [[maybe_unused]] CentreConsts centre_k{};
    if constexpr (Law::kCentredDashpots)
        if (ctx.centred) centre_k = centre_consts(ctx.pp);
    auto block_start = [&](size_t c) { return c == fb_first ? d0 : fuse_blocks_[c - 1].disc_end; };
    auto block_walls = [&](size_t c, size_t& e) {
        e = c == fb_first ? 0 : fuse_sums_end_[c - 1];
        const size_t kw0 = c == fb_first ? wall_split_[tr] : fuse_blocks_[c - 1].wall_end;
        if (!centre_walls(tr, centre_k, kw0, fuse_blocks_[c].wall_end, e)) dash_ok_[tr] = 0;
    };
    auto centre_up_to = [&](size_t c_end) {
        if constexpr (Law::kCentredDashpots) {
            for (; next_centre < c_end && fuse_blocks_[next_centre].reach <= packed; ++next_centre) {
                const size_t c = next_centre;
                if (fuse_blocks_[c].contact_end > first_cross_k && !later_packed) {
                    // its cross pairs read the later ranges' first discs: packed, not yet moved
                    waited += wait_for(centre_packed_.get(), tr + 1, size_t(force_ranges_), ctx.pass);
                    later_packed = true;
                }
                centre_rows(tr, ctx.pp, centre_k, c == fb_first ? 0 : fuse_touching_end_[c - 1], fuse_touching_end_[c],
                            late_end, cross_cursor, ctx.prefetch);
                if (block_start(c) < late_end) continue;  // finished after the cross shifts
                size_t e = 0;
                block_walls(c, e);
                if (dd_fault_[tr].index == SIZE_MAX && dw_fault_[tr].index == SIZE_MAX)
                    integrate_centred(block_start(c), fuse_blocks_[c].disc_end, t, ctx.ic);
            }
        }
    };
    for (size_t fbi = fuse_start_[tr]; fbi < fuse_start_[tr + 1]; ++fbi) {
        const FuseBlock& fb = fuse_blocks_[fbi];
        zero_to(fb.reach);
        for (; k < fb.contact_end; ++k) {
            DiscContact& c = dd_[k];
            if (k == next_k) {  // computed by the range that owns c.j
                if (next == cross_start_[tr]) waited += wait_for_cross(tr, ctx.pass);
                if (cross_todo_[next]) {
                    if (touching_list && cross_out_[next].touching) touching_list[n_touching++] = uint32_t(k);
                    add_to_i(load, size_t(c.i), cross_out_[next]);
                    const DiscContact& h = cross_dd_[size_t(cross_pos_[next])];
                    Law::for_each_history_field([](const auto& from, auto& to) { to = from; }, h, c);
                }
                ++next;
                next_k = next < cross_.size() ? size_t(cross_[next]) : SIZE_MAX;
                continue;
            }
            if constexpr (Law::kWideKernels) if (batch) {
                // up to a batch of pairs before the next cross contact, four (or eight) at a
                // time, then added in list order (what the scalar kernel below does pair by pair)
                const size_t n = std::min({fb.contact_end, next_k, k + PairBatch::kSize}) - k;
                if (ctx.prefetch) prefetch_ahead(k);
                skip_base.clearance = clearance + k;
                const size_t done = avx512_ ? disc_pairs_avx512(ctx.discs, ctx.pp, &c, n, *batch, &skip_base)
                                            : disc_pairs_avx2(ctx.discs, ctx.pp, &c, n, *batch, &skip_base);
                add_pair_batch_avx2(*batch, &c, load);
                if (touching_list)
                    for (size_t b = 0; b < batch->count; ++b) {
                        touching_list[n_touching] = uint32_t(k + batch->index[b]);
                        n_touching += size_t(batch->touching[b] != 0);
                    }
                if (done > 0) {
                    k += done - 1;
                    continue;
                }
            }
            PairOut o;
            double overlap = 0.0;
            if (!disc_pair_force<Law>(ctx.discs, ctx.pp, c, o, overlap)) {
                note_disc_fault(k, overlap, t);
                continue;
            }
            if (touching_list && o.touching) touching_list[n_touching++] = uint32_t(k);
            add_to_i(load, size_t(c.i), o);
            add_to_j(load, size_t(c.j), o);
        }
        if constexpr (Law::kDiscFriction) std::fill(wall_reaction_.begin() + ptrdiff_t(b0), wall_reaction_.begin() + ptrdiff_t(fb.disc_end), Vec2::Zero());
        n_wall_sums = wall_contacts<Law>(kw, fb.wall_end, t, ctx, wall_sums, n_wall_sums);
        if (!bonds_.empty()) add_bond_terms(b0, fb.disc_end);
        if (any_external_force_) add_external_forces(b0, fb.disc_end);
        // The block's sums are complete. A range that met a fault integrates no more blocks,
        // but goes on with its pairs (the pass then throws the first fault in list order,
        // whatever the blocks and ranges).
        const size_t b1 = fb.disc_end;
        if (ctx.centred) {
            fuse_touching_end_[fbi] = n_touching;
            fuse_sums_end_[fbi] = n_wall_sums;
            range_clock_[tr].wall_sums = n_wall_sums;  // (centre_walls reads it)
            pack_centre_discs(b0, b1);
            packed = b1;
            tell_packed();
            centre_up_to(fbi + 1);
            b0 = b1;
            continue;
        }
        const bool integrate =
            ctx.then_integrate && dd_fault_[tr].index == SIZE_MAX && dw_fault_[tr].index == SIZE_MAX;
        // the AVX2 integration adds up the block's ledger terms as it goes
        if (!(integrate && avx2_integration())) block_ledger(b0, b1, tr);
        if (integrate) integrate_discs(b0, b1, t, ctx.ic);
        b0 = b1;
    }
    range_clock_[tr].wall_sums = n_wall_sums;
    if (ctx.centred) {
        centre_up_to(fb_end);  // (every block's reach is packed now)
        // every range tells, so that a range waits for all earlier (or later) ones alike
        centre_shifted_[tr].pass.store(ctx.pass, std::memory_order_release);
        if (late_end > d0) {
            waited += wait_for(centre_shifted_.get(), 0, tr, ctx.pass);
            finish_late_discs(tr);
            const bool integrate = dd_fault_[tr].index == SIZE_MAX && dw_fault_[tr].index == SIZE_MAX;
            for (size_t c = fb_first; c < fb_end && block_start(c) < late_end; ++c) {
                size_t e = 0;
                block_walls(c, e);
                if (integrate) integrate_centred(block_start(c), fuse_blocks_[c].disc_end, t, ctx.ic);
            }
        }
    }
    const double busy = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count() - waited;
    range_clock_[tr].seconds += busy;
    range_clock_[tr].last = busy;
}

// The wall contacts dw_[kw, end) of range t: their law, their terms into their discs' sums,
// and a record (WallSum) for the walls' loads and the ledger of each one that touches or
// dissipates, from sums[n] on. Returns the records' count.
template <typename Law>
size_t World::wall_contacts(size_t& kw, size_t end, int t, const PassContext<Law>& ctx, WallSum* sums, size_t n) {
    const size_t nw = walls_.size();
    DiscLoad* const load = load_.data();
    for (; kw < end; ++kw) {
        WallContact& c = dw_[kw];
        const size_t i = size_t(c.disc), w = size_t(c.wall);
        const Vec2 vwall = wall_moving_[w] ? walls_[w].velocity : Vec2::Zero();
        const typename Law::Params& pm = tables<Law>().disc_wall[size_t(material_[i]) * nw + w];
        WallOut o;
        double overlap = 0.0;
        if (!disc_wall_force<Law>(geom_[w], wall_active_[w] != 0, vwall, pos_[i], vel_[i], omega_[i], radius_[i], pm,
                             ctx.pp.mode, ctx.pp.dt, ctx.pp.last_dt, ctx.pp.max_overlap_ratio, c, o, overlap, def_.gravity)) {
            note_wall_fault(kw, overlap, t);
            continue;
        }
        if (!o.touching) {
            if (o.dissipated != 0.0) sums[n++] = WallSum{0.0, 0.0, 0.0, o.dissipated, -1, int32_t(i)};
            if constexpr (Law::kStepAhead) load[i].k_tran += o.k_tran;  // closing in (DebrisLaw)
            continue;
        }
        sums[n++] = WallSum{o.force.x(), o.force.y(), cross(o.point, o.force), o.dissipated, int32_t(w), int32_t(i)};
        DiscLoad& l = load[i];
        l.force += o.force;
        l.torque += o.torque;
        l.k_tran += o.k_tran;
        l.k_rot += o.k_rot;
        l.wall_normal += o.fn_spring;
        ++l.n_wall;
        if constexpr (Law::kDiscFriction) wall_reaction_[i] += o.force;
    }
    return n;
}

// The ledger's share of discs [b0, b1) of range t: the contacts' dissipation per ledger block
// of discs (in disc order, as a serial pass would add them) and the touching pairs.
void World::block_ledger(size_t b0, size_t b1, size_t t) {
    const DiscLoad* const load = load_.data();
    long touching = 0;
    for (size_t l0 = b0; l0 < b1; l0 += kLedgerBlock) {
        const size_t l1 = std::min(l0 + kLedgerBlock, b1);
        double sum = 0.0;
        for (size_t d = l0; d < l1; ++d) {
            sum += load[d].dissipated;
            touching += load[d].n_disc;
        }
        ledger_blocks_[l0 / kLedgerBlock].contacts = sum;
    }
    range_clock_[t].touching_dd += touching;
}

// After the ranges: the ledger's disc-disc terms through the discs' halves, summed per block
// of discs in the ranges and here over the blocks in order (the same bits for any cut and
// thread count; a serial pass over all discs here made the caller read every line the other
// threads had written, and cost 2 threads a fifth of their speed); then the wall loads, in
// contact-list order.
void World::wall_loads(std::vector<WallLoad>& out) const {
    out.clear();
    for (size_t t = 0; t < wall_sums_.size() && t < range_clock_.size(); ++t)
        for (size_t e = 0, n = range_clock_[t].wall_sums; e < n; ++e) {
            const WallSum& o = wall_sums_[t][e];
            if (o.wall >= 0 && o.disc >= 0) out.push_back({o.disc, o.wall, -Vec2(o.fx, o.fy)});
        }
}

void World::add_up_pass() {
    double dissipated = 0.0;
    for (const LedgerBlock& b : ledger_blocks_) dissipated += b.contacts;
    long touching = 0;
    for (const RangeClock& c : range_clock_) touching += c.touching_dd;
    touching_dd_ = touching / 2;
    touching = 0;
    std::fill(wall_force_.begin(), wall_force_.end(), Vec2::Zero());
    std::fill(wall_moment_.begin(), wall_moment_.end(), 0.0);
    // The records are the wall contacts in list order without those that add nothing: not
    // touching and no dissipation. Leaving out their +0 or -0 keeps the bits: the sum starts
    // at +0, and x + 0 = x for every x but -0, which a sum from +0 never reaches. A 48-byte
    // record per wall contact, all read by this loop, made a worker's stores wait for the
    // lines this loop had read: on slow stretches it spent 5 times the main thread's time on
    // its wall contacts (docs/performance.md).
    for (size_t t = 0; t < wall_sums_.size(); ++t) {
        const WallSum* const sums = wall_sums_[t].data();
        for (size_t e = 0, n = range_clock_[t].wall_sums; e < n; ++e) {
            const WallSum& o = sums[e];
            dissipated += o.dissipated;
            if (o.wall < 0) continue;
            ++touching;
            const size_t w = size_t(o.wall);
            wall_force_[w] -= Vec2(o.fx, o.fy);
            wall_moment_[w] -= o.moment;
        }
    }
    touching_dw_ = touching;
    diss_contacts_ += dissipated;
}

}  // namespace demlab
