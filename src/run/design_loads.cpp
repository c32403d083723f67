#include "run/design_loads.h"

#include <algorithm>
#include <initializer_list>
#include <string>

#include "core/error.h"
#include "dem/world.h"
#include "geometry/deposit.h"
#include "run/measures.h"

namespace demlab {

void DesignLoads::sample(const World& w, const MeasureContext& m, const LoadFilter& filter, const RunSummary& sum) {
    double ix = 0.0;
    for (size_t k = 0; k < m.force_walls.barrier.size(); ++k) {
        const double v = w.wall_impulse(m.force_walls.barrier[k]).x();
        ix = k == 0 ? v : ix + v;  // summed as forces.csv's barrier column
    }
    record(w.time(), filter.fx_barrier, ix);
    if (!std::isnan(t_approach_) || sum.t_front_at_barrier < 0 || !m.path || !std::isfinite(m.barrier.s_barrier)) return;
    // the first sample with the front at the barrier: the flow within the approach length
    // upstream of its foot (the connected discs: a lone disc ahead of the mass is not the flow)
    const size_t n = w.disc_count();
    double r_max = 0.0;
    for (size_t i = 0; i < n; ++i) r_max = std::max(r_max, w.radii()[i]);
    const double length = approach_length_ > 0 ? approach_length_ : 20.0 * r_max;
    const auto conn = connected_discs(w.positions(), w.radii(), m.front_gap);
    double mass = 0.0, top = 0.0;
    Vec2 momentum = Vec2::Zero();
    long count = 0;
    for (size_t i = 0; i < n; ++i) {
        if (!conn[i]) continue;
        double s, h;
        m.path->project(w.positions()[i], s, h);
        if (s < m.barrier.s_barrier - length || s >= m.barrier.s_barrier) continue;
        mass += w.masses()[i];
        momentum += w.masses()[i] * w.velocities()[i];
        top = std::max(top, h + w.radii()[i]);
        ++count;
    }
    if (count == 0) record_approach(w.time(), NAN, NAN, NAN, 0);
    else record_approach(w.time(), top, momentum.norm() / mass, mass / length, count);
}

void DesignLoads::record(double t, double fx_filtered, double ix_barrier) {
    t_.push_back(t);
    fx_.push_back(fx_filtered);
    ix_.push_back(ix_barrier);
}

void DesignLoads::record_approach(double t, double depth, double speed, double mass_per_length, long discs) {
    t_approach_ = t;
    approach_discs_ = double(discs);
    depth_ = depth;
    speed_ = speed;
    mass_per_length_ = mass_per_length;
}

namespace {
// the entry of the last sample at or before t (the first when none is)
size_t sample_at(const std::vector<double>& times, double t) {
    const auto it = std::upper_bound(times.begin(), times.end(), t + 1e-12);
    return it == times.begin() ? 0 : size_t(it - times.begin()) - 1;
}
}  // namespace

void DesignLoads::finish(const LoadFilter& filter, RunSummary& sum, double bulk_density, double gravity) const {
    // a key keeps its first reason (the set-up's before the run's): summary.json has one entry a key
    auto unmeasured = [&](std::initializer_list<const char*> keys, const std::string& why) {
        for (const char* k : keys) {
            const bool known = std::any_of(sum.unmeasured.begin(), sum.unmeasured.end(), [&](const auto& e) { return e.first == k; });
            if (!known) sum.unmeasured.emplace_back(k, why);
        }
    };
    if (!sum.has_arc) unmeasured({"static_fy_arc"}, "the set-up has no arc");
    if (!sum.has_barrier_forces) {
        unmeasured({"static_fx_barrier", "t_barrier_load_steady", "impact_ix_barrier", "t_approach", "approach_depth",
                    "approach_speed", "approach_mass_per_length", "approach_froude", "impact_coefficient_alpha", "static_coefficient_k",
                    "static_bulk_density"},
                   "the set-up has no barrier");
        if (sum.stop_reason == "rest" && sum.has_arc) sum.static_fy_arc = std::abs(filter.fy_arc);
        else if (sum.has_arc) unmeasured({"static_fy_arc"}, "the run did not come to rest (stop: " + sum.stop_reason + ")");
        return;
    }
    // the approaching flow and the hydrodynamic coefficient
    if (!sum.has_barrier) {
        unmeasured({"t_approach", "approach_depth", "approach_speed", "approach_mass_per_length", "approach_froude", "impact_coefficient_alpha"},
                   "the barrier is not on a bed path");
    } else if (std::isnan(t_approach_)) {
        unmeasured({"t_approach", "approach_depth", "approach_speed", "approach_mass_per_length", "approach_froude", "impact_coefficient_alpha"},
                   "the front did not reach the barrier by the end of the run");
    } else if (approach_discs_ == 0) {
        unmeasured({"approach_depth", "approach_speed", "approach_mass_per_length", "approach_froude", "impact_coefficient_alpha"},
                   "no disc of the mass within output.approach_length upstream of the barrier when the front arrived");
        sum.t_approach = t_approach_;
    } else {
        sum.t_approach = t_approach_;
        sum.approach_depth = depth_;
        sum.approach_speed = speed_;
        sum.approach_mass_per_length = mass_per_length_;
        if (depth_ > 0) sum.approach_froude = speed_ / std::sqrt(gravity * depth_);
        if (sum.peak_fx_barrier_filtered > 0 && speed_ > 0)
            sum.impact_coefficient_alpha = sum.peak_fx_barrier_filtered / (mass_per_length_ * speed_ * speed_);
        else
            unmeasured({"impact_coefficient_alpha"}, speed_ > 0 ? "no whole output.load_window with a load on the barrier"
                                                                : "the approaching flow does not move");
    }
    // the static load, when the loads became steady, the impact's impulse, the static coefficient
    if (sum.stop_reason != "rest") {
        unmeasured({"static_fx_barrier", "static_fy_arc", "t_barrier_load_steady", "impact_ix_barrier", "static_coefficient_k",
                    "static_bulk_density"},
                   "the run did not come to rest (stop: " + sum.stop_reason + ")");
        return;
    }
    if (!std::isfinite(filter.fx_barrier)) {
        unmeasured({"static_fx_barrier", "static_fy_arc", "t_barrier_load_steady", "impact_ix_barrier", "static_coefficient_k",
                    "static_bulk_density"},
                   "the run ended before a whole output.load_window");
        return;
    }
    sum.static_fx_barrier = std::abs(filter.fx_barrier);
    if (sum.has_arc) sum.static_fy_arc = std::abs(filter.fy_arc);
    // the arrival: the front's, or where there is no bed path the barrier's first load
    double t_arrival = sum.t_front_at_barrier >= 0 ? sum.t_front_at_barrier : NAN;
    for (size_t k = 0; std::isnan(t_arrival) && k < t_.size(); ++k)
        if (ix_[k] != 0.0) t_arrival = t_[k];
    if (!(sum.static_fx_barrier > 0) || std::isnan(t_arrival) || t_.empty()) {
        unmeasured({"t_barrier_load_steady", "impact_ix_barrier", "static_coefficient_k", "static_bulk_density"},
                   "the barrier carries no load at rest");
        return;
    }
    // steady from the sample after the last one whose filtered load (or its absence: no whole
    // window yet) lies outside the band around the static load
    const double band = kSteadyBand * sum.static_fx_barrier;
    size_t first_steady = 0;
    for (size_t k = t_.size(); k-- > 0;)
        if (!(std::abs(std::abs(fx_[k]) - sum.static_fx_barrier) <= band)) {
            first_steady = k + 1;
            break;
        }
    const double t_steady = std::max(t_arrival, t_[std::min(first_steady, t_.size() - 1)]);
    sum.t_barrier_load_steady = t_steady;
    sum.impact_ix_barrier = std::abs(ix_[sample_at(t_, t_steady)] - ix_[sample_at(t_, t_arrival)]);
    if (!(bulk_density > 0)) {
        unmeasured({"static_coefficient_k", "static_bulk_density"}, "no settled release mass to give the bulk density");
        return;
    }
    sum.static_bulk_density = bulk_density;
    const double height = sum.runup_height;
    if (!sum.has_barrier || !(height > 0)) {
        unmeasured({"static_coefficient_k"}, "no deposit height on the barrier (runup_height)");
        return;
    }
    sum.static_coefficient_k = sum.static_fx_barrier / (0.5 * sum.static_bulk_density * gravity * height * height);
}

void DesignLoads::save(BinaryWriter& out) const {
    out.put(t_);
    out.put(fx_);
    out.put(ix_);
    for (double v : {t_approach_, depth_, speed_, mass_per_length_, approach_discs_}) out.put(v);
}

void DesignLoads::load(BinaryReader& in) {
    in.get(t_);
    in.get(fx_);
    in.get(ix_);
    if (fx_.size() != t_.size() || ix_.size() != t_.size()) throw InputError("corrupt checkpoint (the design loads' samples)");
    for (double* v : {&t_approach_, &depth_, &speed_, &mass_per_length_, &approach_discs_}) in.get(*v);
}

}  // namespace demlab
