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
#include "dem/world_messages.h"

namespace demlab {

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
    if (d.space_order_steps < 1)
        throw InputError(where + ".space_order_steps = " + std::to_string(d.space_order_steps) + ": must be at least 1");
    with_contact_law(d.law, [&](auto law) {
        using Law = decltype(law);
        Law::validate(d.template law_def<Law>(), d);
    });
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
    r_min_stale_ = true;
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
    id_.push_back(int32_t(pos_.size() - 1));
    require_finite(where + ".force", d.force, "N/m");
    external_force_.push_back(d.force);
    any_external_force_ = any_external_force_ || d.force.squaredNorm() > 0.0;
    return int(pos_.size()) - 1;
}

int World::add_wall(const WallDef& w) {
    const std::string where = w.name.empty() ? "wall[" + std::to_string(walls_.size()) + "]" : "wall '" + w.name + "'";
    validate(w, where);
    if (w.material < 0 || size_t(w.material) >= materials_.size())
        throw InputError(where + ".material = " + std::to_string(w.material) + ": no such material (" +
                         std::to_string(materials_.size()) + " defined; a wall refers to one added by add_material)");
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
    r_min_stale_ = true;
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
    with_contact_law(def_.law, [&](auto law) { refresh_dashpots_with<decltype(law)>(); });
}

template <typename Law>
void World::refresh_dashpots_with() {
    const size_t nm = disc_materials_, nw = walls_.size();
    cross_copies_stale_ = true;
    const double beta_n = def_.damping.beta_n, beta_s = def_.damping.beta_s;
    for (DiscContact& c : dd_) {
        const auto& pm = tables<Law>().disc_disc[size_t(material_[size_t(c.i)]) * nm + size_t(material_[size_t(c.j)])];
        Law::refresh_dashpots(c, pm, contact_mass_disc(c.i, c.j), beta_n, beta_s);
    }
    for (WallContact& c : dw_) {
        const auto& pm = tables<Law>().disc_wall[size_t(material_[size_t(c.disc)]) * nw + size_t(c.wall)];
        Law::refresh_dashpots(c, pm, mass_[size_t(c.disc)], beta_n, beta_s);
    }
}

void World::scale_stiffness(double factor) {
    require_positive("stiffness factor", factor, "(ratio)");
    for (MaterialDef& m : materials_) {
        m.kn *= factor;
        m.ks *= factor;
    }
    with_contact_law(def_.law, [&](auto law) {
        build_law_tables<decltype(law)>();
        refresh_dashpots_with<decltype(law)>();
    });
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

// The chosen law's parameters per pair of materials and per material and wall (with what the
// law takes from its own keys), and the stiffness a disc without contacts takes for its step.
template <typename Law>
void World::build_law_tables() {
    const size_t nw = walls_.size(), nm = disc_materials_;
    LawTables<Law>& t = tables<Law>();
    t.disc_disc.resize(nm * nm);
    for (size_t a = 0; a < nm; ++a)
        for (size_t b = 0; b < nm; ++b)
            t.disc_disc[a * nm + b] = Law::pair_params(materials_[a], materials_[b], def_.friction_rule_disc_disc);
    t.disc_wall.resize(nm * nw);
    for (size_t a = 0; a < nm; ++a)
        for (size_t w = 0; w < nw; ++w)
            t.disc_wall[a * nw + w] =
                Law::wall_params(materials_[a], materials_[size_t(walls_[w].material)], def_.friction_rule_disc_wall);
    default_k_tran_.resize(nm);
    default_k_rot_.resize(nm);
    for (size_t m = 0; m < nm; ++m) {
        default_k_tran_[m] = Law::default_k_tran(materials_[m].kn, materials_[m].ks);
        default_k_rot_[m] = Law::default_k_rot(materials_[m].kn, materials_[m].ks);
    }
    Law::fill_tables(t, def_.law_def<Law>());
}

void World::finalize() {
    if (finalized_) return;
    validate(def_, "world");
    if (materials_.empty()) add_material(MaterialDef{});
    disc_materials_ = 1;
    for (const int32_t m : material_) disc_materials_ = std::max(disc_materials_, size_t(m) + 1);
    const size_t n = pos_.size();
    double r_min = 0.0;
    if (n > 0) r_min = *std::min_element(radius_.begin(), radius_.end());
    validate(def_.rotation, r_min, "rotation");

    join_wall_ends();
    const size_t nw = walls_.size();
    wall_active_.assign(nw, 1);
    wall_moving_.assign(nw, 0);
    wall_force_.assign(nw, Vec2::Zero());
    wall_impulse_.assign(nw, Vec2::Zero());
    wall_moment_.assign(nw, 0.0);
    for (size_t w = 0; w < nw; ++w)
        if (walls_[w].remove_at <= 0.0) wall_active_[w] = 0;

    with_contact_law(def_.law, [&](auto law) { build_law_tables<decltype(law)>(); });
    wall_reaction_.assign(n, Vec2::Zero());
    rr_factor_.assign(n, 0.0);
    if (def_.rotation.model >= 2 && def_.rotation.u_rr > 0.0)
        for (size_t i = 0; i < n; ++i) rr_factor_[i] = preh_poisel_factor(radius_[i], def_.rotation.u_rr);
    load_.assign(n, DiscLoad{});
    discs_may_have_escaped_ = true;

    prepare_bonds();
    // renumbering in space order as the discs flow (space_order.cpp); a bonded world keeps its
    // numbers, by which its checkpoints name the bonds
    if (def_.space_order == SpaceOrder::On && !bonds_.empty())
        throw InputError("world.space_order = on: a world with bonds (cohesion.enabled) keeps its disc numbers; use auto or off");
    space_order_every_ = def_.space_order == SpaceOrder::On ||
                                 (def_.space_order == SpaceOrder::Auto && n > kSpaceOrderFlowDiscs && bonds_.empty())
                             ? long(def_.space_order_steps)
                             : 0;
    broad_.init(margin_target(), wall_piece_target(), pos_, radius_, geom_, wall_active_);
    refresh_contacts();
    finalized_ = true;

    // first time step: a force pass with dt = 0 (no shear increment, nothing dissipated)
    // counts the contacts the automatic rule needs
    if (def_.timestep.automatic) {
        // (a law whose closing contacts set the step looks one step ahead: law_part.h)
        dt_ = with_contact_law(def_.law, [&](auto law) { return decltype(law)::first_dt(def_.law_def<decltype(law)>()); });
        compute_forces();
        speed_l1_ = 0.0;
        for (const Vec2& v : vel_) speed_l1_ = std::max(speed_l1_, std::abs(v.x()) + std::abs(v.y()));
        dt_ = capped_by_travel(automatic_dt());
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
    with_contact_law(def_.law, [&](auto law) { refresh_contacts_with<decltype(law)>(); });
}

template <typename Law>
void World::refresh_contacts_with() {
    const size_t nm = disc_materials_, nw = walls_.size();
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
            const auto& pm = tables<Law>().disc_disc[size_t(material_[size_t(i)]) * nm + size_t(material_[size_t(j)])];
            DiscContact& c = dd_scratch_[m];
            c.i = i;
            c.j = j;
            Law::start_history(c, pm, contact_mass_disc(i, j), def_.damping.beta_n, def_.damping.beta_s);
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
        const auto& pm = tables<Law>().disc_wall[size_t(material_[size_t(i)]) * nw + size_t(w)];
        WallContact c{i, w, 0.0, 0.0, 0.0, 0.0f, 0.0f};
        // eq. 2.60: the wall's mass is infinite, the contact's mass the disc's
        Law::start_history(c, pm, mass_[size_t(i)], def_.damping.beta_n, def_.damping.beta_s);
        dw_scratch_.push_back(c);
    }
    dw_.swap(dw_scratch_);

    split_force_pass();
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
    if (space_order_due()) order_discs_in_space();
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
        with_contact_law(def_.law, [&](auto law) {
            using Law = decltype(law);
            for (const WallContact& c : dw_) {
                const size_t w = size_t(c.wall);
                if (wall_active_[w]) continue;
                const size_t i = size_t(c.disc);
                removed_walls_ += wall_contact_elastic_energy<Law>(geom_[w], pos_[i], radius_[i],
                                                                   tables<Law>().disc_wall[size_t(material_[i]) * nw + w], c);
            }
        });
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
        dt_ = capped_by_travel(step_from_critical_squared(best_sq));
    }
    if (!lost_pending_.empty()) take_out_lost_discs();
}

