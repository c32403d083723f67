#include "dem3/world3.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "dem/laws/law_part.h"

namespace demlab {

namespace {
constexpr double kGrowth = DebrisLaw::kStepGrowth;  // the 2-D law's rule and its reasons
constexpr double kAhead = DebrisLaw::kAheadSteps;
// A cell's key: its indices counted from the cells' origin (World3::cell_origin_), 21 bits
// each, x highest and z lowest, so that the sorted list runs column by column. Counted from the
// origin rather than from zero: a terrain in national or UTM coordinates (a northing of 1.2e6 m)
// has cell indices beyond 2^20, whose bits ran into the next field and put distant spheres into
// one cell, their pairs gathered twice. The order of the keys is that of the indices, so the
// sums' order does not depend on the origin.
constexpr std::int64_t kCellSpan = std::int64_t(1) << 21;

std::uint64_t cell_key(const std::int64_t* origin, std::int64_t x, std::int64_t y, std::int64_t z) {
    return (std::uint64_t(x - origin[0]) << 42) | (std::uint64_t(y - origin[1]) << 21) | std::uint64_t(z - origin[2]);
}

// the most a sphere may move in one step, in radii (integrate)
constexpr double kMaxTravel = 0.5;
}  // namespace

World3::World3(const Dem3Def& def, std::shared_ptr<const Tin> terrain) : def_(def), tin_(std::move(terrain)) {
    pool_ = std::make_unique<ThreadPool>(def.threads);
}

void World3::add_sphere(const Vec3& position, const Vec3& velocity, double radius, double density) {
    if (!(radius > 0.0) || !(density > 0.0)) throw InputError("a sphere needs a positive radius and density");
    pos_.push_back(position);
    vel_.push_back(velocity);
    radius_.push_back(radius);
    mass_.push_back(4.0 / 3.0 * kPi * radius * radius * radius * density);  // D1
    lost_.push_back(0);
    r_max_ = std::max(r_max_, radius);
}

void World3::set_bonds(const BondDef& def, const std::vector<std::pair<int, int>>& pairs) {
    std::vector<std::pair<int, int>> sorted;
    for (auto [k, l] : pairs) {
        if (k < 0 || l < 0 || size_t(std::max(k, l)) >= pos_.size() || k == l)
            throw InputError("bond [" + std::to_string(k) + ", " + std::to_string(l) + "]: needs two different spheres of the " +
                             std::to_string(pos_.size()));
        sorted.emplace_back(std::min(k, l), std::max(k, l));
    }
    std::sort(sorted.begin(), sorted.end());
    if (const auto twice = std::adjacent_find(sorted.begin(), sorted.end()); twice != sorted.end())
        throw InputError("a bond is given twice: [" + std::to_string(twice->first) + ", " + std::to_string(twice->second) + "]");
    bond_def_ = def;
    bonds_.clear();
    for (auto [k, l] : sorted) bonds_.push_back(Bond{k, l, (pos_[size_t(l)] - pos_[size_t(k)]).norm(), 0});
    intact_ = bonds_.size();
    breaks_.clear();
}

// Each intact bond once, in bond order (the same sums on any number of threads): its force
// on both spheres, its largest stiffness in both spheres' K (C10), its energy; a bond past its
// strain or to a lost sphere breaks and books what it held (C4, C12).
void World3::add_bond_forces() {
    double elastic = 0.0;
    for (Bond& b : bonds_) {
        if (b.broken) continue;
        const size_t k = size_t(b.k), l = size_t(b.l);
        const double k0 = ElasticBond::k0_sphere(bond_def_, b.rest_length);
        const Vec3 d = pos_[l] - pos_[k];
        const ElasticBond::Eval e = ElasticBond::evaluate(bond_def_, k0, b.rest_length, 1.0 / b.rest_length, d);
        if (e.breaks || lost_[k] || lost_[l]) {
            const double held = e.skipped ? 0.0 : ElasticBond::energy(bond_def_, k0, b.rest_length, e.strain);
            energy_.bond_broken += held;
            breaks_.push_back(BondBreakEvent{time_, b.k, b.l, e.strain, held});
            b.broken = 1;
            --intact_;
            continue;
        }
        const double k_max = ElasticBond::max_stiffness(bond_def_, k0);
        load_[k].k += k_max;
        load_[l].k += k_max;
        if (e.skipped) continue;
        const Vec3 f = e.f * d;  // on k, towards l when stretched
        load_[k].bonds += f;
        load_[l].bonds -= f;
        elastic += ElasticBond::energy(bond_def_, k0, b.rest_length, e.strain);
    }
    energy_.bond_elastic = elastic;
}

size_t World3::lost_count() const {
    size_t n = 0;
    for (std::uint8_t l : lost_) n += l;
    return n;
}

double World3::kinetic_energy() const {
    double e = 0.0;
    for (size_t i = 0; i < pos_.size(); ++i)
        if (!lost_[i]) e += 0.5 * mass_[i] * vel_[i].squaredNorm();
    return e;
}

void World3::build_cells() {
    // cells two largest radii and a margin wide: a sphere's contacts and the pairs closing in
    // within the look-ahead lie in its own and the 26 cells around it
    double v_max = 0.0;
    for (size_t i = 0; i < pos_.size(); ++i)
        if (!lost_[i]) v_max = std::max(v_max, vel_[i].norm());
    const double ahead = kAhead * (dt_ > 0.0 ? dt_ : def_.dt_max) * 2.0 * v_max;
    cell_ = std::max(2.0 * r_max_ + ahead, 1e-9);
    cells_.clear();
    // the origin one cell below the lowest sphere's (the queries look one cell around)
    std::int64_t lo[3] = {INT64_MAX, INT64_MAX, INT64_MAX}, hi[3] = {INT64_MIN, INT64_MIN, INT64_MIN};
    for (size_t i = 0; i < pos_.size(); ++i) {
        if (lost_[i]) continue;
        for (int a = 0; a < 3; ++a) {
            const double c = std::floor(pos_[i][a] / cell_);
            if (!(std::abs(c) < 1e15))
                throw RunError("sphere " + std::to_string(i) + " is at " + format_number(pos_[i][a]) + " m along axis " +
                               std::to_string(a) + ": the run blew up (reduce dem3.dt_max or set dem3.dt_fixed smaller)");
            lo[a] = std::min(lo[a], std::int64_t(c));
            hi[a] = std::max(hi[a], std::int64_t(c));
        }
    }
    for (int a = 0; a < 3; ++a) {
        cell_origin_[a] = lo[a] - 1;
        if (lo[a] <= hi[a] && hi[a] + 1 - cell_origin_[a] >= kCellSpan)
            throw RunError("the spheres spread over more than " + std::to_string(kCellSpan - 2) + " cells of " + format_number(cell_) +
                           " m along axis " + std::to_string(a) + " (from " + format_number(double(lo[a]) * cell_) + " to " +
                           format_number(double(hi[a] + 1) * cell_) + " m): the run blew up");
    }
    for (size_t i = 0; i < pos_.size(); ++i) {
        if (lost_[i]) continue;
        const Vec3& p = pos_[i];
        cells_.emplace_back(cell_key(cell_origin_, std::int64_t(std::floor(p.x() / cell_)), std::int64_t(std::floor(p.y() / cell_)),
                                     std::int64_t(std::floor(p.z() / cell_))),
                            std::uint32_t(i));
    }
    std::sort(cells_.begin(), cells_.end());
}

void World3::gather(size_t i, double ahead_dt, Load& l, std::vector<TinContact>& bed) const {
    l = Load{};
    const double E = def_.youngs_modulus, ri = radius_[i];
    const Vec3 &p = pos_[i], &v = vel_[i];
    // the bed: the features within the radius, and those the sphere may reach in the look-ahead
    const double reach = kAhead * ahead_dt * v.norm();
    bed.clear();
    tin_->sphere_contacts(p, ri + reach, bed);
    for (const TinContact& c : bed) {
        const double delta = ri - c.distance, vn = v.dot(c.normal);
        const double ahead = delta + kAhead * ahead_dt * std::max(0.0, -vn);
        if (ahead > 0.0) l.k += debris::sphere_stiffness(E, std::min(ahead, 0.999 * ri), ri, 0.0);
        if (!(delta > 0.0)) continue;
        const double f = debris::sphere_force(E, delta, ri, 0.0);
        l.bed += f * c.normal;
        l.moduli += f;
        l.elastic += debris::sphere_energy(E, delta, ri, 0.0);
        ++l.touching;
    }
    // the pairs, from the 27 cells around: z is the key's lowest part, so each column of three
    // cells is one run of the sorted list
    const std::int64_t cx = std::int64_t(std::floor(p.x() / cell_)), cy = std::int64_t(std::floor(p.y() / cell_)),
                       cz = std::int64_t(std::floor(p.z() / cell_));
    for (std::int64_t dx = -1; dx <= 1; ++dx)
        for (std::int64_t dy = -1; dy <= 1; ++dy) {
                const std::uint64_t first = cell_key(cell_origin_, cx + dx, cy + dy, cz - 1),
                                    last = cell_key(cell_origin_, cx + dx, cy + dy, cz + 1);
                auto it = std::lower_bound(cells_.begin(), cells_.end(), std::make_pair(first, std::uint32_t(0)));
                for (; it != cells_.end() && it->first <= last; ++it) {
                    const size_t j = it->second;
                    if (j == i) continue;
                    const double rj = radius_[j], rsum = ri + rj;
                    const Vec3 d = pos_[j] - p;
                    const Vec3 vrel = vel_[j] - v;
                    const double reach_ij = rsum + kAhead * ahead_dt * vrel.norm();
                    const double dist2 = d.squaredNorm();
                    if (dist2 >= reach_ij * reach_ij) continue;
                    const double dist = std::sqrt(dist2);
                    const Vec3 n = d / dist;  // from i to j
                    const double delta = rsum - dist, vn = vrel.dot(n);
                    const double ahead = delta + kAhead * ahead_dt * std::max(0.0, -vn);
                    if (ahead > 0.0) l.k += debris::sphere_stiffness(E, std::min(ahead, 0.999 * std::min(ri, rj)), ri, rj);
                    if (!(delta > 0.0)) continue;
                    const double f = debris::sphere_force(E, delta, ri, rj);
                    l.pairs -= f * n;
                    l.moduli += f;
                    l.elastic += 0.5 * debris::sphere_energy(E, delta, ri, rj);
                    ++l.touching;
                }
        }
}

void World3::gather_all(double ahead_dt) {
    const size_t n = pos_.size();
    load_.resize(n);
    build_cells();
    // a sphere's gather (its TIN features, 27 cells) costs microseconds, so a few hundred spheres
    // already pay for sharing out (the pool's own rule waits for thousands of cheap items)
    const size_t parts = n >= 256 ? size_t(pool_->size()) : 1;
    auto chunk = [&](size_t k) {
        thread_local std::vector<TinContact> bed;
        for (size_t i = n * k / parts; i < n * (k + 1) / parts; ++i)
            if (!lost_[i]) gather(i, ahead_dt, load_[i], bed);
    };
    if (parts == 1) chunk(0);
    else pool_->for_each_thread([&](int k) { chunk(size_t(k)); });
    if (!bonds_.empty()) add_bond_forces();
}

// The gathered loads summed at x_n: the contacts and the ledger's elastic and potential
// energy; returns the smallest m / K over the spheres (the step's rule, D12).
double World3::tally() {
    double best_sq = INFINITY, elastic = 0.0, potential = 0.0;
    long touching = 0;
    for (size_t i = 0; i < pos_.size(); ++i) {
        if (lost_[i]) continue;
        if (load_[i].k > 0.0) best_sq = std::min(best_sq, mass_[i] / load_[i].k);
        elastic += load_[i].elastic;
        potential += mass_[i] * def_.gravity * pos_[i].z();
        touching += load_[i].touching;
    }
    contacts_ = touching;
    energy_.elastic = elastic;
    energy_.potential = potential;
    return best_sq;
}

void World3::measure() {
    gather_all(dt_ > 0.0 ? dt_ : def_.dt_max);
    tally();
    energy_.kinetic = kinetic_energy();
}

void World3::step() {
    gather_all(dt_ > 0.0 ? dt_ : def_.dt_max);
    const double best_sq = tally();
    const double dt = def_.dt_fixed > 0.0 ? def_.dt_fixed : capped_growing_step(def_.dt_max, kGrowth, def_.safety, best_sq, dt_);
    book_lost(dt);
    integrate(dt);
    time_ += dt;
    dt_ = dt;
    ++steps_;
}

// The spheres lost in the last step leave this step's ledger; what they carry is booked as
// the ledger would have held them now: the potential at x_n and the leapfrog's kinetic energy
// m v(n-1/2) . v(n+1/2) / 2 with v(n+1/2) from gravity alone (free flight), so the balance
// neither jumps when they go nor counts them twice.
void World3::book_lost(double dt) {
    const double h = dt_ > 0.0 ? 0.5 * (dt_ + dt) : dt;
    const Vec3 g(0.0, 0.0, -def_.gravity);
    for (std::uint32_t i : just_lost_) {
        const Vec3& v = vel_[i];
        energy_.lost += 0.5 * mass_[i] * v.dot(v + h * g) + mass_[i] * def_.gravity * pos_[i].z();
    }
    just_lost_.clear();
}

void World3::integrate(double dt) {
    // a force at x_n acts from t_n - dt_(n-1)/2 to t_n + dt_n/2 (variable-step Stormer-Verlet,
    // as the 2-D law: integrate_debris.cpp)
    const double h = dt_ > 0.0 ? 0.5 * (dt_ + dt) : dt;
    const Vec3 g(0.0, 0.0, -def_.gravity);
    const bool resultant = def_.friction_normal == DebrisNormal::Resultant;
    const bool trial = def_.friction_direction == DebrisDirection::Trial;
    const Vec3 lo = tin_->lower_corner(), hi = tin_->upper_corner();
    const double margin = std::max(hi.z() - lo.z(), 10.0 * r_max_);
    double kinetic = 0.0, friction = 0.0;
    double worst_travel = 0.0;  // the largest (travel / radius)^2 of the step
    size_t worst = 0;
    for (size_t i = 0; i < pos_.size(); ++i) {
        if (lost_[i]) continue;
        const Load& l = load_[i];
        const double m = mass_[i], inv_m = 1.0 / m;
        const Vec3 v_old = vel_[i];
        const Vec3 v_star = v_old + (l.bed + l.pairs + l.bonds + m * g) * (inv_m * h);
        Vec3 v_new = v_star;
        if (l.touching > 0) {
            const double normal = resultant ? l.bed.norm() + l.pairs.norm() : l.moduli;  // N + P (D4)
            if (trial) {
                v_new = debris::friction_trial(v_star, h * def_.mu * normal * inv_m, h * def_.eta * inv_m);
            } else {
                const double speed = v_old.norm();
                if (speed > 0.0) v_new = v_star - (h * inv_m * (def_.mu * normal + def_.eta * speed) / speed) * v_old;
            }
            // the friction impulse's work over the step's mean velocity (centred)
            friction -= 0.5 * m * (v_new - v_star).dot(v_old + v_new);
        }
        kinetic += 0.5 * m * v_old.dot(v_new);
        vel_[i] = v_new;
        pos_[i] += dt * v_new;
        if (const double travel = (dt * dt) * v_new.squaredNorm() / (radius_[i] * radius_[i]);
            travel > worst_travel || (std::isnan(travel) && !std::isnan(worst_travel))) {
            worst_travel = travel;
            worst = i;
        }
        const Vec3& p = pos_[i];
        // past the terrain's edge in map view there is no bed: the sphere is lost there (it
        // would only fall), or below the terrain by its height
        const double edge = radius_[i];
        if (p.x() < lo.x() - edge || p.y() < lo.y() - edge || p.x() > hi.x() + edge || p.y() > hi.y() + edge ||
            p.z() < lo.z() - margin) {
            lost_[i] = 1;
            just_lost_.push_back(std::uint32_t(i));  // this step's ledger still holds it (book_lost)
        }
    }
    energy_.kinetic = kinetic;
    energy_.dissipated += friction;
    // a sphere that moves more than half its radius in a step can pass through the bed or another
    // sphere before a contact sees it (a 1 s step from rest drops it 9.8 m): the run stops, as the
    // 2-D world's fixed step does (World::kMaxTravel), instead of losing the spheres as strays.
    // A sound run moves far less: snow-slide-3d at most 0.007 of the radius a step over its
    // first 0.35 s; Attabad's 10 m spheres at 0.01 s reach half a radius only at 500 m/s.
    if (!(worst_travel <= kMaxTravel * kMaxTravel))
        throw RunError("sphere " + std::to_string(worst) + " (radius " + format_number(radius_[worst]) + " m) moved " +
                       format_number(dt * vel_[worst].norm()) + " m in one step of " + format_number(dt) + " s at " +
                       format_number(vel_[worst].norm()) + " m/s, more than half its radius, at t = " + format_number(time_) +
                       " s: a step that long passes through the bed or another sphere unseen, or the run blew up; give " +
                       (def_.dt_fixed > 0.0 ? "a smaller dem3.dt_fixed" : "a smaller dem3.dt_max or dem3.safety"));
}

void World3::save_state(BinaryWriter& out) const {
    out.tag("DEM3");
    out.put(std::uint64_t(pos_.size()));
    for (size_t i = 0; i < pos_.size(); ++i) {
        for (int k = 0; k < 3; ++k) out.put(pos_[i][k]);
        for (int k = 0; k < 3; ++k) out.put(vel_[i][k]);
        out.put(lost_[i]);
    }
    out.put(time_);
    out.put(dt_);
    out.put(std::int64_t(steps_));
    out.put(energy_.kinetic);
    out.put(energy_.potential);
    out.put(energy_.elastic);
    out.put(energy_.dissipated);
    out.put(energy_.lost);
    out.put(std::uint64_t(just_lost_.size()));
    for (std::uint32_t i : just_lost_) out.put(i);
    out.tag("BND3");
    out.put(std::uint64_t(bonds_.size()));
    for (const Bond& b : bonds_) {
        out.put(b.rest_length);
        out.put(b.broken);
    }
    out.put(energy_.bond_elastic);
    out.put(energy_.bond_broken);
    out.put(std::uint64_t(breaks_.size()));
    for (const BondBreakEvent& e : breaks_) {
        out.put(e.t);
        out.put(std::int64_t(e.k));
        out.put(std::int64_t(e.l));
        out.put(e.strain);
        out.put(e.energy);
    }
}

void World3::load_state(BinaryReader& in) {
    in.expect_tag("DEM3");
    std::uint64_t n = 0;
    in.get(n);
    if (n != pos_.size()) throw InputError("checkpoint: " + std::to_string(n) + " spheres, the scenario makes " + std::to_string(pos_.size()));
    for (size_t i = 0; i < pos_.size(); ++i) {
        for (int k = 0; k < 3; ++k) in.get(pos_[i][k]);
        for (int k = 0; k < 3; ++k) in.get(vel_[i][k]);
        in.get(lost_[i]);
    }
    in.get(time_);
    in.get(dt_);
    std::int64_t steps = 0;
    in.get(steps);
    steps_ = long(steps);
    in.get(energy_.kinetic);
    in.get(energy_.potential);
    in.get(energy_.elastic);
    in.get(energy_.dissipated);
    in.get(energy_.lost);
    in.get(n);
    just_lost_.assign(size_t(n), 0);
    for (std::uint32_t& i : just_lost_) {
        in.get(i);
        if (i >= pos_.size()) throw InputError("checkpoint: a lost sphere " + std::to_string(i) + " that does not exist");
    }
    in.expect_tag("BND3");
    in.get(n);
    if (n != bonds_.size()) throw InputError("checkpoint: " + std::to_string(n) + " bonds, the scenario makes " + std::to_string(bonds_.size()));
    intact_ = 0;
    for (Bond& b : bonds_) {
        in.get(b.rest_length);
        in.get(b.broken);
        intact_ += b.broken ? 0 : 1;
    }
    in.get(energy_.bond_elastic);
    in.get(energy_.bond_broken);
    in.get(n);
    breaks_.assign(size_t(n), BondBreakEvent{});
    for (BondBreakEvent& e : breaks_) {
        std::int64_t k = 0, l = 0;
        in.get(e.t);
        in.get(k);
        in.get(l);
        e.k = std::int32_t(k);
        e.l = std::int32_t(l);
        in.get(e.strain);
        in.get(e.energy);
    }
}

}  // namespace demlab
