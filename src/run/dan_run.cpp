#include "run/dan_run.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/csv.h"
#include "core/error.h"
#include "core/fileio.h"
#include "core/interrupt.h"
#include "core/machine.h"
#include "core/output_dir.h"
#include "core/progress.h"
#include "core/validate.h"
#include "dem/world.h"
#include "run/design_loads.h"
#include "run/measures.h"
#include "run/checkpoint_file.h"
#include "run/run_folder.h"
#include "run/run_loop.h"
#include "run/solver.h"
#include "run/series_columns.h"
#include "run/summary_file.h"
#include "setups/flume.h"
#include "setups/setup.h"

namespace demlab {

namespace {

}  // namespace

DanPath flume_dan_path(const Scenario& s) {
    const std::unique_ptr<Setup> setup = make_setup(s);
    WorldDef def = s.world;
    def.threads = 1;
    World w(def);
    for (const MaterialDef& m : scenario_materials(s)) w.add_material(m);
    const std::vector<WallDef> walls = setup->walls();
    for (int k = 0; k <= kW3; ++k) w.add_wall(walls[size_t(k)]);
    // one disc far above the slope's start, so the world finalizes; it takes no part
    w.add_disc({walls[kW1].p0 + Vec2(0.0, 10.0), 0.001, Vec2::Zero(), 0.0, 0.0, 0});
    w.finalize();
    return DanPath(*setup->bed_path(w), s.dan.curvature_window);
}

namespace {

// s on the path of a point of a front.csv (t, s_front, ...) at time t, interpolated linearly
struct FrontSeries {
    std::vector<double> t, s;
};
FrontSeries read_front(const std::string& path) {
    FrontSeries f;
    std::istringstream in(read_input_file(path, kMaxScenarioBytes * 4, "reference front"));
    std::string line;
    std::getline(in, line);
    const CsvHeader header(line, path);
    const size_t ct = header.column("t_s", "t"), cs = header.column("s_front_m", "s_front");
    long row = 1;
    while (std::getline(in, line)) {
        ++row;
        if (line.empty()) continue;
        std::vector<std::string> cells = csv_cells(line);
        while (cells.size() > header.names().size() && cells.back().empty()) cells.pop_back();  // trailing commas
        const std::string at = path + ":" + std::to_string(row);
        if (cells.size() != header.names().size())
            throw InputError(at + ": " + std::to_string(cells.size()) + " cells, the header has " +
                             std::to_string(header.names().size()));
        f.t.push_back(parse_number_cell(cells[ct], at));
        f.s.push_back(parse_number_cell(cells[cs], at));
        if (!std::isfinite(f.t.back()) || !std::isfinite(f.s.back()))
            throw InputError(path + ":" + std::to_string(row) + ": its t_s and s_front_m must be finite numbers");
        if (f.t.size() > 1 && !(f.t.back() > f.t[f.t.size() - 2]))
            throw InputError(path + ":" + std::to_string(row) + ": t_s must grow from row to row");
    }
    if (f.t.size() < 2) throw InputError(path + ": fewer than two rows");
    return f;
}
double value_at(const std::vector<double>& x, const std::vector<double>& y, double at) {
    if (at <= x.front()) return y.front();
    for (size_t k = 1; k < x.size(); ++k)
        if (x[k] >= at) return y[k - 1] + (y[k] - y[k - 1]) * (at - x[k - 1]) / (x[k] - x[k - 1]);
    return y.back();
}
// The reference's s at dan.sync_time (NaN without dan.sync_front), read once before the run:
// a reference that does not reach dan.sync_time is refused, not extended by its last value.
double sync_target(const DanDef& d) {
    if (d.sync_front.empty()) return NAN;
    const FrontSeries reference = read_front(d.sync_front);
    if (d.sync_time < reference.t.front() || d.sync_time > reference.t.back())
        throw InputError(d.sync_front + ": the reference front covers t = " + format_number(reference.t.front()) + " to " +
                         format_number(reference.t.back()) + " s, not dan.sync_time = " + format_number(d.sync_time) +
                         " s: give a reference that does, or another dan.sync_time");
    return value_at(reference.t, reference.s, d.sync_time);
}
// the first time the series reaches s (linear between samples); NaN if never
double first_time_at(const std::vector<double>& t, const std::vector<double>& s, double target) {
    if (s.front() >= target) return t.front();
    for (size_t k = 1; k < s.size(); ++k)
        if (s[k] >= target) return t[k - 1] + (t[k] - t[k - 1]) * (target - s[k - 1]) / (s[k] - s[k - 1]);
    return NAN;
}
}  // namespace

DanSolver dan_of_scenario(const Scenario& s) {
    DanPath path = flume_dan_path(s);
    refuse_too_many_deposit_bins(s, path.length(), 0.0);  // (deposit.csv along the path)
    const DanDef& d = s.dan;
    if (d.columns == DanColumns::Vertical && !path.x_increasing(-d.path_extension, path.length() + d.path_extension, 0.05))
        throw InputError(s.source + ": dan.columns = \"vertical\" needs a path whose x increases everywhere (cos alpha >= "
                         "0.05); this flume's is steeper: use dan.columns = \"normal\"");
    const DanInitial init = dan_release(d, path, release_box(s).polygon);
    DanSolver solver(d, std::move(path), s.world.gravity, init);
    if (d.dt_mode == DanStep::Fixed && solver.cfl_now() > d.cfl_max)
        throw InputError(s.source + ": dan.dt = " + format_number(d.dt) + " s is beyond the stability limit at the start (CFL " +
                         format_number(solver.cfl_now()) + " > dan.cfl_max = " + format_number(d.cfl_max) +
                         "): lower dan.dt, or dan.dt_mode = \"auto\"");
    return solver;
}

// surface.csv of a DAN run, the DEM's columns: the free surface is the boundary blocks' points
// p(S_k) + H_k n(S_k) (the heights are normal to the bed in both column modes), joined by
// straight lines; over x its upper envelope, every `dx` over the path's span, above the bed's
// height there. Over the concave arc the normals converge and the line may fold back; the
// envelope takes its top. Its deepest sample into sum.
std::string dan_surface(const DanSolver& dan, double dx, RunSummary& sum) {
    const BedPath& bed_path = dan.path().bed();
    double x_lo, x_hi;
    bed_path.x_span(x_lo, x_hi);
    std::vector<Vec2> points;
    for (size_t k = 0; k < dan.blocks(); ++k) {
        const DanPathPoint q = dan.path().at(dan.s()[k]);
        points.push_back(q.p + dan.height()[k] * q.normal());
    }
    return surface_csv(bed_path, upper_envelope(points, x_lo, x_hi, dx), sum);
}

namespace {

// DAN's blocks span its width B (dan.width); its outputs are per metre of it, as a PFC2D run's
// (B = 1 m by default, where the division changes no bit).
DanEnergy per_metre(DanEnergy e, double width) {
    e.kinetic /= width;
    e.potential /= width;
    e.dissipated_friction /= width;
    return e;
}

// DAN as the run loop's solver; its ledger in the DEM's terms: the kinetic energy, the
// potential, and the basal and internal friction's dissipation in dissipated_contacts.
class DanLoopSolver final : public Solver {
public:
    explicit DanLoopSolver(DanSolver& dan) : dan_(dan) {}
    void step() override { dan_.step(); }
    double time() const override { return dan_.time(); }
    double dt() const override { return dan_.dt(); }
    long step_count() const override { return dan_.step_count(); }
    double kinetic_energy() const override { return dan_.kinetic_energy() / dan_.def().width; }
    EnergyReport energy() const override {
        const DanEnergy e = per_metre(dan_.energy(), dan_.def().width);
        EnergyReport r;
        r.kinetic_translation = e.kinetic;
        r.potential = e.potential;
        r.dissipated_contacts = e.dissipated_friction;
        return r;
    }
    void save_state(BinaryWriter& out) const override { dan_.save_state(out); }
    void load_state(BinaryReader& in) override { dan_.load_state(in); }

private:
    DanSolver& dan_;
};

// A DAN run's measures and files, the parts the run loop calls: the walls' loads (each block's
// bed force split between slope, arc and barrier by the share of its tributary interval on
// each), forces.csv as a DEM flume's, front.csv, energy.csv, the blocks at each snapshot
// (blocks.csv), the front's arrival and the run-up.
class DanRun {
public:
    DanRun(const Scenario& s, DanSolver& dan, const std::string& dir)
        : s_(s), dan_(dan), dir_(dir), n_(dan.blocks()), s_arc_(dan.path().part_start(1)),
          s_barrier_(dan.path().part_start(2)), foot_(dan.path().at(s_barrier_).p), s_front0_(dan.s().back()),
          extremes_(walls()), filter_(s.output.load_window), design_(s.output.approach_length), sync_target_(sync_target(s.dan)) {
        const DanEnergy e0 = per_metre(dan.energy(), s.dan.width);
        balance0_ = e0.kinetic + e0.potential;
        max_front_ = s_front0_;
        split_loads();
    }
    static ForceWalls walls() {
        // (the walls' roles only name forces.csv's columns here)
        ForceWalls w;
        w.slope = {0};
        w.arc = {1};
        w.barrier = {2};
        w.gate = 3;
        return w;
    }
    void open() {
        forces_.open(dir_ + "/forces.csv");
        forces_.out() << forces_header(walls()) << '\n';
        front_.open(dir_ + "/front.csv");
        front_.out() << kDanFrontColumns << '\n';
        energy_.open(dir_ + "/energy.csv");
        energy_.out() << kDanEnergyColumns << '\n';
        if (s_.output.snapshot_interval > 0) {
            blocks_.open(dir_ + "/blocks.csv");
            blocks_.out() << kDanBlockColumns << '\n';
        }
    }
    void sample();
    void snapshot();
    std::string after_step();
    // the run's state after the loop's clock in a checkpoint, and back
    void save(BinaryWriter& out, double elapsed);
    void load(BinaryReader& in, double& elapsed);
    // the files and the summary of the finished run
    RunSummary finish(const std::vector<ScenarioInput>& inputs, double wall_seconds);
    double next_series = 0, next_snap = 0, peak_ke = 0, rest_since = -1;
    RunSummary sum;

private:
    void split_loads();
    double runup_now() const;
    const Scenario& s_;
    DanSolver& dan_;
    std::string dir_;
    size_t n_;
    double s_arc_, s_barrier_;
    Vec2 foot_;
    double s_front0_, balance0_ = 0, max_front_ = 0;
    Vec2 load_[3], impulse_[3] = {Vec2::Zero(), Vec2::Zero(), Vec2::Zero()};
    double peak_fx_ = -1, peak_fy_ = -1, t_peak_fx_ = -1, t_peak_fy_ = -1;
    bool left_flume_ = false;
    ForceExtremes extremes_;
    LoadFilter filter_;
    DesignLoads design_;
    double sync_target_;  // the reference front's s at dan.sync_time (read once, before the run)
    SeriesFile forces_, front_, energy_, blocks_;
};

void DanRun::split_loads() {
    for (Vec2& f : load_) f = Vec2::Zero();
    const std::vector<double>& S = dan_.s();
    const double edges[4] = {-INFINITY, s_arc_, s_barrier_, INFINITY};
    for (size_t i = 0; i < n_; ++i) {
        const double a = i > 0 ? S[i] - 0.5 * (S[i] - S[i - 1]) : S[i];
        const double b = i + 1 < n_ ? S[i] + 0.5 * (S[i + 1] - S[i]) : S[i];
        if (b <= a) {  // (a single block: all at its point)
            const int part = S[i] < s_arc_ ? 0 : S[i] < s_barrier_ ? 1 : 2;
            load_[part] += dan_.bed_force()[i] / s_.dan.width;
            continue;
        }
        for (int p = 0; p < 3; ++p) {
            const double overlap = std::max(0.0, std::min(b, edges[p + 1]) - std::max(a, edges[p]));
            load_[p] += (overlap / (b - a)) * dan_.bed_force()[i] / s_.dan.width;
        }
    }
}

// The run-up: the highest point of the flow's surface over the barrier (the column top, or the
// bed-normal depth's top with "normal" columns), on the surface the blocks' heights draw
// between them, from the barrier's foot on. On the barrier (a segment) that surface is linear
// between the blocks, so its highest point is at a block or at the foot, where it is
// interpolated between the two blocks either side. The blocks past the foot alone would make
// it depend on how far past the foot the first block lies: on a steep barrier H falls fast
// there (C, 61 deg: about 1 m/m, doubled by the column's 1/cos alpha), and that gap changes
// with every refinement.
double DanRun::runup_now() const {
    const std::vector<double>& S = dan_.s();
    const std::vector<double>& H = dan_.height();
    auto top = [&](double s, double height) {
        const DanPathPoint q = dan_.path().at(s);
        const double c = std::cos(q.alpha);
        return q.p.y() + (s_.dan.columns == DanColumns::Vertical ? height / c : height * c) - foot_.y();
    };
    double up = 0.0;
    if (S.front() < s_barrier_ && S.back() > s_barrier_) {
        const size_t j = size_t(std::upper_bound(S.begin(), S.end(), s_barrier_) - S.begin()) - 1;  // S_j <= foot < S_j+1
        const double u = (s_barrier_ - S[j]) / (S[j + 1] - S[j]);
        up = top(s_barrier_, H[j] + u * (H[j + 1] - H[j]));
    }
    for (size_t i = 0; i < n_; ++i)
        if (S[i] > s_barrier_) up = std::max(up, top(S[i], H[i]));
    return up;
}

void DanRun::sample() {
    const double t = dan_.time();
    const Vec2 total = load_[0] + load_[1] + load_[2], itotal = impulse_[0] + impulse_[1] + impulse_[2];
    std::ostream& fo = forces_.out();
    fo << t;
    for (const Vec2& v : {load_[0], load_[1], load_[2], total, impulse_[0], impulse_[1], impulse_[2], itotal}) fo << ',' << v.x() << ',' << v.y();
    fo << ",0,0,0,0";
    extremes_.step(t, load_);  // (this step's too: a row's extremes hold its own sample)
    for (double v : extremes_.row()) fo << ',' << v;
    extremes_.reset_row();
    for (double v : {filter_.fx_barrier, filter_.fy_arc}) {
        fo << ',';
        if (std::isfinite(v)) fo << v;
    }
    fo << '\n';
    design_.record(t, filter_.fx_barrier, impulse_[2].x());
    if (std::abs(load_[2].x()) > peak_fx_) {
        peak_fx_ = std::abs(load_[2].x());
        t_peak_fx_ = t;
    }
    if (std::abs(load_[1].y()) > peak_fy_) {
        peak_fy_ = std::abs(load_[1].y());
        t_peak_fy_ = t;
    }
    front_.out() << t << ',' << dan_.s().back() << ',' << dan_.s().back() - s_front0_ << ',' << dan_.s().front() << ','
                 << dan_.v().back() << '\n';
    const DanEnergy e = per_metre(dan_.energy(), s_.dan.width);
    const double balance = e.kinetic + e.potential + e.dissipated_friction;
    energy_.out() << t << ',' << e.kinetic << ',' << e.potential << ',' << e.dissipated_friction << ',' << balance0_ - balance << ','
                  << balance << '\n';
    for (SeriesFile* f : {&forces_, &front_, &energy_}) f->check();
}

void DanRun::snapshot() {
    for (size_t i = 0; i < n_; ++i) {
        const DanPathPoint q = dan_.path().at(dan_.s()[i]);
        blocks_.out() << dan_.time() << ',' << i << ',' << dan_.s()[i] << ',' << q.p.x() << ',' << q.p.y() << ',' << dan_.v()[i]
                      << ',' << dan_.height()[i] << ',' << dan_.k()[i > 0 ? i - 1 : 0] << '\n';
    }
    blocks_.check();
}

std::string DanRun::after_step() {
    sum.dt_min = std::min(sum.dt_min, dan_.dt());
    sum.dt_max = std::max(sum.dt_max, dan_.dt());
    split_loads();
    for (int p = 0; p < 3; ++p) impulse_[p] += dan_.dt() * load_[p];
    const double t = dan_.time(), s_front = dan_.s().back();
    extremes_.step(t, load_);
    filter_.step(t, impulse_[2].x(), impulse_[1].y());
    max_front_ = std::max(max_front_, s_front);
    if (s_front > dan_.path().length()) left_flume_ = true;
    if (sum.t_front_at_barrier < 0 && s_front >= s_barrier_) {
        sum.t_front_at_barrier = t;
        // the flow that arrives: the last block before the barrier's foot
        size_t i = 0;
        while (i + 1 < n_ && dan_.s()[i + 1] < s_barrier_) ++i;
        design_.record_approach(t, dan_.height()[i], std::abs(dan_.v()[i]), s_.dan.density * dan_.height()[i], 1);
    }
    sum.max_runup_height_during_run = std::max(sum.max_runup_height_during_run, runup_now());
    return "";
}

void DanRun::save(BinaryWriter& out, double elapsed) {
    for (double v : {next_series, next_snap, peak_ke, rest_since, balance0_, max_front_, peak_fx_, peak_fy_, t_peak_fx_, t_peak_fy_,
                     left_flume_ ? 1.0 : 0.0, sum.t_front_at_barrier, sum.max_runup_height_during_run, sum.dt_min, sum.dt_max, elapsed})
        out.put(v);
    for (const Vec2& v : load_) out.put(v);
    for (const Vec2& v : impulse_) out.put(v);
    for (SeriesFile* f : {&forces_, &front_, &energy_, &blocks_}) out.put(f->flush());
    dan_.save_state(out);
    extremes_.save(out);
    filter_.save(out);
    design_.save(out);
}

void DanRun::load(BinaryReader& in, double& elapsed) {
    double left = 0;
    for (double* v : {&next_series, &next_snap, &peak_ke, &rest_since, &balance0_, &max_front_, &peak_fx_, &peak_fy_, &t_peak_fx_,
                      &t_peak_fy_, &left, &sum.t_front_at_barrier, &sum.max_runup_height_during_run, &sum.dt_min, &sum.dt_max, &elapsed})
        in.get(*v);
    left_flume_ = left != 0.0;
    for (Vec2& v : load_) in.get(v);
    for (Vec2& v : impulse_) in.get(v);
    uint64_t size[4];
    for (uint64_t& z : size) in.get(z);
    forces_.reopen(dir_ + "/forces.csv", size[0]);
    front_.reopen(dir_ + "/front.csv", size[1]);
    energy_.reopen(dir_ + "/energy.csv", size[2]);
    if (s_.output.snapshot_interval > 0) blocks_.reopen(dir_ + "/blocks.csv", size[3]);
    dan_.load_state(in);
    extremes_.load(in);
    filter_.load(in);
    design_.load(in);
    if (!in.at_end()) throw InputError(dir_ + "/" + kCheckpointFile + ": corrupt checkpoint (trailing bytes)");
}

// the deposit: H between the boundary blocks, 0 outside, and the holding block's h
std::string dan_deposit(const DanSolver& dan, double bin) {
    std::ostringstream dep;
    dep.precision(10);
    dep << "s_m,height_m,block_height_m\n";
    const size_t n = dan.blocks();
    const int bins = int(std::ceil(dan.path().length() / bin)) + 1;
    const std::vector<double>& S = dan.s();
    for (int b = 0; b < bins; ++b) {
        const double at = b * bin;
        double height = 0.0, block = 0.0;
        if (at >= S.front() && at <= S.back()) {
            size_t j = size_t(std::upper_bound(S.begin(), S.end(), at) - S.begin());
            j = std::min(std::max<size_t>(j, 1), n - 1) - 1;  // the block holding the bin: [S_j, S_j+1]
            const double u = (at - S[j]) / (S[j + 1] - S[j]);
            height = dan.height()[j] + u * (dan.height()[j + 1] - dan.height()[j]);
            block = dan.h()[j];
        }
        dep << at << ',' << height << ',' << block << '\n';
    }
    return dep.str();
}

// front_synced.csv: DAN's front shifted in time to meet the reference at dan.sync_time; the
// shift (NaN: none)
double write_synced_front(const DanDef& d, double target, const std::string& dir) {
    if (d.sync_front.empty()) return NAN;
    std::vector<double> ft, fs;
    std::istringstream rows(read_whole(dir + "/front.csv"));
    std::string line;
    std::getline(rows, line);
    std::vector<std::string> lines;
    while (std::getline(rows, line)) {
        lines.push_back(line);
        const std::vector<std::string> c = csv_cells(line);
        ft.push_back(std::stod(c.at(0)));
        fs.push_back(std::stod(c.at(1)));
    }
    const double t_dan = first_time_at(ft, fs, target);
    if (!std::isfinite(t_dan)) {
        std::fprintf(stderr, "demlab: warning: the DAN front never reached the reference's s = %.4g m at %.4g s: no "
                             "front_synced.csv\n", target, d.sync_time);
        return NAN;
    }
    const double shift = d.sync_time - t_dan;
    std::ostringstream synced;
    synced.precision(10);
    synced << kDanFrontColumns << '\n';
    for (size_t k = 0; k < lines.size(); ++k) synced << ft[k] + shift << lines[k].substr(lines[k].find(',')) << '\n';
    write_file_atomic(dir + "/front_synced.csv", synced.str());
    return shift;
}

RunSummary DanRun::finish(const std::vector<ScenarioInput>& inputs, double wall_seconds) {
    const DanDef& d = s_.dan;
    for (SeriesFile* f : {&forces_, &front_, &energy_, &blocks_}) f->close();
    double total_mass = 0.0, volume = 0.0;
    for (double m : dan_.mass()) total_mass += m;
    for (double v : dan_.volume()) volume += v;
    total_mass /= d.width;  // per metre of width, as the loads
    volume /= d.width;
    sum.total_mass = total_mass;
    sum.t_end = dan_.time();
    sum.steps = dan_.step_count();
    sum.dt = dan_.dt();
    sum.runout_s = dan_.s().back();
    sum.runup_height = runup_now();
    // the peaks of every step, of the samples, and filtered (as a DEM run's)
    sum.peak_fx_barrier_sampled = std::max(0.0, peak_fx_);
    sum.peak_fy_arc_sampled = std::max(0.0, peak_fy_);
    sum.t_peak_fx_barrier_sampled = t_peak_fx_;
    sum.t_peak_fy_arc_sampled = t_peak_fy_;
    take_load_peaks(sum, extremes_, filter_);
    design_.finish(filter_, sum, d.density, s_.world.gravity.norm());
    sum.wall_seconds = wall_seconds;
    sum.particle_steps_per_second = double(n_) * double(sum.steps) / std::max(sum.wall_seconds, 1e-9);
    write_file_atomic(dir_ + "/deposit.csv", dan_deposit(dan_, s_.output.deposit_bin));
    write_file_atomic(dir_ + "/surface.csv", dan_surface(dan_, s_.output.deposit_bin, sum));
    const double sync_shift = write_synced_front(d, sync_target_, dir_);
    SummaryJson j;
    j.text("scenario", s_.name);
    j.text("scenario_fingerprint", scenario_fingerprint(s_, inputs));  // what a sweep's reuse compares
    j.text("model", "dan");
    j.integer("blocks", long(n_));
    j.text("columns", d.columns == DanColumns::Vertical ? "vertical" : "normal");
    j.number("volume", volume, "m2");
    j.number("total_mass", total_mass, "kg/m");
    j.number("dt", sum.dt, "s");
    j.number("dt_min", sum.dt_min, "s");
    j.number("dt_max", sum.dt_max, "s");
    j.integer("steps", sum.steps);
    j.number("t_end", sum.t_end, "s");
    j.text("stop_reason", sum.stop_reason);
    j.number("wall_seconds", sum.wall_seconds, "s");
    j.text("machine", machine_summary(machine_info()));
    j.number("runout_s", sum.runout_s, "m");
    j.number("max_front_s", max_front_, "m");
    j.number("deposit_max_depth", sum.deposit_max_depth, "m");  // (surface.csv, as a DEM run's)
    j.number("x_deposit_max_depth", sum.x_deposit_max_depth, "m");
    put_landmarks(j, sum);  // the DEM's landmark keys, for `demlab compare`
    sum.runout_lower_bound = left_flume_;
    j.boolean("left_flume", left_flume_);
    j.boolean("runout_lower_bound", left_flume_);  // (the front passed the flume's end: as a DEM run says it)
    j.number("sync_shift", sync_shift, "s");
    j.number("max_cfl", dan_.max_cfl(), "-");
    j.number("momentum_corrected", dan_.momentum_corrected() / d.width, "kg/s");  // momentum per metre of width
    j.text("note", "DAN releases the mass at once: release.variant (the gate) does not apply");
    write_file_atomic(dir_ + "/summary.json", j.str());
    return sum;
}

// DAN's run as the loop takes it (run_scenario): the solver at t = 0, the loop's view of it,
// and its measures and files.
class DanSolverRun final : public SolverRun {
public:
    DanSolverRun(const Scenario& s, const RunOptions& o, DanSolver dan)
        : s_(s), dir_(o.out_dir), dan_(std::move(dan)), solver_(dan_), run_(s, dan_, dir_) {
        run_.sum.n_discs = 0;
        run_.sum.porosity_over_release_box = -1.0;
        // DAN runs on a flume: its path, W3 the barrier, W2 the arc
        run_.sum.has_path = run_.sum.has_barrier = run_.sum.has_barrier_forces = run_.sum.has_arc = true;
        run_.sum.dt = run_.sum.dt_min = run_.sum.dt_max = dan_.dt();
    }
    Solver& solver() override { return solver_; }
    RunParts parts(const RunOptions& o) override {
        RunParts parts;
        parts.sample = [this] { run_.sample(); };
        if (s_.output.snapshot_interval > 0)
            parts.snapshot = [this, on_snapshot = o.on_snapshot] {
                run_.snapshot();
                if (on_snapshot) on_snapshot(dir_ + "/blocks.csv.part", "", int(std::lround(dan_.time() / s_.output.snapshot_interval)));
            };
        parts.after_step = [this] { return run_.after_step(); };
        return parts;
    }
    LoopClock clock() override { return LoopClock{run_.next_series, run_.next_snap, run_.peak_ke, run_.rest_since}; }
    void open() override { run_.open(); }
    void save(BinaryWriter& out, double elapsed) override { run_.save(out, elapsed); }
    void load(BinaryReader& in, double& elapsed) override { run_.load(in, elapsed); }
    RunSummary finish(const std::string& stop_reason, const std::vector<ScenarioInput>& inputs, double wall_seconds) override {
        run_.sum.stop_reason = stop_reason;
        return run_.finish(inputs, wall_seconds);
    }

private:
    const Scenario& s_;
    std::string dir_;
    DanSolver dan_;
    DanLoopSolver solver_;
    DanRun run_;
};

}  // namespace

std::unique_ptr<SolverRun> make_dan_run(const Scenario& s, const RunOptions& o) {
    const DanDef& d = s.dan;
    if (d.phi_basal_deg > d.phi_internal_deg)
        std::fprintf(stderr, "demlab: warning: dan.phi_basal_deg %.4g > dan.phi_internal_deg %.4g: the earth-pressure limits "
                             "(D5) are clamped to 2/cos^2(phi_i) - 1\n", d.phi_basal_deg, d.phi_internal_deg);
    DanSolver dan = dan_of_scenario(s);  // every refusal before the folder is touched
    // the automatic step at t = 0 already below the floor choose_step refuses (1e-4 dan.dt):
    // a dan.cfl_max too small for any run, refused here rather than at the first step
    if (d.dt_mode == DanStep::Auto && d.cfl_max < 1e-4 * dan.cfl_now())
        throw InputError(s.source + ": dan.cfl_max = " + format_number(d.cfl_max) + " gives a step of " +
                         format_number(d.dt * d.cfl_max / dan.cfl_now()) + " s at t = 0, below 1e-4 of dan.dt = " +
                         format_number(d.dt) + " s: raise dan.cfl_max (0.5 by default), or use fewer dan.blocks");
    return std::make_unique<DanSolverRun>(s, o, std::move(dan));
}

}  // namespace demlab
