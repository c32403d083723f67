#include "run/measures.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "core/error.h"
#include "core/machine.h"
#include "core/validate.h"
#include "run/series_columns.h"
#include "run/solver.h"
#include "run/summary_file.h"

namespace demlab {

namespace {

// A group of walls' force or impulse: the first wall's own value, then the others added (a
// group of one gives that wall's bits, a signed zero too); none: zero.
template <typename Get>
Vec2 group_sum(const std::vector<int>& walls, Get get) {
    if (walls.empty()) return Vec2::Zero();
    Vec2 v = get(walls[0]);
    for (size_t k = 1; k < walls.size(); ++k) v += get(walls[k]);
    return v;
}
}  // namespace

std::string forces_header(const ForceWalls& walls) {
    const std::vector<ForceGroup> groups = walls.written();
    std::string h = "t_s";
    for (const char* q : {"f", "i"}) {
        const std::string unit = q[0] == 'f' ? "_N_per_m" : "_Ns_per_m";
        for (const ForceGroup& g : groups) h += std::string(",") + q + "x_" + g.name + unit + "," + q + "y_" + g.name + unit;
        h += std::string(",") + q + "x_total" + unit + "," + q + "y_total" + unit;
    }
    if (walls.gate >= 0) h += ",fx_gate_N_per_m,fy_gate_N_per_m,ix_gate_Ns_per_m,iy_gate_Ns_per_m";
    std::vector<std::string> names;
    for (const ForceGroup& g : groups) names.push_back(g.name);
    names.push_back("total");
    for (const std::string& g : names)
        for (const char* c : {"x", "y"})
            for (const char* e : {"max", "min"}) h += std::string(",f") + c + "_" + g + "_" + e + "_N_per_m";
    // the impulse-filtered loads (LoadFilter), empty before a whole window has passed
    if (!walls.barrier.empty()) h += ",fx_barrier_filtered_N_per_m";
    if (!walls.arc.empty()) h += ",fy_arc_filtered_N_per_m";
    return h;
}

ForceExtremes::ForceExtremes(const ForceWalls& walls) : groups_(walls.written()) {
    for (size_t g = 0; g < groups_.size(); ++g) {
        if (groups_[g].name == "barrier") barrier_ = int(g);
        if (groups_[g].name == "arc") arc_ = int(g);
    }
    row_.assign(4 * (groups_.size() + 1), 0.0);
    reset_row();
}

void ForceExtremes::reset_row() {
    for (size_t k = 0; k < row_.size(); k += 2) {
        row_[k] = -INFINITY;     // max
        row_[k + 1] = INFINITY;  // min
    }
}

void ForceExtremes::step(const World& w) {
    auto force = [&](int k) { return w.wall_force(k); };
    forces_.resize(groups_.size());
    for (size_t g = 0; g < groups_.size(); ++g) forces_[g] = group_sum(groups_[g].walls, force);
    step(w.time(), forces_.data());
}

void ForceExtremes::step(double t, const Vec2* group_forces) {
    Vec2 total = Vec2::Zero();
    auto fold = [&](size_t g, const Vec2& f) {
        double* r = &row_[4 * g];
        r[0] = std::max(r[0], f.x());
        r[1] = std::min(r[1], f.x());
        r[2] = std::max(r[2], f.y());
        r[3] = std::min(r[3], f.y());
    };
    for (size_t g = 0; g < groups_.size(); ++g) {
        const Vec2 f = group_forces[g];
        total = g == 0 ? f : Vec2(total + f);  // summed as forces.csv's total
        fold(g, f);
        if (int(g) == barrier_ && std::abs(f.x()) > peak_fx_barrier) {
            peak_fx_barrier = std::abs(f.x());
            t_peak_fx_barrier = t;
        }
        if (int(g) == arc_ && std::abs(f.y()) > peak_fy_arc) {
            peak_fy_arc = std::abs(f.y());
            t_peak_fy_arc = t;
        }
    }
    fold(groups_.size(), total);
}

void LoadFilter::step(const World& w, const ForceWalls& walls) {
    auto impulse = [&](int k) { return w.wall_impulse(k); };
    step(w.time(), group_sum(walls.barrier, impulse).x(), group_sum(walls.arc, impulse).y());
}

void LoadFilter::step(double t, double ix_barrier, double iy_arc) {
    t_.push_back(t);
    ix_.push_back(ix_barrier);
    iy_.push_back(iy_arc);
    // the last entry at or before t - W starts the window; those before it are not needed again
    while (first_ + 1 < t_.size() && t_[first_ + 1] <= t - window_) ++first_;
    if (first_ > 4096 && first_ > t_.size() / 2) {  // drop the consumed half now and then
        t_.erase(t_.begin(), t_.begin() + long(first_));
        ix_.erase(ix_.begin(), ix_.begin() + long(first_));
        iy_.erase(iy_.begin(), iy_.begin() + long(first_));
        first_ = 0;
    }
    const double span = t - t_[first_];
    if (!(t_[first_] <= t - window_) || !(span > 0.0)) return;  // not a whole window yet
    fx_barrier = (ix_barrier - ix_[first_]) / span;
    fy_arc = (iy_arc - iy_[first_]) / span;
    if (std::abs(fx_barrier) > peak_fx_barrier) {
        peak_fx_barrier = std::abs(fx_barrier);
        t_peak_fx_barrier = t;
    }
    if (std::abs(fy_arc) > peak_fy_arc) {
        peak_fy_arc = std::abs(fy_arc);
        t_peak_fy_arc = t;
    }
}

void take_load_peaks(RunSummary& sum, const ForceExtremes& extremes, const LoadFilter& filter) {
    sum.peak_fx_barrier = extremes.peak_fx_barrier;
    sum.t_peak_fx_barrier = extremes.t_peak_fx_barrier;
    sum.peak_fy_arc = extremes.peak_fy_arc;
    sum.t_peak_fy_arc = extremes.t_peak_fy_arc;
    sum.peak_fx_barrier_filtered = filter.peak_fx_barrier;
    sum.t_peak_fx_barrier_filtered = filter.t_peak_fx_barrier;
    sum.peak_fy_arc_filtered = filter.peak_fy_arc;
    sum.t_peak_fy_arc_filtered = filter.t_peak_fy_arc;
}

void LoadFilter::save(BinaryWriter& out) const {
    const std::vector<double> t(t_.begin() + long(first_), t_.end()), ix(ix_.begin() + long(first_), ix_.end()),
        iy(iy_.begin() + long(first_), iy_.end());
    out.put(t);
    out.put(ix);
    out.put(iy);
    for (double v : {peak_fx_barrier, t_peak_fx_barrier, peak_fy_arc, t_peak_fy_arc, fx_barrier, fy_arc}) out.put(v);
}

void LoadFilter::load(BinaryReader& in) {
    in.get(t_);
    in.get(ix_);
    in.get(iy_);
    if (ix_.size() != t_.size() || iy_.size() != t_.size()) throw InputError("corrupt checkpoint (the load filter's window)");
    first_ = 0;
    for (double* v : {&peak_fx_barrier, &t_peak_fx_barrier, &peak_fy_arc, &t_peak_fy_arc, &fx_barrier, &fy_arc}) in.get(*v);
}

void ForceExtremes::save(BinaryWriter& out) const {
    out.put(row_);
    for (double v : {peak_fx_barrier, t_peak_fx_barrier, peak_fy_arc, t_peak_fy_arc}) out.put(v);
}

void ForceExtremes::load(BinaryReader& in) {
    std::vector<double> row;
    in.get(row);
    if (row.size() != row_.size()) throw InputError("corrupt checkpoint (the force extremes do not match the set-up's walls)");
    row_ = std::move(row);
    for (double* v : {&peak_fx_barrier, &t_peak_fx_barrier, &peak_fy_arc, &t_peak_fy_arc}) in.get(*v);
}

void RunSeries::open() {
    forces_.open(dir_ + "/forces.csv");
    forces_.out() << forces_header_ << '\n';
    energy_.open(dir_ + "/energy.csv");
    energy_.out() << kEnergyColumns << (has_bonds_ ? kEnergyBondColumns : "") << '\n';
    if (has_front_) {
        front_.open(dir_ + "/front.csv");
        front_.out() << kFrontColumns << '\n';
    }
    if (has_track_) {
        track_.open(dir_ + "/track.csv");
        track_.out() << kTrackColumns << '\n';
    }
}

void RunSeries::reopen(const std::array<uint64_t, 4>& size) {
    // a checkpoint of an earlier build whose forces.csv has other columns (before the every-step
    // extremes, or the flume's columns for a dam break): rows of this build would not match
    // its header
    std::string header;
    std::getline(std::ifstream(dir_ + "/forces.csv.part"), header);
    if (!header.empty() && header != forces_header_)
        throw InputError("cannot resume " + dir_ + ": its forces.csv was begun by an earlier build with other columns (" +
                         std::to_string(std::count(header.begin(), header.end(), ',') + 1) + ", this build writes " +
                         std::to_string(std::count(forces_header_.begin(), forces_header_.end(), ',') + 1) +
                         "); run it again from the start (demlab run ... --force)");
    forces_.reopen(dir_ + "/forces.csv", size[0]);
    energy_.reopen(dir_ + "/energy.csv", size[1]);
    if (has_front_) front_.reopen(dir_ + "/front.csv", size[2]);
    if (has_track_) track_.reopen(dir_ + "/track.csv", size[3]);
}

std::array<uint64_t, 4> RunSeries::flush() { return {forces_.flush(), energy_.flush(), front_.flush(), track_.flush()}; }

void RunSeries::close() {
    forces_.close();
    energy_.close();
    front_.close();
    track_.close();
}

void RunSeries::sample(const World& w, const MeasureContext& m, RunState& st, RunSummary& sum, ForceExtremes& extremes,
                       const LoadFilter& filter) {
    const double t = w.time();
    const ForceWalls& fw = m.force_walls;
    auto force = [&](int k) { return w.wall_force(k); };
    auto impulse = [&](int k) { return w.wall_impulse(k); };
    // the roles the landmarks read (zero where the set-up has none: never written then)
    const Vec2 f[3] = {group_sum(fw.slope, force), group_sum(fw.arc, force), group_sum(fw.barrier, force)};
    std::ostream& fo = forces_.out();
    fo << t;
    for (const bool forces : {true, false}) {
        // the groups in forces_header's order, then their total (summed in that order: the
        // flume's slope + arc + barrier as before)
        Vec2 total = Vec2::Zero();
        for (size_t k = 0; k < groups_.size(); ++k) {
            const Vec2 v = forces ? group_sum(groups_[k].walls, force) : group_sum(groups_[k].walls, impulse);
            total = k == 0 ? v : Vec2(total + v);
            fo << ',' << v.x() << ',' << v.y();
        }
        fo << ',' << total.x() << ',' << total.y();
    }
    if (has_gate_) {
        const Vec2 fg = w.wall_force(fw.gate), ig = w.wall_impulse(fw.gate);
        fo << ',' << fg.x() << ',' << fg.y() << ',' << ig.x() << ',' << ig.y();
    }
    // the extremes of every step since the previous row, this one's included
    extremes.step(w);
    for (double v : extremes.row()) fo << ',' << v;
    extremes.reset_row();
    auto filtered = [&](double v) {
        fo << ',';
        if (std::isfinite(v)) fo << v;
    };
    if (!fw.barrier.empty()) filtered(filter.fx_barrier);
    if (!fw.arc.empty()) filtered(filter.fy_arc);
    fo << '\n';
    if (std::abs(f[2].x()) > st.peak_fx_barrier) {
        st.peak_fx_barrier = std::abs(f[2].x());
        sum.t_peak_fx_barrier_sampled = t;
    }
    if (std::abs(f[1].y()) > st.peak_fy_arc) {
        st.peak_fy_arc = std::abs(f[1].y());
        sum.t_peak_fy_arc_sampled = t;
    }
    const EnergyReport e = w.energy();
    require_finite_ledger(e, w.step_count(), t);
    st.peak_put_in = std::max(st.peak_put_in, energy_put_in(e, st.e0));
    energy_.out() << t << ',' << e.kinetic_translation << ',' << e.kinetic_rotation << ',' << e.potential << ','
                  << e.elastic << ',' << e.dissipated_contacts << ',' << e.dissipated_local << ','
                  << e.dissipated_rotation << ',' << e.work_by_walls << ',' << e.removed_with_walls << ','
                  << e.lost_with_discs << ',' << e.balance();
    if (has_bonds_) {
        const size_t total = w.bonds_at_start(), gone = w.bond_breaks().size() + w.bonds_lost_with_discs();
        energy_.out() << ',' << e.bond_elastic << ',' << e.bond_break_loss << ',' << double(total - gone) / double(total);
    }
    energy_.out() << '\n';
    if (m.path) {
        const BedPath& path = *m.path;
        const size_t n = w.disc_count();
        const auto conn = connected_discs(w.positions(), w.radii(), m.front_gap);
        double s_front = -INFINITY, disp = 0, runup = 0;
        for (size_t i = 0; i < n; ++i) {
            if (!conn[i]) continue;
            double si, hi_;
            path.project(w.positions()[i], si, hi_);
            if (si > s_front) {
                s_front = si;
                disp = (w.positions()[i] - m.start_pos[size_t(w.disc_ids()[i])]).norm();
            }
            if (si > m.barrier.s_barrier) runup = std::max(runup, w.positions()[i].y() + w.radii()[i] - m.barrier.foot.y());
        }
        front_.out() << t << ',' << s_front << ',' << disp << '\n';
        sum.max_runup_height_during_run = std::max(sum.max_runup_height_during_run, runup);
        if (sum.t_front_at_barrier < 0 && s_front >= m.barrier.s_barrier) sum.t_front_at_barrier = t;
    }
    for (long id : m.scenario.output.track) {
        const long index = w.disc_index(id);
        if (index < 0) continue;  // lost (lost.csv)
        const size_t i = size_t(index);
        track_.out() << t << ',' << id << ',' << w.positions()[i].x() << ',' << w.positions()[i].y() << ','
                     << w.velocities()[i].x() << ',' << w.velocities()[i].y() << ',' << w.angles()[i] << ','
                     << w.omegas()[i] << '\n';
    }
    // a write refused since the last sample (a full disk) ends the run here, not at its end
    for (SeriesFile* file : {&forces_, &energy_, &front_, &track_}) file->check();
}

// Energy created by the numerics (an unstable step, a disc driven through a wall): the
// ledger's balance stays at its start value e0 in a sound run, so a rise beyond `max_gain`
// times the energy put in is a blow-up in the making. The energy put in is what the run had
// and was given: e0 - the potential + the walls' work (the kinetic and elastic energy at the
// start plus the potential energy released), its largest value so far. Created energy cannot
// inflate it: it depends on the potential alone, bounded by the mass at its lowest, and a
// disc thrown up by an unstable step lowers it (a scale of the peak kinetic energy, as first,
// grew with the energy created and missed a ninefold gain). The largest value, not the
// present one: an undamped disc at the top of its bounce has put in nothing at that instant.
// The centred ledger's error on a contact oscillating near the critical step (20-50 % of the
// contact's energy at 0.4-0.9 of the critical step) stays below the energy that went into it.
//
// `noise` is the ledger's resolution, below which no gain counts: a thousandth of the energy
// that lifts every disc by its radius (a disc resting on a floor from the start has put in
// almost nothing, and its contact's centred-ledger error was measured at 4.5 times that).
//
// Checked every kEnergyWatchSteps steps, and when a step fails (a lost disc, an overlap), so
// that a runaway is named as one: every 100 steps, as first, the check cost 1.3 % of a
// 2-thread flume run (one World::energy() took 225 us on geometry A, more than a step).
double energy_put_in(const EnergyReport& e, double e0) { return e0 - e.potential - e.lost_potential + e.work_by_walls; }

double ledger_noise(const World& w, double gravity) {
    double noise = 0.0;
    for (size_t i = 0; i < w.disc_count(); ++i) noise += 1e-3 * w.masses()[i] * gravity * w.radii()[i];
    return noise;
}

void require_finite_ledger(const EnergyReport& e, long step, double t) {
    if (std::isfinite(e.balance())) return;
    throw RunError("blow-up: the energy ledger is not finite at step " + std::to_string(step) + ", t = " + format_number(t) +
                   " s (kinetic " + format_number(e.kinetic_translation + e.kinetic_rotation) + ", potential " +
                   format_number(e.potential) + ", elastic " + format_number(e.elastic) +
                   " J/m). Likely cause: velocities, forces or gravity too large for double precision");
}

void check_energy_growth(const Solver& w, double e0, double max_gain, double noise, double& peak_put_in,
                         DissipationPeaks& dissipation) {
    const EnergyReport e = w.energy();
    require_finite_ledger(e, w.step_count(), w.time());
    peak_put_in = std::max(peak_put_in, energy_put_in(e, e0));
    const double gain = e.balance() - e0, put_in = peak_put_in;
    // A dissipation account only grows: a damper takes energy out. One that falls is a damper
    // that made energy, an unstable step, even when the ledger closes (the energy made shows as
    // motion, booked on both sides); the drop is measured against the energy put in, so the
    // rounding of the accounts' sums (each step adds to them) never counts.
    const double drop_allowed = kDissipationDrop * std::max(put_in, 0.0) + noise;
    struct Account {
        const char* name;
        double now;
        double& peak;
        const char* cause;
    };
    for (const Account& a :
         {Account{"dissipated_contacts", e.dissipated_contacts, dissipation.contacts,
                  "a time step too large for the damped contacts (the dashpots of an unstable step push instead of "
                  "damping; lagged dashpots, timestep.dashpots = \"lagged\", are unstable at PFC's rule as printed "
                  "with free rotation and a shear dashpot unless timestep.damping_correction is on: docs/engine.md): "
                  "use the centred dashpots (the default) or the damping correction with the automatic step, or a "
                  "smaller timestep.safety or timestep.fixed"},
          Account{"dissipated_local", e.dissipated_local, dissipation.local,
                  "a time step too large for the local damping (damping.local_alpha; the automatic step with "
                  "timestep.damping_correction shrinks it by 1/sqrt(1 + alpha))"},
          Account{"dissipated_rotation", e.dissipated_rotation, dissipation.rotation,
                  "a time step too large for the rotation (rolling resistance, rotational damping: rotation.model, "
                  "rotation.mu_br, rotation.u_rr): use the automatic step with the damping correction, or a smaller "
                  "timestep.safety"}}) {
        if (a.peak - a.now > drop_allowed)
            throw RunError("blow-up: the energy ledger's " + std::string(a.name) + " account fell by " +
                           format_number(a.peak - a.now) + " J/m (from " + format_number(a.peak) + " to " + format_number(a.now) +
                           " J/m" + (put_in > 0 ? ", " + format_number((a.peak - a.now) / put_in) + " times the energy put in" : std::string()) +
                           "): a damper made energy, at step " + std::to_string(w.step_count()) + ", t = " + format_number(w.time()) +
                           " s. Likely cause: " + a.cause);
        a.peak = std::max(a.peak, a.now);
    }
    if (gain > max_gain * std::max(put_in, 0.0) && gain > noise)
        throw RunError("blow-up: energy growth: the energy balance rose by " + format_number(gain) + " J/m, " +
                       (put_in > 0 ? format_number(gain / put_in) + " times the energy put in (" + format_number(put_in) + " J/m"
                                   : std::string("with no energy put in (the mass holds more potential energy than it had")) +
                       "; stop.max_energy_gain = " + format_number(max_gain) + "), at step " + std::to_string(w.step_count()) + ", t = " + format_number(w.time()) +
                       " s. Likely cause: a time step too large for the stiffness "
                       "(use the automatic step or a smaller timestep.safety)");
}

void write_deposit(const World& w, const MeasureContext& m, const std::string& dir, RunSummary& sum) {
    const BedPath& path = *m.path;
    const double bin = m.scenario.output.deposit_bin;
    const size_t n = w.disc_count();
    const auto conn = connected_discs(w.positions(), w.radii(), m.front_gap);
    const int bins = int(std::ceil(path.length() / bin)) + 1;
    std::vector<double> top(size_t(bins), 0.0);
    for (size_t i = 0; i < n; ++i) {
        if (!conn[i]) continue;
        double si, hi_;
        path.project(w.positions()[i], si, hi_);
        sum.runout_s = std::max(sum.runout_s, si + w.radii()[i]);
        const int b = int(std::floor(si / bin + 0.5));
        if (b >= 0 && b < bins) top[size_t(b)] = std::max(top[size_t(b)], hi_ + w.radii()[i]);
        if (si > m.barrier.s_barrier)
            sum.runup_height = std::max(sum.runup_height, w.positions()[i].y() + w.radii()[i] - m.barrier.foot.y());
    }
    std::ostringstream d;
    d << "s_m,height_m\n";
    for (int b = 0; b < bins; ++b) d << b * bin << ',' << top[size_t(b)] << '\n';
    // the deposit's thickest point (normal to the bed) and its length: from its first bin to
    // its last that holds mass, along the path
    int first = -1, last = -1;
    for (int b = 0; b < bins; ++b) {
        sum.deposit_max_height = std::max(sum.deposit_max_height, top[size_t(b)]);
        if (top[size_t(b)] > 0.0) {
            if (first < 0) first = b;
            last = b;
        }
    }
    sum.deposit_length = first < 0 ? 0.0 : double(last - first + 1) * bin;
    write_file_atomic(dir + "/deposit.csv", d.str());
}

void refuse_too_many_deposit_bins(const Scenario& s, double along, double span_x) {
    const double bin = s.output.deposit_bin, longest = std::max(along, span_x);
    if (longest / bin <= kMaxDepositBins) return;
    auto g4 = [](double v) {  // (the figures of a message, to 4 digits)
        char b[32];
        std::snprintf(b, sizeof b, "%.4g", v);
        return std::string(b);
    };
    throw InputError(s.source + ": output.deposit_bin = " + format_number(bin) + " m would cut the bed path (" + g4(along) +
                     " m long" + (span_x > 0.0 ? ", " + g4(span_x) + " m in x" : std::string()) + ") into " + g4(longest / bin) + " bins, more than " +
                     g4(kMaxDepositBins) + ": it must be at least " + g4(longest / kMaxDepositBins) + " m (and at most 10 m)");
}

void write_surface(const World& w, const MeasureContext& m, const std::string& dir, RunSummary& sum) {
    const BedPath& path = *m.path;
    const double dx = m.scenario.output.deposit_bin;
    double x_lo, x_hi;
    path.x_span(x_lo, x_hi);
    const auto conn = connected_discs(w.positions(), w.radii(), m.front_gap);
    // y(x) = max over discs covering x of y_c + sqrt(r^2 - (x - x_c)^2) (geometry/deposit.h),
    // on the grid x_lo + k dx; the last sample at or before x_hi
    write_file_atomic(dir + "/surface.csv", surface_csv(path, upper_envelope(w.positions(), w.radii(), conn, x_lo, x_hi, dx), sum));
}

std::string surface_csv(const BedPath& path, const Envelope& top, RunSummary& sum) {
    std::ostringstream d;
    // 10 digits: a terrain's x and y may be map coordinates (hundreds of kilometres, metres
    // above the sea) whose depths are centimetres
    d.precision(10);
    d << "x_m,bed_m,surface_m,depth_m\n";
    sum.deposit_max_depth = 0.0;
    sum.x_deposit_max_depth = 0.0;
    for (size_t k = 0; k < top.y.size(); ++k) {
        const double x = top.x(k);
        double bed;
        if (!path.height_at(x, bed)) continue;  // (a path with a gap in x: nothing to stand on)
        // where no mass stands the surface is the bed's, 0 deep (as deposit.csv's empty bins)
        const double surface = std::isnan(top.y[k]) ? bed : std::max(top.y[k], bed);
        d << x << ',' << bed << ',' << surface << ',' << surface - bed << '\n';
        if (surface - bed > sum.deposit_max_depth) {
            sum.deposit_max_depth = surface - bed;
            sum.x_deposit_max_depth = x;
        }
    }
    return d.str();
}

SlopeAngles write_envelope(const World& w, double gap, double length, double sections_start, const std::string& dir, RunSummary& sum) {
    const auto conn = connected_discs(w.positions(), w.radii(), gap);
    const Envelope env = upper_envelope(w.positions(), w.radii(), conn, 0.0, length, 0.001);
    const SlopeAngles angles = slope_angles(env, 0.1, 0.0, sections_start);
    sum.runout_s = angles.toe_x;
    // the deposit over the floor: its thickest point and its length from the first sample
    // with mass to the toe (the envelope's, in place of deposit.csv's bins along the floor)
    double first = NAN;
    sum.deposit_max_height = 0.0;
    for (size_t k = 0; k < env.y.size(); ++k)
        if (!std::isnan(env.y[k]) && env.y[k] > 0.0) {
            if (std::isnan(first)) first = env.x(k);
            sum.deposit_max_height = std::max(sum.deposit_max_height, env.y[k]);
            // over the floor (y = 0) the height is the vertical depth
            if (env.y[k] > sum.deposit_max_depth) {
                sum.deposit_max_depth = env.y[k];
                sum.x_deposit_max_depth = env.x(k);
            }
        }
    sum.deposit_length = std::isnan(first) ? 0.0 : std::max(0.0, angles.toe_x - first);
    std::ostringstream d;
    d << "x_m,surface_m\n";
    for (size_t k = 0; k < env.y.size(); ++k)
        if (!std::isnan(env.y[k])) d << env.x(k) << ',' << env.y[k] << '\n';
    write_file_atomic(dir + "/envelope.csv", d.str());
    return angles;
}

void write_bond_breaks(const World& w, const std::string& dir) {
    std::ostringstream o;
    o << "t_s,k,l,strain,energy_J_per_m\n";
    for (const BondBreakEvent& e : w.bond_breaks()) o << e.t << ',' << e.k << ',' << e.l << ',' << e.strain << ',' << e.energy << '\n';
    write_file_atomic(dir + "/bonds_broken.csv", o.str());
}

std::vector<NotMeasured> not_measured(const RunSummary& sum) {
    std::vector<NotMeasured> out;
    auto add = [&](std::initializer_list<const char*> keys, const std::string& reason) {
        for (const char* k : keys) out.push_back({k, reason});
    };
    if (!sum.has_path && !sum.has_envelope)
        add({"runout_s", "deposit_max_height", "deposit_length", "deposit_max_depth", "x_deposit_max_depth"},
            "the set-up has no bed path or floor to measure a deposit along");
    else if (!sum.has_deposit)
        add({"deposit_max_height", "deposit_length"}, "DAN gives the deposit as deposit.csv's depths along the path");
    if (!sum.has_barrier)
        add({"t_front_at_barrier", "runup_height", "max_runup_height_during_run"}, "the set-up has no barrier");
    else if (sum.t_front_at_barrier < 0)
        add({"t_front_at_barrier"}, "the front did not reach the barrier by the end of the run");
    // a wall's load: absent without the wall; its every-step, sampled and filtered peaks each
    // absent when no step, sample or whole window carried a load
    auto load = [&](const std::string& k, bool has, const char* wall, double step, double sampled, double filtered) {
        const std::string peak = "peak_" + k, sampled_peak = peak + "_sampled", filtered_peak = peak + "_filtered";
        auto pair = [&](const std::string& p, const std::string& reason) {
            out.push_back({p, reason});
            out.push_back({"t_" + p, reason});
        };
        if (!has) {
            for (const std::string& p : {peak, sampled_peak, filtered_peak}) pair(p, std::string("the set-up has no ") + wall);
            return;
        }
        if (!(step > 0)) pair(peak, std::string("the ") + wall + " carried no load in any step");
        if (!(sampled > 0)) pair(sampled_peak, std::string("the ") + wall + " carried no load in any sample");
        if (!(filtered > 0)) pair(filtered_peak, std::string("no whole output.load_window with a load on the ") + wall);
    };
    load("fx_barrier", sum.has_barrier_forces, "barrier", sum.peak_fx_barrier, sum.peak_fx_barrier_sampled, sum.peak_fx_barrier_filtered);
    load("fy_arc", sum.has_arc, "arc", sum.peak_fy_arc, sum.peak_fy_arc_sampled, sum.peak_fy_arc_filtered);
    for (const auto& [key, reason] : sum.unmeasured) out.push_back({key, reason});
    return out;
}

std::string not_measured_reason(const RunSummary& sum, const std::string& key) {
    for (const NotMeasured& m : not_measured(sum))
        if (m.key == key) return m.reason;
    return "";
}

void put_landmarks(SummaryJson& j, const RunSummary& sum) {
    auto put = [&](const char* key, double v, const char* unit) {
        j.number(key, not_measured_reason(sum, key).empty() ? v : NAN, unit);
    };
    put("runup_height", sum.runup_height, "m");
    put("max_runup_height_during_run", sum.max_runup_height_during_run, "m");
    put("t_front_at_barrier", sum.t_front_at_barrier, "s");
    put("t_peak_fx_barrier", sum.t_peak_fx_barrier, "s");
    put("t_peak_fy_arc", sum.t_peak_fy_arc, "s");
    put("peak_fx_barrier", sum.peak_fx_barrier, "N/m");
    put("peak_fy_arc", sum.peak_fy_arc, "N/m");
    put("t_peak_fx_barrier_sampled", sum.t_peak_fx_barrier_sampled, "s");
    put("t_peak_fy_arc_sampled", sum.t_peak_fy_arc_sampled, "s");
    put("peak_fx_barrier_sampled", sum.peak_fx_barrier_sampled, "N/m");
    put("peak_fy_arc_sampled", sum.peak_fy_arc_sampled, "N/m");
    put("peak_fx_barrier_filtered", sum.peak_fx_barrier_filtered, "N/m");
    put("t_peak_fx_barrier_filtered", sum.t_peak_fx_barrier_filtered, "s");
    put("peak_fy_arc_filtered", sum.peak_fy_arc_filtered, "N/m");
    put("t_peak_fy_arc_filtered", sum.t_peak_fy_arc_filtered, "s");
    // the design figures (design_loads.h)
    put("static_fx_barrier", sum.static_fx_barrier, "N/m");
    put("static_fy_arc", sum.static_fy_arc, "N/m");
    put("t_barrier_load_steady", sum.t_barrier_load_steady, "s");
    put("impact_ix_barrier", sum.impact_ix_barrier, "N s/m");
    put("t_approach", sum.t_approach, "s");
    put("approach_depth", sum.approach_depth, "m");
    put("approach_speed", sum.approach_speed, "m/s");
    put("approach_mass_per_length", sum.approach_mass_per_length, "kg/m2");
    put("approach_froude", sum.approach_froude, "-");
    put("impact_coefficient_alpha", sum.impact_coefficient_alpha, "-");
    put("static_coefficient_k", sum.static_coefficient_k, "-");
    put("static_bulk_density", sum.static_bulk_density, "kg/m3");
    std::vector<std::pair<std::string, std::string>> reasons;
    for (const NotMeasured& m : not_measured(sum)) reasons.emplace_back(m.key, m.reason);
    j.reasons("not_measured", reasons);
}

void write_lost_discs(const World& w, const std::string& dir) {
    std::ostringstream o;
    o << "t_s,id,x_m,y_m,vx_m_per_s,vy_m_per_s,omega_rad_per_s,mass_kg_per_m,kinetic_J_per_m\n";
    for (const LostDiscEvent& e : w.lost_discs())
        o << e.t << ',' << e.id << ',' << e.pos.x() << ',' << e.pos.y() << ',' << e.vel.x() << ',' << e.vel.y() << ','
          << e.omega << ',' << e.mass << ',' << e.energy << '\n';
    write_file_atomic(dir + "/lost.csv", o.str());
}

namespace {
SummaryJson summary_json(const Scenario& s, const RunSummary& sum, const ReleaseFigures& release, const SlopeAngles* angles) {
    const bool r = release.generated;
    SummaryJson j;
    j.text("scenario", s.name);
    j.text("scenario_fingerprint", sum.scenario_fingerprint);
    j.integer("n_discs", sum.n_discs);
    j.integer("lost_discs", sum.lost_discs);
    j.number("total_mass", sum.total_mass, "kg/m");
    j.number("porosity_over_release_box", sum.porosity_over_release_box, "-");
    j.number("porosity_inside_mass", sum.porosity_inside_mass, "-");
    j.number("release_porosity_generated", r ? release.porosity_generated : NAN, "-");
    j.number("release_settle_time", r ? release.settle_time : NAN, "s");
    j.number("release_settle_ratio", r ? release.settle_ratio : NAN, "-");
    j.number("release_wall_seconds", r ? release.wall_seconds : NAN, "s");
    j.number("dt", sum.dt, "s");
    j.number("dt_min", sum.dt_min, "s");
    j.number("dt_max", sum.dt_max, "s");
    j.integer("steps", sum.steps);
    j.number("t_end", sum.t_end, "s");
    j.text("stop_reason", sum.stop_reason);
    j.number("wall_seconds", sum.wall_seconds, "s");
    j.number("particle_steps_per_second", sum.particle_steps_per_second, "1/s");
    // the machine the timings above come from (a resumed run: the one that finished it)
    j.text("machine", machine_summary(machine_info()));
    auto measured = [&](const char* key, double v) { return not_measured_reason(sum, key).empty() ? v : NAN; };
    j.number("runout_s", measured("runout_s", sum.runout_s), "m");
    j.boolean("runout_lower_bound", sum.runout_lower_bound);
    j.boolean("left_flume", sum.left_flume_discs > 0);
    j.integer("left_flume_discs", sum.left_flume_discs);
    j.number("left_flume_mass", sum.left_flume_mass, "kg/m");
    j.number("t_left_flume", sum.t_left_flume >= 0 ? sum.t_left_flume : NAN, "s");
    j.number("deposit_max_height", measured("deposit_max_height", sum.deposit_max_height), "m");
    j.number("deposit_length", measured("deposit_length", sum.deposit_length), "m");
    j.number("deposit_max_depth", measured("deposit_max_depth", sum.deposit_max_depth), "m");
    j.number("x_deposit_max_depth", measured("x_deposit_max_depth", sum.x_deposit_max_depth), "m");
    put_landmarks(j, sum);
    if (sum.s_peak_barrier_pressure >= 0) {  // a barrier (barrier_pressure.csv)
        j.number("peak_barrier_pressure", sum.peak_barrier_pressure, "Pa");
        j.number("s_peak_barrier_pressure", sum.s_peak_barrier_pressure, "m");
        j.number("t_peak_barrier_pressure", sum.t_peak_barrier_pressure, "s");
        j.number("barrier_pressure_bin", sum.barrier_pressure_bin, "m");
    }
    j.number("energy_balance_error", sum.energy_balance_error, "-");
    j.number("broadphase_margin", sum.broadphase_margin, "m");
    j.integer("broadphase_updates", sum.broadphase_updates);
    j.integer("broadphase_reinserts", sum.broadphase_reinserts);
    j.number("broadphase_mean_candidates", sum.broadphase_mean_candidates, "-");
    j.number("broadphase_mean_touching", sum.broadphase_mean_touching, "-");
    j.number("broadphase_update_seconds", sum.broadphase_update_seconds, "s");
    j.integer("force_pass_one_range_cuts", sum.force_pass_one_range_cuts);
    j.integer("space_orderings", sum.space_orderings);
    j.number("force_pass_busy_share", sum.force_pass_busy_share, "-");
    j.integer("force_pass_busy_fallbacks", sum.force_pass_busy_fallbacks);
    if (sum.bonds >= 0) {
        j.integer("bonds", sum.bonds);
        j.integer("bonds_broken", sum.bonds_broken);
        j.integer("bonds_lost_with_discs", sum.bonds_lost_with_discs);
    }
    if (angles) {
        j.number("gamma_ges", angles->gamma_ges, "deg");
        for (int i = 0; i < 5; ++i) j.number("gamma_" + std::to_string(i + 1), angles->gamma[i], "deg");
        j.number("toe_x", angles->toe_x, "m");
        j.number("surface_at_back_wall", angles->h_wall, "m");
        if (s.dam_break.sections_start > 0.0) j.number("surface_at_sections_start", angles->h_start, "m");
    }
    return j;
}
}  // namespace

void write_summary(const std::string& path, const Scenario& s, const RunSummary& sum, const ReleaseFigures& release,
                   const SlopeAngles* angles) {
    write_file_atomic(path, summary_json(s, sum, release, angles).str());
}

std::vector<std::string> summary_number_keys() {
    // the DEM summary with every optional part: a barrier, bonds, the dam break's angles
    RunSummary sum;
    sum.s_peak_barrier_pressure = 0;
    sum.bonds = 0;
    const SlopeAngles angles{};
    std::vector<std::string> keys = summary_json(Scenario{}, sum, ReleaseFigures{}, &angles).number_keys();
    // and DAN's own (dan_run.cpp)
    for (const char* k : {"blocks", "volume", "max_front_s", "left_flume", "sync_shift", "max_cfl", "momentum_corrected"})
        if (std::find(keys.begin(), keys.end(), k) == keys.end()) keys.push_back(k);
    return keys;
}

}  // namespace demlab
