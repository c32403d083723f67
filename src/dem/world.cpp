#include "dem/world.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>
#include <thread>

#include "core/error.h"
#include "dem/integrate_kernel.h"
#include "core/machine.h"
#include "dem/range_balance.h"
#include "core/thread_pool.h"
#include "dem/timestep.h"
#include "core/validate.h"

namespace demlab {

static PairMaterial pair_material(double kn, double ks, double mu) { return {kn, ks, mu, std::max(kn, ks), 1.0 / ks}; }

void validate(const WorldDef& d, const std::string& where) {
    require_finite(where + ".gravity", d.gravity, "m/s2");
    require_range(where + ".damping.beta_n", d.damping.beta_n, 0.0, 1.0, true, "(ratio)");
    require_range(where + ".damping.beta_s", d.damping.beta_s, 0.0, 1.0, true, "(ratio)");
    require_range(where + ".damping.local_alpha", d.damping.local_alpha, 0.0, 1.0, true, "(ratio)");
    const int mode = int(d.damping.dp_mode);
    if (mode < 0 || mode > 3)
        throw InputError(where + ".damping.dp_mode = " + std::to_string(mode) + ": must be 0, 1, 2 or 3");
    require_range(where + ".timestep.safety", d.timestep.safety, 1e-6, 1.0, false, "(factor)");
    if (!d.timestep.automatic) require_positive(where + ".timestep.fixed", d.timestep.fixed, "s");
    require_non_negative(where + ".broadphase_margin", d.broadphase_margin, "m");
    require_finite(where + ".domain_lo", d.domain_lo, "m");  // the integrator's lost-disc test needs finite bounds
    require_finite(where + ".domain_hi", d.domain_hi, "m");
    require_non_negative(where + ".wall_piece_length", d.wall_piece_length, "m");
    require_non_negative(where + ".joint_tolerance", d.joint_tolerance, "m");
    require_range(where + ".max_overlap_ratio", d.max_overlap_ratio, 1e-6, 2.0, false, "(ratio)");
}

World::World(const WorldDef& def)
    : def_(def), pool_(std::make_unique<ThreadPool>(def.threads)), avx2_(def.simd && cpu_has_avx2()),
      avx512_(avx2_ && def.avx512 && cpu_has_avx512()) {
    broad_.set_pool(pool_.get());
    if (avx2_) pair_batch_.resize(size_t(pool_->size()));
}

World::~World() = default;
World::World(World&&) noexcept = default;

int World::add_material(const MaterialDef& m) {
    validate(m, "material[" + std::to_string(materials_.size()) + "]");
    materials_.push_back(m);
    return int(materials_.size()) - 1;
}

int World::add_disc(const DiscDef& d) {
    const std::string where = "disc[" + std::to_string(pos_.size()) + "]";
    require_finite(where + ".position", d.pos, "m");
    require_positive(where + ".radius", d.radius, "m");
    require_finite(where + ".velocity", d.vel, "m/s");
    require_finite(where + ".omega", d.omega, "rad/s");
    require_finite(where + ".angle", d.angle, "rad");
    if (d.material < 0 || size_t(d.material) >= materials_.size())
        throw InputError(where + ".material = " + std::to_string(d.material) + ": no such material (" +
                         std::to_string(materials_.size()) + " defined)");
    if (finalized_) throw InputError(where + ": discs must be added before finalize()");
    const MaterialDef& m = materials_[size_t(d.material)];
    const double mass = m.density * kPi * d.radius * d.radius;
    const double inertia = 0.5 * mass * d.radius * d.radius;
    pos_.push_back(d.pos);
    vel_.push_back(d.vel);
    radius_.push_back(d.radius);
    mass_.push_back(mass);
    inv_mass_.push_back(1.0 / mass);
    inertia_.push_back(inertia);
    inv_inertia_.push_back(1.0 / inertia);
    angle_.push_back(d.angle);
    omega_.push_back(def_.rotation.model == 1 ? 0.0 : d.omega);
    material_.push_back(d.material);
    return int(pos_.size()) - 1;
}

int World::add_wall(const WallDef& w) {
    validate(w, w.name.empty() ? "wall[" + std::to_string(walls_.size()) + "]" : "wall '" + w.name + "'");
    if (finalized_) throw InputError("walls must be added before finalize()");
    walls_.push_back(w);
    return int(walls_.size()) - 1;
}

void World::set_dt(double dt) {
    require_positive("dt", dt, "s");
    def_.timestep.automatic = false;
    def_.timestep.fixed = dt;
    dt_ = dt;
}

void World::set_radius(int i, double r) {
    require_positive("disc[" + std::to_string(i) + "].radius", r, "m");
    const size_t k = size_t(i);
    const double mass = materials_[size_t(material_[k])].density * kPi * r * r;
    radius_[k] = r;
    discs_may_have_escaped_ = true;
    forget_clearances();  // a larger disc may touch a pair found clear
    mass_[k] = mass;
    inv_mass_[k] = 1.0 / mass;
    inertia_[k] = 0.5 * mass * r * r;
    inv_inertia_[k] = 1.0 / inertia_[k];
    if (!rr_factor_.empty() && def_.rotation.model >= 2 && def_.rotation.u_rr > 0.0)
        rr_factor_[k] = preh_poisel_factor(r, def_.rotation.u_rr);
}

void World::refresh_dashpots() {
    const size_t nm = materials_.size(), nw = walls_.size();
    cross_copies_stale_ = true;
    for (DiscContact& c : dd_) {
        const PairMaterial& pm = mat_dd_[size_t(material_[size_t(c.i)]) * nm + size_t(material_[size_t(c.j)])];
        const double m_eff = contact_mass_disc(c.i, c.j);
        c.cn = dashpot_coefficient(def_.damping.beta_n, m_eff, pm.kn);
        c.cs = dashpot_coefficient(def_.damping.beta_s, m_eff, pm.ks);
    }
    for (WallContact& c : dw_) {
        const PairMaterial& pm = mat_dw_[size_t(material_[size_t(c.disc)]) * nw + size_t(c.wall)];
        c.cn = dashpot_coefficient(def_.damping.beta_n, mass_[size_t(c.disc)], pm.kn);
        c.cs = dashpot_coefficient(def_.damping.beta_s, mass_[size_t(c.disc)], pm.ks);
    }
}

double World::unbalanced_force_ratio() const {
    double net = 0.0, contact = 0.0;
    long touching = 0;
    for (size_t i = 0; i < pos_.size(); ++i) {
        if (load_[i].k_tran == 0.0) continue;  // no contacts
        ++touching;
        net += (load_[i].force + mass_[i] * def_.gravity).norm();
        contact += load_[i].force.norm();
    }
    return touching == 0 || contact == 0.0 ? 0.0 : net / contact;
}

void World::set_local_damping(double alpha) {
    require_range("local_alpha", alpha, 0.0, 1.0, true, "(ratio)");
    def_.damping.local_alpha = alpha;
}

// Wall ends closer than joint_tolerance are joined: a segment's end is moved onto the
// neighbour's end (an arc's ends are fixed by its centre and angles), so the two walls meet
// exactly. A tangential joint is left open (no corner), so a disc crossing it is carried by
// one wall or the other with a continuous normal force; any other joint keeps its corners.
void World::join_wall_ends() {
    const size_t nw = walls_.size();
    geom_.resize(nw);
    for (size_t w = 0; w < nw; ++w) geom_[w] = make_geom(walls_[w]);
    auto end_point = [&](size_t w, int e) -> Vec2& { return e == 0 ? geom_[w].p0 : geom_[w].p1; };
    std::vector<int> joined(2 * nw, 0);
    for (size_t a = 0; a < nw; ++a) {
        for (int ea = 0; ea < 2; ++ea) {
            for (size_t b = a + 1; b < nw; ++b) {
                for (int eb = 0; eb < 2; ++eb) {
                    Vec2& pa = end_point(a, ea);
                    Vec2& pb = end_point(b, eb);
                    if ((pa - pb).norm() > def_.joint_tolerance) continue;
                    const bool seg_a = geom_[a].shape == WallShape::Segment;
                    const bool seg_b = geom_[b].shape == WallShape::Segment;
                    if (seg_a && seg_b) {
                        const Vec2 mid = 0.5 * (pa + pb);
                        pa = mid;
                        pb = mid;
                    } else if (seg_a) {
                        pa = pb;
                    } else if (seg_b) {
                        pb = pa;
                    }
                    // tangents at the joint, oriented along each wall away from its start
                    const Vec2 ta = ea == 0 ? tangent_at_start(geom_[a]) : tangent_at_end(geom_[a]);
                    const Vec2 tb = eb == 0 ? tangent_at_start(geom_[b]) : tangent_at_end(geom_[b]);
                    const bool tangential = std::abs(cross(ta, tb)) < std::sin(deg_to_rad(2.0));
                    joined[2 * a + size_t(ea)] = tangential ? 2 : 1;
                    joined[2 * b + size_t(eb)] = tangential ? 2 : 1;
                }
            }
        }
    }
    for (size_t w = 0; w < nw; ++w) {
        WallGeom& g = geom_[w];
        if (g.shape == WallShape::Segment) {  // re-derive after snapping
            WallDef d = walls_[w];
            d.p0 = g.p0;
            d.p1 = g.p1;
            const bool c0 = g.cap0, c1 = g.cap1;
            g = make_geom(d);
            g.cap0 = c0;
            g.cap1 = c1;
        }
        auto resolve = [&](EndCap cap, int joint) {
            if (cap == EndCap::Capped) return true;
            if (cap == EndCap::Open) return false;
            return joint != 2;
        };
        g.cap0 = resolve(walls_[w].cap_start, joined[2 * w]);
        g.cap1 = resolve(walls_[w].cap_end, joined[2 * w + 1]);
    }
}

void World::finalize() {
    if (finalized_) return;
    validate(def_, "world");
    if (materials_.empty()) add_material(MaterialDef{});
    const size_t n = pos_.size();
    double r_min = 0.0;
    if (n > 0) r_min = *std::min_element(radius_.begin(), radius_.end());
    validate(def_.rotation, r_min, "rotation");

    join_wall_ends();
    const size_t nw = walls_.size(), nm = materials_.size();
    wall_active_.assign(nw, 1);
    wall_moving_.assign(nw, 0);
    wall_force_.assign(nw, Vec2::Zero());
    wall_impulse_.assign(nw, Vec2::Zero());
    wall_moment_.assign(nw, 0.0);
    for (size_t w = 0; w < nw; ++w)
        if (walls_[w].remove_at <= 0.0) wall_active_[w] = 0;

    mat_dd_.resize(nm * nm);
    for (size_t a = 0; a < nm; ++a)
        for (size_t b = 0; b < nm; ++b)
            mat_dd_[a * nm + b] = pair_material(series_stiffness(materials_[a].kn, materials_[b].kn),
                                                series_stiffness(materials_[a].ks, materials_[b].ks),
                                                combine_friction(def_.friction_rule_disc_disc, materials_[a].friction,
                                                                 materials_[b].friction));
    mat_dw_.resize(nm * nw);
    for (size_t a = 0; a < nm; ++a)
        for (size_t w = 0; w < nw; ++w)
            mat_dw_[a * nw + w] = pair_material(series_stiffness(materials_[a].kn, walls_[w].kn),
                                                series_stiffness(materials_[a].ks, walls_[w].ks),
                                                combine_friction(def_.friction_rule_disc_wall, materials_[a].friction,
                                                                 walls_[w].friction));

    rr_factor_.assign(n, 0.0);
    if (def_.rotation.model >= 2 && def_.rotation.u_rr > 0.0)
        for (size_t i = 0; i < n; ++i) rr_factor_[i] = preh_poisel_factor(radius_[i], def_.rotation.u_rr);
    load_.assign(n, DiscLoad{});
    discs_may_have_escaped_ = true;

    broad_.init(margin_target(), wall_piece_target(), pos_, radius_, geom_, wall_active_);
    refresh_contacts();
    finalized_ = true;

    // first time step: a force pass with dt = 0 (no shear increment, nothing dissipated)
    // counts the contacts the automatic rule needs
    if (def_.timestep.automatic) {
        dt_ = 0.0;
        compute_forces();
        dt_ = automatic_dt();
    } else {
        dt_ = def_.timestep.fixed;
    }
}

double World::margin_target() const {
    if (def_.broadphase_margin > 0.0) return def_.broadphase_margin;
    if (radius_.empty()) return 0.001;
    return 0.5 * *std::min_element(radius_.begin(), radius_.end());
}

// A wall piece's box holds every disc within a margin of the piece, and on a slope the box is
// as tall as the piece is long times the sine of the slope. Geometry A with 5 cm pieces (about
// 16 disc diameters) had 1,041 disc-wall candidates a step for 191 touching; with 1 cm pieces,
// 401. Every candidate costs the force pass a narrow-phase test and the caller's serial sum of
// wall forces a visit (0.19 against 0.10 s to t = 0.15 s). Three diameters keep the pieces
// few where the discs are large (a 100 m terrain profile under 5 cm discs: 333 pieces).
double World::wall_piece_target() const {
    if (def_.wall_piece_length > 0.0) return def_.wall_piece_length;
    if (radius_.empty()) return 0.05;
    return 6.0 * *std::max_element(radius_.begin(), radius_.end());
}

double World::contact_mass_disc(int i, int j) const { return effective_mass(mass_[size_t(i)], mass_[size_t(j)]); }

// Carries the shear history of pairs that stay candidates; new pairs start with F_s = 0 and
// get their dashpot coefficients (eq. 2.56-2.62) once.
void World::refresh_contacts() {
    const size_t nm = materials_.size(), nw = walls_.size();
    const auto& keys = broad_.disc_pairs();
    // The new list has one contact per key, in key order: contact m is key m's, so the
    // threads can each take a part of the keys and find where to read the old list by a
    // binary search (measured on DB-9k, 2 threads: the serial merge was 2.5 % of the wall time)
    dd_scratch_.resize(keys.size());
    clearance_scratch_.resize(keys.size());
    clearance_.resize(dd_.size(), 0.0f);
    auto merge = [&](size_t begin, size_t end, int) {
        if (begin == end) return;
        size_t o = size_t(std::lower_bound(dd_.begin(), dd_.end(), keys[begin],
                                           [](const DiscContact& c, uint64_t key) { return pair_key(c.i, c.j) < key; }) -
                          dd_.begin());
        for (size_t m = begin; m < end; ++m) {
            const uint64_t key = keys[m];
            const int32_t i = key_first(key), j = key_second(key);
            while (o < dd_.size() && pair_key(dd_[o].i, dd_[o].j) < key) ++o;
            if (o < dd_.size() && dd_[o].i == i && dd_[o].j == j) {
                dd_scratch_[m] = dd_[o];
                clearance_scratch_[m] = clearance_[o];  // still a bound: the approach goes on
                continue;
            }
            clearance_scratch_[m] = 0.0f;  // a new pair: look at it
            const PairMaterial& pm = mat_dd_[size_t(material_[size_t(i)]) * nm + size_t(material_[size_t(j)])];
            const double m_eff = contact_mass_disc(i, j);
            dd_scratch_[m] = {i, j, 0.0, dashpot_coefficient(def_.damping.beta_n, m_eff, pm.kn),
                              dashpot_coefficient(def_.damping.beta_s, m_eff, pm.ks), 0.0f, 0.0f};
        }
    };
    pool_->parallel_for(keys.size(), merge);
    dd_.swap(dd_scratch_);
    clearance_.swap(clearance_scratch_);

    const auto& wkeys = broad_.wall_pairs();
    dw_scratch_.clear();
    dw_scratch_.reserve(wkeys.size());
    size_t o = 0;
    for (uint64_t key : wkeys) {
        const int32_t i = key_first(key), w = key_second(key);
        while (o < dw_.size() && pair_key(dw_[o].disc, dw_[o].wall) < key) ++o;
        if (o < dw_.size() && dw_[o].disc == i && dw_[o].wall == w) {
            dw_scratch_.push_back(dw_[o]);
            continue;
        }
        const PairMaterial& pm = mat_dw_[size_t(material_[size_t(i)]) * nw + size_t(w)];
        const double m_eff = mass_[size_t(i)];  // eq. 2.60: the wall's mass is infinite
        dw_scratch_.push_back({i, w, 0.0, dashpot_coefficient(def_.damping.beta_n, m_eff, pm.kn),
                               dashpot_coefficient(def_.damping.beta_s, m_eff, pm.ks), 0.0f, 0.0f});
    }
    dw_.swap(dw_scratch_);

    split_force_pass();
}

// The force pass's ranges: one contiguous range of discs per thread, cut where the work
// (contacts owned, plus discs) is shared in the ranges' target shares (equal at first, then
// corrected from the measured times: balance_force_pass); the cross contacts and, per range,
// which of them it receives. Rebuilt with the candidate lists. How the work is cut changes no
// bit: every disc sums its terms in contact-list order in any case (compute_forces).
//
// Ranges pay off when discs near in space are near in index, so that few pairs cross (flume
// 2 %, DB-9k 1 % of the candidates on 2 threads). A world in random order (the release
// generator's, before its mass is ordered in space) has half its pairs crossing: the first
// range then waits for the second to compute them all before its first pair, and 2 threads
// took 131 s where 1 thread took 89 s for the release of geometry A (session 11). Above
// max_cross_share_ of the candidates crossing, the pass runs as one range on the calling
// thread: the same bits, at the 1-thread speed. The limit, 10 %, is where 2 ranges stopped
// beating one on DB-9k with part of its discs swapped at random (ns per particle-step,
// 1 / 2 threads: 0.7 % crossing 30 / 19-25, 5 % 31-48 / 28, 9 % 32-38 / 31-32, 16 % 36-38 /
// 39-44, 27 % 45 / 52, 42 % 34 / 65).
void World::split_force_pass() {
    const size_t n = pos_.size();
    const size_t wanted = pool_->shares(n) && one_range_left_ == 0 ? size_t(pool_->size()) : 1;
    if (range_share_.size() != wanted) range_share_.assign(wanted, 1.0 / double(wanted));
    cut_ranges(wanted);
    if (wanted > 1 && double(cross_.size()) > max_cross_share_ * double(dd_.size())) {
        ++one_range_cuts_;
        cut_ranges(1);
    }
    restart_balance_window();
}

void World::cut_ranges(size_t r) {
    const size_t n = pos_.size();
    force_ranges_ = int(r);
    ledger_blocks_.resize((n + kLedgerBlock - 1) / kLedgerBlock);
    // the ranges' first disc, disc-disc contact and wall contact (both lists are sorted by disc)
    disc_split_.assign(r + 1, n);
    contact_split_.assign(r + 1, dd_.size());
    wall_split_.assign(r + 1, dw_.size());
    disc_split_[0] = contact_split_[0] = wall_split_[0] = 0;
    if (r > 1) {
        // work of disc d: 1 + the contacts it owns
        const double total = double(n + dd_.size() + dw_.size());
        size_t k = 0, kw = 0, part = 1;
        double done = 0.0, target = total * range_share_[0];
        for (size_t d = 0; d < n && part < r; ++d) {
            const size_t k0 = k, kw0 = kw;
            while (k < dd_.size() && size_t(dd_[k].i) == d) ++k;
            while (kw < dw_.size() && size_t(dw_[kw].disc) == d) ++kw;
            done += double(1 + (k - k0) + (kw - kw0));
            // ranges hold whole ledger blocks, so the ledger's sums do not depend on the cut
            if (done >= target && (d + 1) % kLedgerBlock == 0) {
                disc_split_[part] = d + 1;
                contact_split_[part] = k;
                wall_split_[part] = kw;
                target += total * range_share_[part];
                ++part;
            }
        }
    }
    cross_.clear();
    cross_in_.clear();
    cross_start_.assign(r + 1, 0);
    cross_in_start_.assign(r + 1, 0);
    if (r > 1) {
        auto range_of = [&](int32_t d) {
            return size_t(std::upper_bound(disc_split_.begin(), disc_split_.end(), size_t(d)) - disc_split_.begin()) - 1;
        };
        for (size_t t = 0; t < r; ++t) {
            cross_start_[t] = cross_.size();
            for (size_t k = contact_split_[t]; k < contact_split_[t + 1]; ++k)
                if (size_t(dd_[k].j) >= disc_split_[t + 1]) {
                    cross_.push_back(int32_t(k));
                    ++cross_in_start_[range_of(dd_[k].j) + 1];
                }
        }
        cross_start_[r] = cross_.size();
        for (size_t t = 0; t < r; ++t) cross_in_start_[t + 1] += cross_in_start_[t];
        cross_in_.resize(cross_.size());
        std::vector<int32_t> fill(cross_in_start_.begin(), cross_in_start_.end() - 1);
        for (size_t m = 0; m < cross_.size(); ++m)
            cross_in_[size_t(fill[range_of(dd_[size_t(cross_[m])].j)]++)] = int32_t(m);
    }
    cross_out_.resize(cross_.size());
    cross_todo_.assign(cross_.size(), 0);
    cross_copies_stale_ = true;
    if (cross_done_size_ < r) {
        cross_done_ = std::make_unique<CrossDone[]>(r);  // a new array: no pass is marked done
        cross_done_size_ = r;
    }

    // the range pass' blocks (FuseBlock) and how far ahead each one's pairs reach
    fuse_blocks_.clear();
    fuse_start_.assign(r + 1, 0);
    cross_in_reach_.assign(r, 0);
    for (size_t t = 0; t < r; ++t) {
        const size_t d0 = disc_split_[t], d1 = disc_split_[t + 1];
        size_t reach = d0;
        for (int32_t e = cross_in_start_[t]; e < cross_in_start_[t + 1]; ++e)
            reach = std::max(reach, size_t(dd_[size_t(cross_[size_t(cross_in_[size_t(e)])])].j) + 1);
        cross_in_reach_[t] = std::min(reach, d1);
        fuse_start_[t] = fuse_blocks_.size();
        size_t k = contact_split_[t], kw = wall_split_[t];
        for (size_t b0 = d0; b0 < d1;) {
            const size_t b1 = std::min(b0 + kFuseBlock, d1);
            size_t far = b1;
            for (; k < contact_split_[t + 1] && size_t(dd_[k].i) < b1; ++k) far = std::max(far, size_t(dd_[k].j) + 1);
            while (kw < wall_split_[t + 1] && size_t(dw_[kw].disc) < b1) ++kw;
            fuse_blocks_.push_back({b1, k, kw, std::min(far, d1)});  // a cross pair's j is another range's
            b0 = b1;
        }
    }
    fuse_start_[r] = fuse_blocks_.size();
}

// The ranges' work model (one unit per disc and per owned contact) misses what a unit costs:
// a touching pair costs more than a candidate that does not touch, a wall contact more than
// either, and the two cores need not run at the same speed. So every kBalanceWindow steps the
// ranges' times are compared, and when they differ by more than kBalanceTolerance the shares
// move halfway towards the measured speeds (rebalance_shares) and the pass is cut again. The
// cut changes no bit. Measured on DB-9k, 2 threads: the shares settle near 0.48/0.52.
void World::balance_force_pass() {
    if (one_range_left_ > 0) {
        ++one_range_steps_;
        if (--one_range_left_ == 0) split_force_pass();  // try the pool again
        return;
    }
    const size_t r = range_clock_.size();
    if (r < 2 || ++balance_steps_ < kBalanceWindow) return;
    double busy = 0.0;
    for (const RangeClock& c : range_clock_) busy += c.seconds;
    if (busy_fallback_ && busy_watch_.window(busy, window_pass_seconds_, r)) {
        ++busy_fallbacks_;
        run_as_one_range_for(kOneRangeSteps);
        return;
    }
    const auto seconds = [this](size_t t) { return range_clock_[t].seconds; };
    if (rebalance_shares(range_share_.data(), seconds, r, kBalanceTolerance)) {
        ++rebalances_;
        split_force_pass();  // also restarts the window
    } else {
        restart_balance_window();
    }
}

void World::restart_balance_window() {
    range_clock_.assign(size_t(force_ranges_), RangeClock{});
    balance_steps_ = 0;
    window_pass_seconds_ = 0.0;
}

double World::force_pass_busy_share() const {
    // a shared pass has one range per thread of the pool
    return shared_pass_seconds_ > 0.0 ? shared_pass_busy_seconds_ / (shared_pass_seconds_ * double(pool_->size())) : 1.0;
}

void World::run_as_one_range_for(long steps) {
    if (steps < 0) throw InputError("force pass: one range for " + std::to_string(steps) + " steps: must be >= 0");
    if (!finalized_) finalize();
    one_range_left_ = steps;
    split_force_pass();
}

void World::cut_force_pass(const std::vector<double>& shares) {
    if (!finalized_) finalize();
    const size_t r = size_t(pool_->shares(pos_.size()) ? pool_->size() : 1);
    double sum = 0.0;
    bool each_valid = true;
    for (double x : shares) {
        each_valid = each_valid && std::isfinite(x) && x >= 0.0;
        sum += x;
    }
    if (shares.size() != r || !each_valid || !(std::abs(sum - 1.0) < 1e-9))
        throw InputError("force-pass shares: " + std::to_string(r) +
                         " finite shares >= 0 summing to 1 expected (one per range)");
    range_share_ = shares;
    split_force_pass();
}

void World::set_cross_share_limit(double share) {
    if (!(share >= 0.0 && share <= 1.0))
        throw InputError("force-pass cross share limit: " + format_number(share) + " is not in [0, 1]");
    max_cross_share_ = share;
    if (finalized_) split_force_pass();
}

// the float nearest a double on the safe side: no greater / no smaller than it
static float round_down_float(double v) {
    const float f = float(v);
    return double(f) > v ? std::nextafter(f, -INFINITY) : f;
}
static float round_up_float(double v) {
    const float f = float(v);
    return double(f) < v ? std::nextafter(f, INFINITY) : f;
}

static std::string where_disc(long step, double t, int i, const Vec2& p) {
    std::ostringstream s;
    s << "step " << step << ", t = " << t << " s, disc " << i << " at (" << p.x() << ", " << p.y() << ")";
    return s.str();
}

// Software prefetch in the force pass (WorldDef::prefetch). Once the step's arrays outgrow
// the last-level cache, every step brings them from memory, and the hardware prefetchers did
// not keep up with the pass' 20-odd streams: DB-9k's columns side by side (`bench db9k
// --copies`) took 27 ns per particle-step on 1 thread for 9,140 discs and 52-61 ns for
// 146,240 (perf: the pass stalled on its first load of each batch's contact records), with
// the memory 150-165 ns away (a dependent-load chain over 64 MB; the EPYC of sessions 5-19).
// The pass now asks for the lines it will need kPrefetchContacts contacts and kPrefetchDiscs
// discs ahead (every disc a pair or the integration reads lies at or after the batch's first
// disc i, and its partners j within a few hundred places in space order), into L2 (the T1
// hint): 37-44 ns for 146,240 discs, 20-24 ns on 2 threads (26-36 before; docs/performance.md,
// session 17).
// Into L1 (T0) it bought nothing: the core's few L1 miss buffers filled and the prefetches
// stalled the loop. With the arrays in the cache it costs 1-2 ns per particle-step, so Auto
// turns it on once the step streams more than half the last-level cache
// (prefetch_threshold_bytes): on that EPYC (32 MB) 36,560 discs (11 MB) ran 3-8 % slower
// with it, 54,840 (17 MB) about as fast, 73,120 (22 MB) 8-33 % faster. No prefetch changes a
// result.
constexpr size_t kPrefetchContacts = 256, kPrefetchDiscs = 256;

// Half of CPU 0's largest cache as Linux lists it (/sys/devices/system/cpu/cpu0/cache,
// machine.h), or 16 MB when it lists none. (On the AMD EPYC of sessions 5-19 Linux listed
// 32 MB, where glibc's sysconf(_SC_LEVEL3_CACHE_SIZE) said 320 MB; on the Intel Xeon of
// sessions 20-21 it lists 300 MB, shared with the host's other guests, and the step of
// 146,240 discs, 44.5 MB, ran no faster with prefetch: docs/performance.md, session 21.)
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

// The force pass. Every disc sums its terms from zero in contact-list order: its disc-disc
// contacts (sorted by (i, j)), then its wall contacts. Each thread owns a range of discs and
// the contacts whose first disc lies in it (split_force_pass), so it adds most pairs straight
// into both discs' sums. A cross contact (j in a later range) is computed before the ranges
// start, into a slot: the range owning j adds it first, which is its place in j's order
// (every cross contact of j has i in an earlier range, so it precedes j's own contacts in
// the list); the range owning i adds it when its loop reaches it. So the bits are the same
// for any number of threads. With the discs numbered in space order (order_in_space), under
// 2 % of the pairs cross, and the threads share no cache lines but those few slots; the
// earlier design (every pair to a slot, then a per-disc gather) moved 64 bytes per pair
// between the cores and gained 1.1-1.4x on 2 threads (docs/performance.md).
void World::compute_forces(bool then_integrate) {
    const size_t nw = walls_.size();
    const DashpotMode mode = def_.damping.dp_mode;
    const double dt = dt_;
    const double last_dt = last_dt_;
    const double max_ratio = def_.max_overlap_ratio;
    const DiscArrays discs{pos_.data(), vel_.data(), radius_.data(), omega_.data(), material_.data()};
    const PairPassParams pp{mat_dd_.data(), materials_.size(), mode, dt, last_dt, max_ratio};
    wall_sums_.resize(size_t(force_ranges_));
    for (size_t t = 0; t < wall_sums_.size(); ++t) wall_sums_[t].resize(wall_split_[t + 1] - wall_split_[t]);
    // one fault record per chunk, kept between steps (no allocation in the step)
    dd_fault_.resize(size_t(pool_->size()));
    dw_fault_.resize(size_t(pool_->size()));
    for (Fault& f : dd_fault_) f.index = SIZE_MAX;
    for (Fault& f : dw_fault_) f.index = SIZE_MAX;
    auto disc_fault = [&](size_t k, double overlap, int chunk) {
        if (k >= dd_fault_[size_t(chunk)].index) return;
        const size_t i = size_t(dd_[k].i), j = size_t(dd_[k].j);
        dd_fault_[size_t(chunk)] = Fault{k, "blow-up: overlap " + format_number(overlap) + " m between discs " +
                                                std::to_string(i) + " and " + std::to_string(j) + " exceeds " +
                                                format_number(max_ratio) + " of the smaller radius at " +
                                                where_disc(steps_, time_, int(i), pos_[i]) +
                                                ". Likely cause: the time step is too large for the stiffness and "
                                                "speeds (use the automatic time step or a smaller safety factor)"};
    };

    const IntegrateConsts ic = then_integrate ? integrate_prepare() : IntegrateConsts{};
    const bool prefetch = prefetching();

    // The cross contacts (split_force_pass) are computed into their slots by the range that
    // owns their second disc, first thing, and it then raises its flag for this pass. The
    // range that owns their first disc waits for the flags of all later ranges before its
    // first cross contact: it reads the slots there, and from there on it integrates the
    // discs those pairs read (its cross contacts are its last, in list order, and a pair's
    // first disc comes no earlier). Before, the calling thread computed them all while the
    // others waited: 4 % of a 2-thread flume run.
    //
    // The computing range works on copies of the cross contacts' records and clearances
    // (cross_dd_, cross_clearance_), with the pass' own selection: a pair that is clear
    // skips the law and never reads its discs. It used to run the law on every cross
    // contact in place in dd_, among the owning range's contacts: every history it wrote
    // took a line of dd_ from the other core's cache and handed it back when that range
    // came to it. Timers, 2 threads: DB-9k's 223 cross contacts a step took 22-44 ns each
    // (14-31 ns with the copies); geometry A's late deposit, 456 a step, 29-92 ns each as
    // the machine wandered (26-47 ns), up to a fifth of the computing range's time. The
    // owning range copies a history back when it adds the contact, so dd_ is whole after
    // every pass (energy(), checkpoints and the lists' merge read it).
    const uint64_t pass = ++cross_pass_;
    const size_t ranges = size_t(force_ranges_);
    // Returns the seconds it waited: not the range's work, so left out of its measured time
    // (the balancing would otherwise move work away from the range that waits). It yields
    // after a short spin, as the pool does: with more threads than free cores the range it
    // waits for may need this core.
    auto wait_for_cross = [&](size_t t) {
        double waited = 0.0;
        for (size_t u = t + 1; u < ranges; ++u) {
            if (cross_done_[u].pass.load(std::memory_order_acquire) == pass) continue;
            const auto w0 = std::chrono::steady_clock::now();
            for (unsigned polls = 1; cross_done_[u].pass.load(std::memory_order_acquire) != pass; ++polls) {
                if (polls < 2048)
                    DEMLAB_CPU_RELAX();
                else
                    std::this_thread::yield();
            }
            waited += std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count();
        }
        return waited;
    };

    // 2. each range sums its discs' terms
    DiscLoad* const load = load_.data();
    // the clearance test's bound as floats, rounded outwards (PairSkip)
    if (clearances_stale_) {
        std::fill(clearance_.begin(), clearance_.end(), 0.0f);
        approach_ = 0.0;
        clearances_stale_ = false;
    }
    if (cross_copies_stale_) {
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
    float* const clearance = clearance_.data();
    const float approach_lo = round_down_float(approach_), approach_hi = round_up_float(approach_);
    auto add_to_i = [load](size_t i, const PairOut& o) {
        DiscLoad& l = load[i];
        l.dissipated += 0.5 * o.dissipated;  // the ledger: half to each disc (exact)
        if (!o.touching) return;
        l.force -= o.f;
        l.torque += o.torque_i;
        l.k_tran += o.k_tran;
        l.k_rot += o.k_rot;
        ++l.n_disc;
    };
    auto add_to_j = [load](size_t j, const PairOut& o) {
        DiscLoad& l = load[j];
        l.dissipated += 0.5 * o.dissipated;
        if (!o.touching) return;
        l.force += o.f;
        l.torque += o.torque_j;
        l.k_tran += o.k_tran;
        l.k_rot += o.k_rot;
        ++l.n_disc;
    };
    auto range_pass = [&](int t) {
        const auto started = std::chrono::steady_clock::now();
        const size_t d0 = disc_split_[size_t(t)];
        double waited = 0.0;  // s, for the cross contacts of later ranges (wait_for_cross)
        // The loads are zeroed just ahead of the first pair that adds to them (the blocks'
        // reach, split_force_pass), not all at the range's start: by the time the pairs of a
        // range's last discs came, their zeroed lines had left the cache.
        size_t zeroed = d0;
        auto zero_to = [&](size_t e) {
            if (e <= zeroed) return;
            std::fill(load + zeroed, load + e, DiscLoad{});
            zeroed = e;
        };
        // cross contacts into this range's discs: computed here, then added first, in their order
        if (ranges > 1) {
            PairBatch* const batch = avx2_ ? &pair_batch_[size_t(t)] : nullptr;
            const size_t e0 = size_t(cross_in_start_[size_t(t)]), e1 = size_t(cross_in_start_[size_t(t) + 1]);
            // The pass' own selection and law over their copies (cross_dd_, cross_clearance_):
            // a pair with nothing to do gets no results (it would add +0 and keep its zero
            // history); the rest of a batch (fewer than four, or from a blown-up pair on) goes
            // to the scalar kernel, which reports a blow-up
            PairSkip skip{nullptr, approach_lo, approach_hi};
            for (size_t e = e0; e < e1;) {
                const size_t n = std::min(PairBatch::kSize, e1 - e);
                for (size_t p = e; p < e + n; ++p) cross_todo_[size_t(cross_in_[p])] = 0;
                size_t done = 0;
                if (batch) {
                    skip.clearance = cross_clearance_.data() + e;
                    done = avx512_ ? disc_pairs_avx512(discs, pp, cross_dd_.data() + e, n, *batch, &skip)
                                   : disc_pairs_avx2(discs, pp, cross_dd_.data() + e, n, *batch, &skip);
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
                    if (!disc_pair_force(discs, pp, cross_dd_[p], cross_out_[m], overlap)) disc_fault(size_t(cross_[m]), overlap, t);
                    cross_todo_[m] = 1;
                }
                e += n;
            }
            cross_done_[size_t(t)].pass.store(pass, std::memory_order_release);
        }
        zero_to(cross_in_reach_[size_t(t)]);
        for (int32_t e = cross_in_start_[size_t(t)]; e < cross_in_start_[size_t(t) + 1]; ++e) {
            const size_t m = size_t(cross_in_[size_t(e)]);
            if (cross_todo_[m]) add_to_j(size_t(cross_dd_[size_t(e)].j), cross_out_[m]);
        }
        // this range's own cross contacts, in list order
        size_t next = cross_start_[size_t(t)];
        size_t next_k = next < cross_.size() ? size_t(cross_[next]) : SIZE_MAX;
        PairBatch* const batch = avx2_ ? &pair_batch_[size_t(t)] : nullptr;
        PairSkip skip_base{nullptr, approach_lo, approach_hi};
        range_clock_[size_t(t)].touching_dd = 0;
        WallSum* const wall_sums = wall_sums_[size_t(t)].data();
        size_t n_wall_sums = 0;
        size_t k = contact_split_[size_t(t)], kw = wall_split_[size_t(t)], b0 = d0;
        // software prefetch (kPrefetchContacts): the contacts and discs asked for so far
        const size_t contact_end = contact_split_[size_t(t) + 1], disc_end = disc_split_[size_t(t) + 1];
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
        // Block by block (FuseBlock): the pairs whose first disc is in the block, then the
        // block's wall contacts; then the block's sums are complete (a disc's pairs with
        // earlier discs came in earlier blocks, its cross terms first) and no later pair reads
        // its discs (a pair's second disc comes after its first), so the block is integrated
        // while its loads and state are still in the cache. Every disc adds its terms in the
        // order it did when the range was one block: the same bits.
        for (size_t fbi = fuse_start_[size_t(t)]; fbi < fuse_start_[size_t(t) + 1]; ++fbi) {
            const FuseBlock& fb = fuse_blocks_[fbi];
            zero_to(fb.reach);
            for (; k < fb.contact_end; ++k) {
                DiscContact& c = dd_[k];
                if (k == next_k) {  // computed by the range that owns c.j
                    if (next == cross_start_[size_t(t)]) waited += wait_for_cross(size_t(t));
                    if (cross_todo_[next]) {
                        add_to_i(size_t(c.i), cross_out_[next]);
                        const DiscContact& h = cross_dd_[size_t(cross_pos_[next])];
                        c.fs = h.fs;
                        c.damp_n = h.damp_n;
                        c.damp_s = h.damp_s;
                    }
                    ++next;
                    next_k = next < cross_.size() ? size_t(cross_[next]) : SIZE_MAX;
                    continue;
                }
                if (batch) {
                    // up to a batch of pairs before the next cross contact, four at a time, then
                    // added in list order (what the scalar kernel below does pair by pair)
                    const size_t n = std::min({fb.contact_end, next_k, k + PairBatch::kSize}) - k;
                    if (prefetch) prefetch_ahead(k);
                    skip_base.clearance = clearance + k;
                    const size_t done = avx512_ ? disc_pairs_avx512(discs, pp, &c, n, *batch, &skip_base)
                                                : disc_pairs_avx2(discs, pp, &c, n, *batch, &skip_base);
                    add_pair_batch_avx2(*batch, &c, load);
                    if (done > 0) {
                        k += done - 1;
                        continue;
                    }
                }
                PairOut o;
                double overlap = 0.0;
                if (!disc_pair_force(discs, pp, c, o, overlap)) {
                    disc_fault(k, overlap, t);
                    continue;
                }
                add_to_i(size_t(c.i), o);
                add_to_j(size_t(c.j), o);
            }

            // disc-wall: n from the wall (A) to the disc (B)
            for (; kw < fb.wall_end; ++kw) {
                WallContact& c = dw_[kw];
                const size_t i = size_t(c.disc), w = size_t(c.wall);
                WallHit hit;
                if (!wall_active_[w] || !disc_wall_contact(geom_[w], pos_[i], radius_[i], hit)) {
                    if (c.damp_n != 0.0f || c.damp_s != 0.0f) {
                        // the last dashpot force's second half, along the normal it had
                        const Vec2 vrel = vel_[i] - (wall_moving_[w] ? walls_[w].velocity : Vec2::Zero());
                        const Vec2 q = closest_point(geom_[w], pos_[i]);
                        const Vec2 nrm = (pos_[i] - q).normalized();
                        const double vs = vrel.dot(perp(nrm)) - omega_[i] * radius_[i];
                        const double dissipated = -0.5 * last_dt * (c.damp_n * vrel.dot(nrm) + c.damp_s * vs);
                        if (dissipated != 0.0) wall_sums[n_wall_sums++] = WallSum{0.0, 0.0, 0.0, dissipated, -1};
                    }
                    c.fs = 0.0;
                    c.damp_n = c.damp_s = 0.0f;
                    continue;
                }
                if (!(hit.overlap <= max_ratio * radius_[i])) {
                    if (kw < dw_fault_[size_t(t)].index)
                        dw_fault_[size_t(t)] = Fault{kw, "blow-up: overlap " + format_number(hit.overlap) + " m of disc " +
                                                            std::to_string(i) + " with wall '" + walls_[w].name + "' exceeds " +
                                                            format_number(max_ratio) + " of its radius at " +
                                                            where_disc(steps_, time_, int(i), pos_[i]) +
                                                            ". Likely cause: a time step too large for the stiffness, or a "
                                                            "disc crossing the wall"};
                    continue;
                }
                const Vec2 nrm = hit.normal;
                const Vec2 tan = perp(nrm);
                const double rb = radius_[i] - 0.5 * hit.overlap;
                const Vec2 vwall = wall_moving_[w] ? walls_[w].velocity : Vec2::Zero();
                const Vec2 vrel = vel_[i] - vwall;
                const double vn = vrel.dot(nrm);
                const double vs = vrel.dot(tan) - omega_[i] * rb;
                const PairMaterial& pm = mat_dw_[size_t(material_[i]) * nw + w];
                double dissipated = 0.0;
                const LinearContactForce f =
                    step_contact({pm.kn, pm.ks, pm.mu, c.cn, c.cs, mode, pm.inv_ks}, hit.overlap, vn, vs, dt, last_dt, c, dissipated);
                const Vec2 force = f.fn * nrm + f.ft * tan;
                const Vec2 point = pos_[i] - rb * nrm;
                wall_sums[n_wall_sums++] = WallSum{force.x(), force.y(), cross(point, force), dissipated, int32_t(w)};
                DiscLoad& l = load[i];
                l.force += force;
                l.torque += -rb * f.ft;
                l.k_tran += pm.k_tran;
                l.k_rot += pm.ks;
                l.wall_normal += f.fn_spring;
                ++l.n_wall;
            }

            // The block's sums are complete. A range that met a fault integrates no more
            // blocks, but goes on with its pairs (the pass then throws the first fault in list
            // order, whatever the blocks and ranges).
            const size_t b1 = fb.disc_end;
            const bool integrate =
                then_integrate && dd_fault_[size_t(t)].index == SIZE_MAX && dw_fault_[size_t(t)].index == SIZE_MAX;
            // the ledger's share of the block: the contacts' dissipation per ledger block of
            // discs (in disc order, as a serial pass would add them) and the touching pairs;
            // the AVX2 integration adds them up as it goes
            if (!(integrate && avx2_integration())) {
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
                range_clock_[size_t(t)].touching_dd += touching;
            }
            if (integrate) integrate_discs(b0, b1, t, ic);
            b0 = b1;
        }
        range_clock_[size_t(t)].wall_sums = n_wall_sums;
        const double busy = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count() - waited;
        range_clock_[size_t(t)].seconds += busy;
        range_clock_[size_t(t)].last = busy;
    };
    if (force_ranges_ == 1) {
        range_pass(0);
    } else {
        const auto pass_started = std::chrono::steady_clock::now();
        pool_->for_each_thread(range_pass);
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

    // the ledger: disc-disc contacts through the discs' halves, summed per block of discs in
    // the ranges and here over the blocks in order (the same bits for any cut and thread
    // count; a serial pass over all discs here made the caller read every line the other
    // threads had written, and cost 2 threads a fifth of their speed); then the wall loads,
    // in contact-list order
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
    // at +0, and x + 0 = x for every x but -0, which a sum from +0 never reaches. Before, every
    // range wrote a 48-byte record per wall contact and this loop read them all, with the
    // contact itself for its wall: on slow stretches the worker then spent 5 times the main
    // thread's time on its wall contacts, its stores waiting for the lines this loop had read
    // (docs/performance.md, sessions 19 and 20).
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

World::DtFactors World::dt_factors() const {
    const bool corr = def_.timestep.damping_correction;
    const double local = corr ? local_damping_factor(def_.damping.local_alpha) : 1.0;
    const double phi = local * (corr ? rotational_damping_factor(def_.damping.beta_s) : 1.0);
    const double phi_t = local * (corr ? translational_damping_factor(def_.damping.beta_n) : 1.0);
    return {def_.rotation.model != 1, phi * phi, phi_t * phi_t};
}

// One disc's squared critical step from its loads (the PFC rule, timestep.h): a disc
// without contacts uses its own stiffnesses. Inlined by force: out of line it was a call per
// disc and step, 7 % of geometry A's time (perf); inlined, its two divisions overlap the
// integration's other work.
[[gnu::always_inline]] inline double World::critical_step_squared_at(const DiscLoad& l, const MaterialDef& m, double mass,
                                                                     double inertia, double radius, const DtFactors& f) {
    const double kt = l.k_tran > 0.0 ? l.k_tran : std::max(m.kn, m.ks);
    const double kr = l.k_rot > 0.0 ? l.k_rot : m.ks;
    return critical_step_squared(mass, inertia, radius, kt, kr, f.rotation_free, f.phi_sq, f.phi_t_sq);
}

double World::critical_step_squared_of(size_t i, const DtFactors& f) const {
    return critical_step_squared_at(load_[i], materials_[size_t(material_[i])], mass_[i], inertia_[i], radius_[i], f);
}

double World::step_from_critical_squared(double best_sq) const {
    if (!std::isfinite(best_sq)) return def_.timestep.fixed;  // no discs
    return def_.timestep.safety * std::sqrt(best_sq);
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
    default_k_tran_.resize(materials_.size());
    default_k_rot_.resize(materials_.size());
    for (size_t m = 0; m < materials_.size(); ++m) {
        default_k_tran_[m] = std::max(materials_[m].kn, materials_[m].ks);
        default_k_rot_[m] = materials_[m].ks;
    }
    return {dt_, def_.gravity, def_.damping.local_alpha, def_.gravity.norm(), def_.timestep.automatic, dt_factors()};
}

bool World::avx2_integration() const {
    return avx2_ && !(def_.rotation.model == 3 && def_.rotation.damping_per != RotDampingPer::Disc);
}

void World::integrate_discs(size_t begin, size_t end, int chunk, const IntegrateConsts& k) {
    // four (AVX2) or eight (AVX-512) discs at a time where those loops have every rule the run
    // uses (per-disc rotational damping; local damping or none), the same bits
    if (avx2_integration()) {
        const IntegrateArrays arrays{pos_.data(),      vel_.data(),          omega_.data(),       angle_.data(),
                                     mass_.data(),     inv_mass_.data(),     inertia_.data(),     inv_inertia_.data(),
                                     radius_.data(),   rr_factor_.data(),    material_.data(),    load_.data(),
                                     broad_.fat_lo_data(), broad_.fat_hi_data(), default_k_tran_.data(),
                                     default_k_rot_.data(), materials_.size()};
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
    const MaterialDef* const materials = materials_.data();
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
            best_sq = std::min(best_sq, critical_step_squared_at(load[i], materials[size_t(material[i])], mass[i],
                                                                 inertia[i], radius[i], dtf));
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
        const bool inside = (p.x() >= lo.x()) & (p.x() <= hi.x()) & (p.y() >= lo.y()) & (p.y() <= hi.y());
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
    for (const ChunkNote& note : chunk_note_) {
        const size_t i = note.fault;
        if (i == SIZE_MAX) continue;
        const Vec2& p = pos_[i];
        if (!std::isfinite(p.x() + p.y() + vel_[i].x() + vel_[i].y()))
            throw RunError("blow-up: non-finite state of disc " + std::to_string(i) + " at step " +
                           std::to_string(steps_) + ", t = " + format_number(time_) +
                           " s. Likely cause: a time step too large for the stiffness");
        throw RunError("lost disc: " + where_disc(steps_, time_, int(i), p) +
                       " left the domain. Likely cause: a disc crossed a wall (time step too large, or a gap "
                       "between walls)");
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
    double speed = 0.0, extent = 0.0;
    for (const ChunkNote& note : chunk_note_) {
        speed = std::max(speed, note.speed);
        extent = std::max(extent, note.extent);
    }
    const double moved = speed * dt_ * (1.0 + 0x1p-40) + 0x1p-50 * extent;
    approach_ += 2.0 * moved;
    // Rebase now and then: clearances are floats, and the slack of PairSkip is a fraction
    // 2^-20 of the approach, so keep it a small length (1024 margins, 0.4 m in DB-9k: every
    // few thousand steps of a fast flow). Not finite: look at every pair again.
    if (!(approach_ <= 1024.0 * broad_.margin())) forget_clearances();
}

void World::forget_clearances() {
    // at the next force pass: an edit by hand may come once per disc (the release's growth)
    clearances_stale_ = true;
    cross_copies_stale_ = true;  // (and the histories may have been edited: World::load_state)
}

void World::move_walls() {
    for (size_t w = 0; w < walls_.size(); ++w) {
        if (!wall_active_[w] || !wall_moving_[w]) continue;
        const Vec2 d = walls_[w].velocity * dt_;
        translate(geom_[w], d);
        // power the wall puts into the discs: -(force on wall) . v_wall
        work_walls_ += -wall_force_[w].dot(walls_[w].velocity) * dt_;
    }
}

void World::step() {
    if (!finalized_) finalize();
    // wall schedule at time t: removal and which walls move during this step
    bool wall_removed = false;
    for (size_t w = 0; w < walls_.size(); ++w) {
        if (wall_active_[w] && time_ >= walls_[w].remove_at) {
            wall_active_[w] = 0;
            wall_removed = true;
        }
        const bool moving = walls_[w].velocity.squaredNorm() > 0.0 && time_ >= walls_[w].move_from &&
                            time_ < walls_[w].move_until;
        wall_moving_[w] = moving ? 1 : 0;
    }
    if (wall_removed) {
        // the elastic energy stored in contacts with a removed wall leaves the ledger
        const size_t nw = walls_.size();
        for (const WallContact& c : dw_) {
            const size_t w = size_t(c.wall);
            if (wall_active_[w]) continue;
            WallHit hit;
            if (disc_wall_contact(geom_[w], pos_[size_t(c.disc)], radius_[size_t(c.disc)], hit)) {
                const PairMaterial& pm = mat_dw_[size_t(material_[size_t(c.disc)]) * nw + w];
                removed_walls_ += 0.5 * pm.kn * hit.overlap * hit.overlap + 0.5 * c.fs * c.fs / pm.ks;
            }
        }
    }
    // every kPadCheckSteps steps the broad phase also looks for pads wider than the discs'
    // speeds ask for (a scan of the discs: a tenth of a step's time, once in 128 steps)
    const bool check_pads = steps_ % kPadCheckSteps == 0;
    const auto t_list = std::chrono::steady_clock::now();
    if (broad_.update(pos_, radius_, geom_, wall_active_, wall_moving_, discs_may_have_escaped_, &vel_, dt_, check_pads)) {
        refresh_contacts();
        list_seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - t_list).count();
    }
    compute_forces(true);
    integrate_finish();
    balance_force_pass();
    move_walls();
    for (size_t w = 0; w < walls_.size(); ++w) wall_impulse_[w] += wall_force_[w] * dt_;
    time_ += dt_;
    last_dt_ = dt_;
    ++steps_;
    if (def_.timestep.automatic) {
        double best_sq = INFINITY;
        for (const ChunkNote& note : chunk_note_) best_sq = std::min(best_sq, note.dt_sq);
        dt_ = step_from_critical_squared(best_sq);
    }
}

void World::run(long steps) {
    for (long s = 0; s < steps; ++s) step();
}

// The sums run over fixed blocks (kEnergyBlock discs or contacts), each added up in order,
// then the blocks in order, with the blocks shared out among the pool's threads: the same
// bits for any thread count. The run's blow-up watch calls this every 100 steps, and on the
// calling thread alone it was 1.4 % of a 2-thread flume run with the other thread waiting.
EnergyReport World::energy() const {
    const size_t nd = pos_.size(), nc = dd_.size();
    const size_t disc_blocks = (nd + kEnergyBlock - 1) / kEnergyBlock;
    const size_t blocks = disc_blocks + (nc + kEnergyBlock - 1) / kEnergyBlock;
    energy_blocks_.assign(blocks, EnergyBlock{});
    const Vec2 g = def_.gravity;
    const size_t nm = materials_.size(), nw = walls_.size();
    auto block = [&](size_t b) {
        EnergyBlock& s = energy_blocks_[b];
        if (b < disc_blocks) {
            for (size_t i = b * kEnergyBlock, end = std::min(nd, (b + 1) * kEnergyBlock); i < end; ++i) {
                s.kinetic_translation += 0.5 * mass_[i] * vel_[i].squaredNorm();
                s.kinetic_rotation += 0.5 * inertia_[i] * omega_[i] * omega_[i];
                // at t - dt/2: the mean of x(t) and x(t - dt) = x(t) - v(t - dt/2) dt
                s.potential -= mass_[i] * g.dot(pos_[i] - 0.5 * last_dt_ * vel_[i]);
            }
            return;
        }
        const size_t c0 = (b - disc_blocks) * kEnergyBlock;
        for (size_t k = c0, end = std::min(nc, c0 + kEnergyBlock); k < end; ++k) {
            const DiscContact& c = dd_[k];
            const size_t i = size_t(c.i), j = size_t(c.j);
            const double overlap = radius_[i] + radius_[j] - (pos_[j] - pos_[i]).norm();
            if (overlap <= 0.0) continue;
            const PairMaterial& pm = mat_dd_[size_t(material_[i]) * nm + size_t(material_[j])];
            s.elastic += 0.5 * pm.kn * overlap * overlap + 0.5 * c.fs * c.fs / pm.ks;
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
        WallHit hit;
        if (!wall_active_[w] || !disc_wall_contact(geom_[w], pos_[i], radius_[i], hit)) continue;
        const PairMaterial& pm = mat_dw_[size_t(material_[i]) * nw + w];
        e.elastic += 0.5 * pm.kn * hit.overlap * hit.overlap + 0.5 * c.fs * c.fs / pm.ks;
    }
    e.dissipated_contacts = diss_contacts_;
    e.dissipated_local = diss_local_;
    e.dissipated_rotation = diss_rotation_;
    e.work_by_walls = work_walls_;
    e.removed_with_walls = removed_walls_;
    return e;
}

}  // namespace demlab
