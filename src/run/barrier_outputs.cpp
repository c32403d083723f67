#include "run/barrier_outputs.h"

#include <algorithm>
#include <cmath>
#include <sstream>


namespace demlab {

BarrierOutputs::BarrierOutputs(std::string dir, const World& w, const MeasureContext& m) : dir_(std::move(dir)), m_(m) {
    // the barrier as a polyline from its lower end (the flume's W3 from its foot, a terrain's
    // barrier in the order given: foot first); the flow is on its left
    double s0 = 0.0;
    for (int k : m.force_walls.barrier) {
        const WallGeom& g = w.wall_geom(k);
        if (g.shape != WallShape::Segment) continue;
        const Vec2 t = (g.p1 - g.p0).normalized();
        segments_.push_back({k, g.p0, g.p1, perp(t), s0, (g.p1 - g.p0).norm()});
        s0 += segments_.back().length;
    }
    if (!segments_.empty()) {
        // A bin no shorter than the largest disc's diameter: a disc presses over its own width,
        // and a bin shorter than that holds one contact's force over a part of it (at scale 20,
        // 1 cm bins under discs up to 2 cm wide gave 76,945 Pa from one bin at the foot)
        double r_max = 0.0;
        for (double r : w.radii()) r_max = std::max(r_max, r);
        const double bin = std::max(m.scenario.output.pressure_bin, 2.0 * r_max);
        const long n = std::max(1L, std::lround(s0 / bin));
        bin_length_ = s0 / double(n);
        pressure_.assign(size_t(n), 0.0);
    }
    bed_wall_.assign(w.wall_count(), 0);
    for (const std::vector<int>* ws : {&m.force_walls.slope, &m.force_walls.arc, &m.force_walls.barrier})
        for (int k : *ws) bed_wall_[size_t(k)] = 1;
    if (m.path) {
        path_bin_ = m.scenario.output.deposit_bin;
        const size_t bins = size_t(std::ceil(m.path->length() / path_bin_)) + 1;
        peak_height_.assign(bins, 0.0);
        peak_speed_.assign(bins, 0.0);
        peak_pressure_.assign(bins, 0.0);
    }
}

void BarrierOutputs::open() {
    if (!has_barrier()) return;
    file_.open(dir_ + "/barrier_pressure.csv");
    std::ostringstream h;
    h.precision(6);
    h << "t_s";
    for (size_t k = 0; k < pressure_.size(); ++k) h << ",p_at_" << (double(k) + 0.5) * bin_length_ << "_m_Pa";
    file_.out() << h.str() << '\n';
}

void BarrierOutputs::reopen(uint64_t size) {
    if (has_barrier()) file_.reopen(dir_ + "/barrier_pressure.csv", size);
}

uint64_t BarrierOutputs::flush() { return has_barrier() ? file_.flush() : 0; }

void BarrierOutputs::sample(const World& w, double t) {
    w.wall_loads(loads_);
    const std::vector<Vec2>& pos = w.positions();
    const std::vector<Vec2>& vel = w.velocities();
    const std::vector<double>& radius = w.radii();
    if (has_barrier()) {
        std::fill(pressure_.begin(), pressure_.end(), 0.0);
        for (const World::WallLoad& l : loads_) {
            for (const Segment& g : segments_) {
                if (g.wall != l.wall) continue;
                // where the disc touches: its centre's foot on the segment
                const Vec2 along = (g.p1 - g.p0) / g.length;
                const double u = std::clamp((pos[size_t(l.disc)] - g.p0).dot(along), 0.0, g.length);
                const size_t b = std::min(pressure_.size() - 1, size_t(std::max(0.0, (g.s0 + u) / bin_length_)));
                // the disc pushes against the normal (out of the barrier): a positive pressure
                pressure_[b] -= l.force.dot(g.normal) / bin_length_;
            }
        }
        std::ostream& o = file_.out();
        o << t;
        for (double p : pressure_) o << ',' << p;
        o << '\n';
        file_.check();
        for (size_t b = 0; b < pressure_.size(); ++b)
            if (pressure_[b] > peak_barrier_pressure_) {
                peak_barrier_pressure_ = pressure_[b];
                s_peak_barrier_pressure_ = (double(b) + 0.5) * bin_length_;
                t_peak_barrier_pressure_ = t;
            }
    }
    if (!m_.path || !enabled_) return;
    const BedPath& path = *m_.path;
    const size_t bins = peak_height_.size();
    auto bin_of = [&](double s) { return long(std::floor(s / path_bin_ + 0.5)); };
    // the bed's pressure: each bed contact's normal force, binned by where its disc is along the path
    std::vector<double> bed(bins, 0.0), top(bins, 0.0), speed_sum(bins, 0.0);
    std::vector<long> count(bins, 0);
    for (const World::WallLoad& l : loads_) {
        if (!bed_wall_[size_t(l.wall)]) continue;
        double s, h;
        path.project(pos[size_t(l.disc)], s, h);
        const long b = bin_of(s);
        if (b < 0 || b >= long(bins)) continue;
        Vec2 point, normal;
        path.at(s, point, normal);
        bed[size_t(b)] -= l.force.dot(normal) / path_bin_;
    }
    for (size_t i = 0; i < pos.size(); ++i) {
        double s, h;
        path.project(pos[i], s, h);
        const long b = bin_of(s);
        if (b < 0 || b >= long(bins)) continue;
        top[size_t(b)] = std::max(top[size_t(b)], h + radius[i]);
        speed_sum[size_t(b)] += vel[i].norm();
        ++count[size_t(b)];
    }
    for (size_t b = 0; b < bins; ++b) {
        peak_height_[b] = std::max(peak_height_[b], top[b]);
        if (count[b] > 0) peak_speed_[b] = std::max(peak_speed_[b], speed_sum[b] / double(count[b]));
        peak_pressure_[b] = std::max(peak_pressure_[b], bed[b]);
    }
}

void BarrierOutputs::finish(RunSummary& sum) {
    if (has_barrier()) {
        file_.close();
        sum.peak_barrier_pressure = peak_barrier_pressure_;
        sum.barrier_pressure_bin = bin_length_;
        sum.s_peak_barrier_pressure = s_peak_barrier_pressure_;
        sum.t_peak_barrier_pressure = t_peak_barrier_pressure_;
    }
    if (!m_.path || !enabled_) return;
    std::ostringstream o;
    o.precision(10);
    o << "s_m,max_height_m,max_mean_speed_m_per_s,max_bed_pressure_Pa\n";
    for (size_t b = 0; b < peak_height_.size(); ++b)
        o << double(b) * path_bin_ << ',' << peak_height_[b] << ',' << peak_speed_[b] << ',' << peak_pressure_[b] << '\n';
    write_file_atomic(dir_ + "/peaks.csv", o.str());
}

void BarrierOutputs::save(BinaryWriter& out) {
    out.tag("BARR");
    out.put(flush());
    out.put(peak_height_);
    out.put(peak_speed_);
    out.put(peak_pressure_);
    out.put(peak_barrier_pressure_);
    out.put(s_peak_barrier_pressure_);
    out.put(t_peak_barrier_pressure_);
}

void BarrierOutputs::load(BinaryReader& in) {
    in.expect_tag("BARR");
    const uint64_t size = in.get<uint64_t>();
    const size_t bins = peak_height_.size();
    in.get(peak_height_, bins);
    in.get(peak_speed_, bins);
    in.get(peak_pressure_, bins);
    in.get(peak_barrier_pressure_);
    in.get(s_peak_barrier_pressure_);
    in.get(t_peak_barrier_pressure_);
    reopen(size);
}

}  // namespace demlab