double World::smallest_radius() {
    if (r_min_stale_) {
        r_min_ = radius_.empty() ? 0.0 : *std::min_element(radius_.begin(), radius_.end());
        r_min_stale_ = false;
    }
    return r_min_;
}

// The automatic step (the rule's, or DEBRIS' ceiling) shortened when the fastest disc would
// move more than kTravelCap of the smallest radius in it: a disc in free flight at DEBRIS'
// 0.01 s, or one given 3,000 m/s, would otherwise go through a wall between two steps.
// (|vx| + |vy| >= |v|: the cap is on the safe side.) Binds only then: otherwise dt itself.
double World::capped_by_travel(double dt) {
    const double reach = kTravelCap * smallest_radius();
    if (speed_l1_ * dt > reach && reach > 0.0) return reach / speed_l1_;
    return dt;
}

// With a fixed step, a disc that moved more than kMaxTravel of its radius in the last step
// may have crossed a wall (or another disc) without a contact ever seeing it: the run stops,
// naming it. One comparison a step; the scan only when the largest speed trips it. (The
// automatic step is cut instead, capped_by_travel: a sound first step of a bonded pair
// pulled from rest moves 0.68 of a radius, Cohesion.PairStretchedByForce.)
void World::check_travel() {
    if (def_.timestep.automatic || !(speed_l1_ * dt_ > kMaxTravel * smallest_radius())) return;
    for (size_t i = 0; i < pos_.size(); ++i) {
        const double moved = vel_[i].norm() * dt_;
        if (!(moved > kMaxTravel * radius_[i]) || !std::isfinite(moved)) continue;
        const std::string cause = "a time step too large for its speed (timestep.fixed = " + format_number(dt_) +
                                  " s: use a smaller fixed step or the automatic one, timestep.automatic = true)";
        throw RunError("blow-up: disc " + std::to_string(id_[i]) + " moved " + format_number(moved) + " m in one step (speed " +
                       format_number(vel_[i].norm()) + " m/s), more than " + format_number(kMaxTravel) + " of its radius " +
                       format_number(radius_[i]) + " m, at " + where_disc(steps_, time_, id_[i], pos_[i]) +
                       ": it can pass through a wall or a disc unseen. Likely cause: " + cause);
    }
}

void World::run(long steps) {
    for (long s = 0; s < steps; ++s) step();
}

}  // namespace demlab
