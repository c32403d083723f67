#include "run/dan_run.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "core/csv.h"
#include "core/error.h"
#include "core/fileio.h"
#include "core/machine.h"
#include "core/output_dir.h"
#include "core/progress.h"
#include "core/validate.h"
#include "dem/world.h"
#include "run/design_loads.h"
#include "run/measures.h"
#include "run/run_folder.h"
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
    w.add_material(s.disc);
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
        const std::vector<std::string> cells = csv_cells(line);
        try {
            if (std::max(ct, cs) >= cells.size()) throw InputError("short row");
            f.t.push_back(std::stod(cells[ct]));
            f.s.push_back(std::stod(cells[cs]));
        } catch (const std::exception&) {
            throw InputError(path + ":" + std::to_string(row) + ": no numbers in its t_s and s_front_m columns");
        }
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

RunSummary run_dan(const Scenario& s, const RunOptions& o) {
    if (o.resume) throw InputError(o.out_dir + ": a DAN run writes no checkpoint to resume (it takes seconds): run it again");
    const DanDef& d = s.dan;
    if (d.phi_basal_deg > d.phi_internal_deg)
        std::fprintf(stderr, "demlab: warning: dan.phi_basal_deg %.4g > dan.phi_internal_deg %.4g: the earth-pressure limits "
                             "(D5) are clamped to 2/cos^2(phi_i) - 1\n", d.phi_basal_deg, d.phi_internal_deg);
    DanSolver dan = dan_of_scenario(s);  // every refusal before the folder is touched
    FrontSeries reference;
    if (!d.sync_front.empty()) reference = read_front(d.sync_front);

    const std::string dir = o.out_dir;
    const std::vector<ScenarioInput> inputs = scenario_inputs(s);
    std::unique_ptr<RunFolderLock> lock;
    open_run_folder(o, resolved_toml(s), inputs, lock, run_inputs(s, o, inputs));
    const auto t0 = std::chrono::steady_clock::now();

    const DanPath& path = dan.path();
    const size_t n = dan.blocks();
    const double s_arc = path.part_start(1), s_barrier = path.part_start(2), length = path.length();
    const Vec2 foot = path.at(s_barrier).p;
    double total_mass = 0.0, volume = 0.0;
    for (double m : dan.mass()) total_mass += m;
    for (double v : dan.volume()) volume += v;
    const double s_front0 = dan.s().back();

    // forces.csv as a DEM flume's (the walls' roles only name its columns here): the samples,
    // the impulses, the gate's zeros, every step's extremes and the filtered loads
    ForceWalls walls;
    walls.slope = {0};
    walls.arc = {1};
    walls.barrier = {2};
    walls.gate = 3;
    ForceExtremes extremes(walls);
    LoadFilter filter(s.output.load_window);
    DesignLoads design(s.output.approach_length);
    std::ostringstream forces, front, energy, blocks;
    forces << forces_header(walls) << '\n';
    front << kDanFrontColumns << '\n';
    energy << kDanEnergyColumns << '\n';
    blocks << kDanBlockColumns << '\n';
    for (auto* o2 : {&forces, &front, &energy, &blocks}) o2->precision(10);

    // each block's bed force split between slope, arc and barrier by the share of its
    // tributary interval on each
    Vec2 load[3], impulse[3] = {Vec2::Zero(), Vec2::Zero(), Vec2::Zero()};
    auto split_loads = [&] {
        for (Vec2& f : load) f = Vec2::Zero();
        const std::vector<double>& S = dan.s();
        for (size_t i = 0; i < n; ++i) {
            const double a = i > 0 ? S[i] - 0.5 * (S[i] - S[i - 1]) : S[i];
            const double b = i + 1 < n ? S[i] + 0.5 * (S[i + 1] - S[i]) : S[i];
            const double edges[4] = {-INFINITY, s_arc, s_barrier, INFINITY};
            if (b <= a) {  // (a single block: all at its point)
                const int part = S[i] < s_arc ? 0 : S[i] < s_barrier ? 1 : 2;
                load[part] += dan.bed_force()[i];
                continue;
            }
            for (int p = 0; p < 3; ++p) {
                const double overlap = std::max(0.0, std::min(b, edges[p + 1]) - std::max(a, edges[p]));
                load[p] += (overlap / (b - a)) * dan.bed_force()[i];
            }
        }
    };
    RunSummary sum;
    sum.n_discs = 0;
    sum.total_mass = total_mass;
    sum.porosity_over_release_box = -1.0;
    // DAN runs on a flume: its path, W3 the barrier, W2 the arc
    sum.has_path = sum.has_barrier = sum.has_barrier_forces = sum.has_arc = true;
    sum.dt = sum.dt_min = sum.dt_max = dan.dt();
    double peak_fx = -1.0, peak_fy = -1.0, t_peak_fx_sampled = -1.0, t_peak_fy_sampled = -1.0, peak_ke = 0.0, rest_since = -1.0, max_front = s_front0;
    bool left_flume = false;
    const DanEnergy e0 = dan.energy();
    const double balance0 = e0.kinetic + e0.potential;
    auto runup_now = [&] {
        double up = 0.0;
        for (size_t i = 0; i < n; ++i) {
            if (dan.s()[i] <= s_barrier) continue;
            const DanPathPoint q = path.at(dan.s()[i]);
            const double top = d.columns == DanColumns::Vertical ? dan.height()[i] / std::cos(q.alpha) : dan.height()[i] * std::cos(q.alpha);
            up = std::max(up, q.p.y() + top - foot.y());
        }
        return up;
    };
    auto sample = [&] {
        const double t = dan.time();
        const Vec2 total = load[0] + load[1] + load[2], itotal = impulse[0] + impulse[1] + impulse[2];
        forces << t;
        for (const Vec2& v : {load[0], load[1], load[2], total, impulse[0], impulse[1], impulse[2], itotal})
            forces << ',' << v.x() << ',' << v.y();
        forces << ",0,0,0,0";
        extremes.step(t, load);  // (this step's too: a row's extremes hold its own sample)
        for (double v : extremes.row()) forces << ',' << v;
        extremes.reset_row();
        for (double v : {filter.fx_barrier, filter.fy_arc}) {
            forces << ',';
            if (std::isfinite(v)) forces << v;
        }
        forces << '\n';
        design.record(t, filter.fx_barrier, impulse[2].x());
        if (std::abs(load[2].x()) > peak_fx) {
            peak_fx = std::abs(load[2].x());
            t_peak_fx_sampled = t;
        }
        if (std::abs(load[1].y()) > peak_fy) {
            peak_fy = std::abs(load[1].y());
            t_peak_fy_sampled = t;
        }
        front << t << ',' << dan.s().back() << ',' << dan.s().back() - s_front0 << ',' << dan.s().front() << ',' << dan.v().back() << '\n';
        const DanEnergy e = dan.energy();
        const double balance = e.kinetic + e.potential + e.dissipated_friction;
        energy << t << ',' << e.kinetic << ',' << e.potential << ',' << e.dissipated_friction << ',' << balance0 - balance << ','
               << balance << '\n';
    };
    auto snapshot = [&] {
        for (size_t i = 0; i < n; ++i) {
            const DanPathPoint q = path.at(dan.s()[i]);
            blocks << dan.time() << ',' << i << ',' << dan.s()[i] << ',' << q.p.x() << ',' << q.p.y() << ',' << dan.v()[i] << ','
                   << dan.height()[i] << ',' << dan.k()[i > 0 ? i - 1 : 0] << '\n';
        }
    };
    split_loads();
    sample();
    if (s.output.snapshot_interval > 0) snapshot();
    double next_series = s.output.series_interval, next_snap = s.output.snapshot_interval;
    Progress progress(s.stop.t_max, "s");
    sum.stop_reason = "t_max";
    while (dan.time() < s.stop.t_max - 1e-12) {
        if (s.stop.max_steps > 0 && dan.step_count() >= s.stop.max_steps) {
            sum.stop_reason = "max_steps";
            break;
        }
        dan.step();
        sum.dt_min = std::min(sum.dt_min, dan.dt());
        sum.dt_max = std::max(sum.dt_max, dan.dt());
        split_loads();
        for (int p = 0; p < 3; ++p) impulse[p] += dan.dt() * load[p];
        const double t = dan.time(), s_front = dan.s().back();
        extremes.step(t, load);
        filter.step(t, impulse[2].x(), impulse[1].y());
        max_front = std::max(max_front, s_front);
        if (s_front > length) left_flume = true;
        if (sum.t_front_at_barrier < 0 && s_front >= s_barrier) {
            sum.t_front_at_barrier = t;
            // the flow that arrives: the last block before the barrier's foot
            size_t i = 0;
            while (i + 1 < n && dan.s()[i + 1] < s_barrier) ++i;
            design.record_approach(t, dan.height()[i], std::abs(dan.v()[i]), d.density * dan.height()[i], 1);
        }
        sum.max_runup_height_during_run = std::max(sum.max_runup_height_during_run, runup_now());
        if (t >= next_series - 1e-12) {
            sample();
            while (next_series <= t + 1e-12) next_series += s.output.series_interval;
        }
        if (s.output.snapshot_interval > 0 && t >= next_snap - 1e-12) {
            snapshot();
            while (next_snap <= t + 1e-12) next_snap += s.output.snapshot_interval;
        }
        const double ke = dan.kinetic_energy();
        peak_ke = std::max(peak_ke, ke);
        if ((dan.step_count() & 255) == 0) progress.update(t, dan.step_count());
        if (peak_ke > 0.0 && ke < s.stop.rest_ke_fraction * peak_ke) {
            if (rest_since < 0) rest_since = t;
            if (t - rest_since >= s.stop.rest_duration) {
                sum.stop_reason = "rest";
                break;
            }
        } else {
            rest_since = -1.0;
        }
    }
    progress.finish();
    if (std::abs(dan.time() - (next_series - s.output.series_interval)) > 1e-12) sample();  // the last state, once
    sum.t_end = dan.time();
    sum.steps = dan.step_count();
    sum.dt = dan.dt();
    sum.runout_s = dan.s().back();
    sum.runup_height = runup_now();
    // the peaks of every step, of the samples, and filtered (as a DEM run's)
    sum.peak_fx_barrier_sampled = std::max(0.0, peak_fx);
    sum.peak_fy_arc_sampled = std::max(0.0, peak_fy);
    sum.t_peak_fx_barrier_sampled = t_peak_fx_sampled;
    sum.t_peak_fy_arc_sampled = t_peak_fy_sampled;
    sum.peak_fx_barrier = extremes.peak_fx_barrier;
    sum.t_peak_fx_barrier = extremes.t_peak_fx_barrier;
    sum.peak_fy_arc = extremes.peak_fy_arc;
    sum.t_peak_fy_arc = extremes.t_peak_fy_arc;
    sum.peak_fx_barrier_filtered = filter.peak_fx_barrier;
    sum.t_peak_fx_barrier_filtered = filter.t_peak_fx_barrier;
    sum.peak_fy_arc_filtered = filter.peak_fy_arc;
    sum.t_peak_fy_arc_filtered = filter.t_peak_fy_arc;
    design.finish(filter, sum, d.density, s.world.gravity.norm());
    sum.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    sum.particle_steps_per_second = double(n) * double(sum.steps) / std::max(sum.wall_seconds, 1e-9);

    // the deposit: H between the boundary blocks, 0 outside, and the holding block's h
    std::ostringstream dep;
    dep.precision(10);
    dep << "s_m,height_m,block_height_m\n";
    const double bin = s.output.deposit_bin;
    const int bins = int(std::ceil(length / bin)) + 1;
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

    // front_synced.csv: DAN's front shifted in time to meet the reference at dan.sync_time
    double sync_shift = NAN;
    if (!reference.t.empty()) {
        const double target = value_at(reference.t, reference.s, d.sync_time);
        std::vector<double> ft, fs;
        std::istringstream rows(front.str());
        std::string line;
        std::getline(rows, line);
        std::vector<std::string> lines;
        while (std::getline(rows, line)) {
            lines.push_back(line);
            std::istringstream c(line);
            std::string a, b;
            std::getline(c, a, ',');
            std::getline(c, b, ',');
            ft.push_back(std::stod(a));
            fs.push_back(std::stod(b));
        }
        const double t_dan = first_time_at(ft, fs, target);
        if (std::isfinite(t_dan)) {
            sync_shift = d.sync_time - t_dan;
            std::ostringstream synced;
            synced.precision(10);
            synced << kDanFrontColumns << '\n';
            for (size_t k = 0; k < lines.size(); ++k) synced << ft[k] + sync_shift << lines[k].substr(lines[k].find(',')) << '\n';
            write_file_atomic(dir + "/front_synced.csv", synced.str());
        } else {
            std::fprintf(stderr, "demlab: warning: the DAN front never reached the reference's s = %.4g m at %.4g s: no "
                                 "front_synced.csv\n", target, d.sync_time);
        }
    }

    write_file_atomic(dir + "/forces.csv", forces.str());
    write_file_atomic(dir + "/front.csv", front.str());
    write_file_atomic(dir + "/energy.csv", energy.str());
    if (s.output.snapshot_interval > 0) write_file_atomic(dir + "/blocks.csv", blocks.str());
    write_file_atomic(dir + "/deposit.csv", dep.str());
    SummaryJson j;
    j.text("scenario", s.name);
    j.text("scenario_fingerprint", scenario_fingerprint(s, inputs));  // what a sweep's reuse compares
    j.text("model", "dan");
    j.integer("blocks", long(n));
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
    j.number("max_front_s", max_front, "m");
    put_landmarks(j, sum);  // the DEM's landmark keys, for `demlab compare`
    sum.runout_lower_bound = left_flume;
    j.boolean("left_flume", left_flume);
    j.boolean("runout_lower_bound", left_flume);  // (the front passed the flume's end: as a DEM run says it)
    j.number("sync_shift", sync_shift, "s");
    j.number("max_cfl", dan.max_cfl(), "-");
    j.number("momentum_corrected", dan.momentum_corrected(), "kg/s");  // momentum per metre of width
    j.text("note", "DAN releases the mass at once: release.variant (the gate) does not apply");
    write_file_atomic(dir + "/summary.json", j.str());
    lock->release_and_remove();
    remove_replaced_output(dir);  // a forced run's old folder, now that the new one is complete
    return sum;
}

}  // namespace demlab
