// The run loop (run_scenario): a scenario's world from its set-up and release mass, stepped
// to rest or t_max with the measurements sampled on their intervals, checkpoints on a timer
// and on a signal, and the run folder's files at the end (run.h lists them).
#include "run/run.h"

#include "geometry/packing.h"
#include "run/barrier_outputs.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "core/error.h"
#include "core/fileio.h"
#include "core/interrupt.h"
#include "core/output_dir.h"
#include "core/progress.h"
#include "core/validate.h"
#include "dem/world.h"
#include "run/checkpoint_file.h"
#include "run/dan_run.h"
#include "dem3/dem3_run.h"
#include "run/design_loads.h"
#include "run/force_history.h"
#include "run/measures.h"
#include "run/run_folder.h"
#include "run/run_loop.h"
#include "run/snapshot.h"
#include "run/solver.h"
#include "setups/lattice_release.h"
#include "setups/release.h"
#include "setups/setup.h"

namespace demlab {

namespace {

// The release mass: restored from a checkpoint (the discs as they were at the start), read
// from a saved mass (release.from_file), or generated, in space order (the caller saves it to
// release.csv once the run folder exists).
ReleaseMass start_mass(const Scenario& s, const Setup& setup, BinaryReader* restore, const std::string& dir, bool terminal) {
    ReleaseMass mass;
    if (restore) {
        // the discs as they were at the start (their motion is restored with the world)
        restore->get(mass.pos);
        restore->get(mass.radius, mass.pos.size());
        restore->get(mass.layer, mass.pos.size());
        restore->get(mass.grid, mass.pos.size());
        restore->get(mass.porosity_settled);
        restore->get(mass.porosity_generated);
        restore->get(mass.settle_time);
        restore->get(mass.wall_seconds);
        // the ratio the settling reached, from the run's own release.csv (not in the checkpoint)
        if (setup.has_release() && std::filesystem::is_regular_file(dir + "/release.csv"))
            mass.settle_ratio = load_release(dir + "/release.csv").settle_ratio;
        return mass;
    }
    if (s.lattice_release.enabled) {
        std::vector<WallDef> walls = setup.walls();
        walls.insert(walls.end(), s.walls.begin(), s.walls.end());
        return lattice_mass(s, walls);
    }
    if (!setup.has_release()) return mass;
    const std::vector<WallDef> box_walls = setup.release_box().walls;
    if (!s.release.from_file.empty()) {
        mass = load_release(s.release.from_file);
        // the resolved scenario must describe the discs used: the mass's radii within this
        // scenario's release radii (after the reduction)
        double lo = INFINITY, hi = 0.0;
        for (double r : mass.radius) {
            lo = std::min(lo, r);
            hi = std::max(hi, r);
        }
        const double shrink = 1.0 - s.release.radius_reduction;
        const double want_lo = s.release.r_min * shrink, want_hi = s.release.r_max * shrink;
        if (!mass.radius.empty() && (lo < want_lo * (1.0 - 1e-6) || hi > want_hi * (1.0 + 1e-6)))
            throw InputError(s.release.from_file + ": its radii [" + format_number(lo) + ", " + format_number(hi) +
                             "] m are not those of this scenario's release (release.scale = " + std::to_string(s.release.scale) +
                             ": [" + format_number(want_lo) + ", " + format_number(want_hi) +
                             "] m after the reduction); give the scale or radii it was generated with, or omit --release-from");
        // a mass settled against other walls (another geometry's W1 differs by ~0.1 mm at
        // the box) would start with overlaps of tens of micrometres: kilonewtons per disc
        if (mass.box_walls.size() != box_walls.size())
            throw InputError(s.release.from_file + ": its '# wall' lines do not match this set-up: not a release mass for it");
        for (size_t k = 0; k < box_walls.size(); ++k) {
            const double d = std::max((mass.box_walls[k][0] - box_walls[k].p0).norm(), (mass.box_walls[k][1] - box_walls[k].p1).norm());
            if (d > 1e-6)
                throw InputError(s.release.from_file + ": the mass was settled against other walls (" + box_walls[k].name +
                                 " differs by " + format_number(d) +
                                 " m): it fits another geometry. Generate it for this scenario (omit --release-from)");
        }
        // discs that overlap more than the run allows would stop it at its first step, blamed
        // on the step: named here, with the file
        refuse_overlapping_discs(mass, s.world.max_overlap_ratio, s.release.from_file);
        refuse_loaded_mass_outside_box(setup.release_box(), mass, s.release.from_file);
    } else {
        if (terminal) std::fprintf(stderr, "generating the release mass ...\n");
        mass = generate_release(s);
    }
    mass.box_walls.clear();
    for (const WallDef& wd : box_walls) mass.box_walls.push_back({wd.p0, wd.p1});
    if (!mass.settled) {
        // a mass still moving starts the run with stored energy and no defined porosity
        if (!s.release.accept_unsettled)
            throw RunError(s.source + ": the release mass did not settle: its unbalanced force ratio reached " +
                           format_number(mass.settle_ratio) + " within release.settle_max_time = " +
                           format_number(s.release.settle_max_time) + " s, above release.settle_ratio = " +
                           format_number(s.release.settle_ratio) +
                           "; raise settle_max_time, or set release.accept_unsettled = true to run it as it is");
        std::fprintf(stderr, "demlab: warning: the release mass did not reach settle_ratio %.3g within %.3g s (ratio %.3g); "
                             "run as it is (release.accept_unsettled)\n",
                     s.release.settle_ratio, s.release.settle_max_time, mass.settle_ratio);
    }
    // space order (release.h): strips two of the largest diameters wide
    double r_max = 0.0;
    for (double r : mass.radius) r_max = std::max(r_max, r);
    order_in_space(mass, 4.0 * r_max);
    return mass;
}

// Cohesive bonds at t = 0 (COHESION.md section 4.1): the explicit pairs, or the filtered
// Delaunay edges of the disc centres. A cohesive scenario without a bond is refused.
void add_bonds(const Scenario& s, World& w) {
    const long n = long(w.disc_count());
    if (!s.cohesion.bonds.empty()) {
        for (const auto& [k, l] : s.cohesion.bonds) {
            if (k >= n || l >= n)
                throw InputError(s.source + ": cohesion.bonds: [" + std::to_string(k) + ", " + std::to_string(l) +
                                 "] names a disc that does not exist (" + std::to_string(n) + " discs)");
            w.add_bond(int(k), int(l));
        }
        return;
    }
    double r_min = INFINITY;
    for (double r : w.radii()) r_min = std::min(r_min, r);
    const auto bonds = delaunay_bonds(w.positions(), w.radii(), with_default_gap(s.cohesion.build, r_min));
    if (bonds.empty())
        throw InputError(s.source + ": cohesion.enabled = true, but the triangulation of the " + std::to_string(n) +
                         " disc centres gave no bond with cohesion.filter's rule");
    for (const auto& [k, l] : bonds) w.add_bond(k, l);
}

// The world: the release mass, then the explicit discs (a checkpoint's mass holds them
// already), the set-up's walls, then the explicit ones; the domain is world.domain, or their
// box padded by 0.5 m (a disc leaving it is lost: taken out, or the run stops).
World build_world(const Scenario& s, const Setup& setup, const ReleaseMass& mass, bool restored, std::vector<int>& layer,
                  std::vector<int>& grid) {
    WorldDef def = s.world;
    def.bond = s.cohesion.bond;
    Vec2 lo(INFINITY, INFINITY), hi(-INFINITY, -INFINITY);
    auto grow = [&](const Vec2& p) {
        lo = lo.cwiseMin(p);
        hi = hi.cwiseMax(p);
    };
    for (const Vec2& p : mass.pos) grow(p);
    for (const DiscDef& d : s.discs) grow(d.pos);
    for (const WallDef& wd : s.walls) {
        grow(wd.shape == WallShape::Segment ? wd.p0 : wd.centre - Vec2(wd.radius, wd.radius));
        grow(wd.shape == WallShape::Segment ? wd.p1 : wd.centre + Vec2(wd.radius, wd.radius));
    }
    const std::vector<WallDef> setup_walls = setup.walls();
    for (const WallDef& wd : setup_walls)
        for (const Vec2& p : {wd.p0, wd.p1}) grow(p);
    for (const Vec2& p : setup.extent()) grow(p);
    def.domain_lo = lo - Vec2(0.5, 0.5);
    def.domain_hi = hi + Vec2(0.5, 0.5);
    if (!s.domain.empty()) {  // world.domain: given; every disc at the start inside it
        def.domain_lo = s.domain[0];
        def.domain_hi = s.domain[1];
        for (const Vec2& p : mass.pos)
            if (p.x() < def.domain_lo.x() || p.x() > def.domain_hi.x() || p.y() < def.domain_lo.y() || p.y() > def.domain_hi.y())
                throw InputError(s.source + ": world.domain: a disc of the release at [" + format_number(p.x()) + ", " +
                                 format_number(p.y()) + "] lies outside it: the domain must hold every disc at t = 0");
    }
    World w(def);
    for (const MaterialDef& m : scenario_materials(s)) w.add_material(m);
    const int mat = kDiscMaterial;
    for (size_t i = 0; i < mass.pos.size(); ++i) {
        w.add_disc({mass.pos[i], mass.radius[i], Vec2::Zero(), 0.0, 0.0, mat});
        layer.push_back(mass.layer[i]);
        grid.push_back(mass.grid[i]);
    }
    if (!restored)
        for (const DiscDef& d : s.discs) {
            DiscDef dd = d;
            dd.material = mat;
            w.add_disc(dd);
            layer.push_back(0);
            grid.push_back(0);
        }
    for (const WallDef& wd : setup_walls) w.add_wall(wd);
    for (WallDef wd : s.walls) w.add_wall(wd);
    if (s.cohesion.enabled) add_bonds(s, w);
    w.finalize();
    const size_t n = w.disc_count();
    if (n == 0) throw InputError(s.source + ": the scenario has no discs");
    for (long id : s.output.track)
        if (id >= long(n)) throw InputError(s.source + ": output.track: disc id " + std::to_string(id) + " does not exist (" + std::to_string(n) + " discs)");
    return w;
}

// The world's performance figures into the summary.
void finish_summary(const World& w, RunSummary& sum, double candidate_sum, double touching_sum, long pair_samples) {
    sum.broadphase_margin = w.broad_phase_margin();
    sum.broadphase_updates = w.broad_phase_stats().updates;
    sum.broadphase_reinserts = w.broad_phase_stats().disc_reinserts;
    sum.broadphase_mean_candidates = pair_samples > 0 ? candidate_sum / double(pair_samples) : 0.0;
    sum.broadphase_mean_touching = pair_samples > 0 ? touching_sum / double(pair_samples) : 0.0;
    sum.broadphase_update_seconds = w.list_update_seconds();
    sum.force_pass_one_range_cuts = w.force_pass_one_range_cuts();
    sum.space_orderings = w.space_orderings();
    sum.force_pass_busy_share = w.force_pass_busy_share();
    sum.force_pass_busy_fallbacks = w.force_pass_busy_fallbacks();
    sum.steps = w.step_count();
    sum.t_end = w.time();
    sum.dt = w.dt();
}

// The summary's figures known at the start: the set-up's landmarks (which it has), the mass and
// the release's porosities.
RunSummary start_summary(const Setup& setup, const MeasureContext& measure, const ReleaseMass& mass,
                         double total_mass, size_t n) {
    RunSummary sum;
    sum.n_discs = long(n);
    sum.total_mass = total_mass;
    sum.has_path = measure.path != nullptr;
    sum.has_envelope = setup.measures_envelope();
    sum.has_deposit = sum.has_path || sum.has_envelope;
    sum.has_barrier = measure.path != nullptr && std::isfinite(measure.barrier.s_barrier);
    sum.has_barrier_forces = !measure.force_walls.barrier.empty();
    sum.has_arc = !measure.force_walls.arc.empty();
    sum.porosity_over_release_box = setup.has_release() ? mass.porosity_settled : -1.0;
    if (setup.has_release()) {
        std::vector<std::array<Vec2, 2>> box;
        for (const WallDef& wd : setup.release_box().walls) box.push_back({wd.p0, wd.p1});
        sum.porosity_inside_mass = interior_porosity(mass.pos, mass.radius, box).porosity;
    }
    return sum;
}

// The wall loads' peaks into the summary: of the samples, of every step, filtered.
void take_peaks(RunSummary& sum, const RunState& st, const ForceExtremes& extremes, const LoadFilter& filter) {
    sum.peak_fx_barrier_sampled = std::max(0.0, st.peak_fx_barrier);
    sum.peak_fy_arc_sampled = std::max(0.0, st.peak_fy_arc);
    take_load_peaks(sum, extremes, filter);
}

// What rebuilds a run's world: the discs at the start and the release mass's figures.
struct RunStart {
    const std::vector<Vec2>& pos;
    const std::vector<double>& radius;
    const std::vector<int>& layer;
    const std::vector<int>& grid;
    const ReleaseMass& mass;
};

// The loop's state into a checkpoint, after its header and tag (restore_run reads it back):
// the world's start, the measurements so far, the timings, the snapshots' times, the series
// files' lengths (flushed first: a resume cuts off what came after), the solver's state and
// the measures' own.
void save_run(BinaryWriter& out, const RunStart& start, RunState& st, RunSummary& sum, double elapsed, const SnapshotWriter* snaps,
              RunSeries& series, const Solver& solver, BarrierOutputs& barrier, const ForceExtremes& extremes,
              const LoadFilter& filter, const DesignLoads& design, ForceHistory& history) {
    out.put(start.pos);
    out.put(start.radius);
    out.put(start.layer);
    out.put(start.grid);
    out.put(start.mass.porosity_settled);
    out.put(start.mass.porosity_generated);
    out.put(start.mass.settle_time);
    out.put(start.mass.wall_seconds);
    st.fields(out, [](BinaryWriter& b, double& v) { b.put(v); }, sum);
    out.put(elapsed);
    out.put(snaps ? snaps->times() : std::vector<double>{});
    for (uint64_t z : series.flush()) out.put(z);
    solver.save_state(out);
    barrier.save(out);
    extremes.save(out);
    filter.save(out);
    design.save(out);
    history.save(out);
}

// The loop's state from a checkpoint (after the world's set-up part): the measurements so
// far, the timings, the snapshots' times, the series files cut back to what they held, and
// the solver's state.
void restore_run(BinaryReader& in, const std::string& checkpoint_path, RunState& st, RunSummary& sum,
                 double& wall_seconds_before, SnapshotWriter* snaps, RunSeries& series, Solver& solver,
                 BarrierOutputs& barrier, ForceExtremes& extremes, LoadFilter& filter, DesignLoads& design,
                 ForceHistory& history) {
    st.fields(in, [](BinaryReader& r, double& v) { r.get(v); }, sum);
    in.get(wall_seconds_before);
    std::vector<double> snap_times;
    in.get(snap_times);
    if (snaps) snaps->restore_times(std::move(snap_times));
    std::array<uint64_t, 4> size{};
    for (uint64_t& z : size) in.get(z);
    series.reopen(size);
    solver.load_state(in);
    if (in.at_end()) barrier.disable();  // an earlier build's checkpoint
    else barrier.load(in);
    if (!in.at_end()) extremes.load(in);  // (an earlier build's: counted from the resume)
    if (!in.at_end()) filter.load(in);
    if (!in.at_end()) design.load(in);
    if (!in.at_end()) history.load(in);
    else if (history.enabled()) throw InputError(checkpoint_path + ": a checkpoint of an earlier build without force_history.csv");
    if (!in.at_end()) throw InputError(checkpoint_path + ": corrupt checkpoint (trailing bytes)");
}

// The files of a finished run: the deposit along the bed path and over x, the dam break's envelope, the
// bonds that broke, and the summary.
void write_results(const Scenario& s, const Setup& setup, const World& w, const MeasureContext& measure,
                   const ReleaseMass& mass, const std::string& dir, RunSummary& sum,
                   const std::function<void(RunSummary&)>& design_figures) {
    if (measure.path) write_deposit(w, measure, dir, sum);
    // the surface over x; a dam break's is envelope.csv (its bed is the floor, y = 0)
    if (measure.path && !setup.measures_envelope()) write_surface(w, measure, dir, sum);
    SlopeAngles angles{};
    if (setup.measures_envelope()) angles = write_envelope(w, measure.front_gap, setup.envelope_length(), s.dam_break.sections_start, dir, sum);
    write_lost_discs(w, dir);
    sum.lost_discs = long(w.lost_discs().size());
    if (measure.path) {
        // a disc that left the domain of a run with a bed path went over the barrier or off an
        // end: the deposit measured is what stayed, and its run-out and run-up are lower bounds;
        // so are they when the deposit reaches the path's end
        for (const LostDiscEvent& e : w.lost_discs()) {
            ++sum.left_flume_discs;
            sum.left_flume_mass += e.mass;
            if (sum.t_left_flume < 0 || e.t < sum.t_left_flume) sum.t_left_flume = e.t;
        }
        sum.runout_lower_bound = sum.left_flume_discs > 0 || sum.runout_s >= measure.path->length() - 1e-9;
    }
    if (w.bonds_at_start() > 0) {
        write_bond_breaks(w, dir);
        sum.bonds = long(w.bonds_at_start());
        sum.bonds_broken = long(w.bond_breaks().size());
        sum.bonds_lost_with_discs = long(w.bonds_lost_with_discs());
    }
    design_figures(sum);  // (after the deposit: the static coefficient reads its height on the barrier)
    // a settled lattice reports its settling (it has no generated porosity)
    const bool settled_lattice = s.lattice_release.enabled && s.lattice_release.settle;
    write_summary(dir + "/summary.json", s, sum,
                  ReleaseFigures{setup.has_release() || settled_lattice, settled_lattice ? NAN : mass.porosity_generated,
                                 mass.settle_time, mass.wall_seconds, mass.settle_ratio > 0.0 ? mass.settle_ratio : NAN},
                  setup.measures_envelope() ? &angles : nullptr);
}

}  // namespace

World world_of_scenario(const Scenario& s) {
    const std::unique_ptr<Setup> setup = make_setup(s);
    ReleaseMass mass;
    if (s.lattice_release.enabled) {
        std::vector<WallDef> walls = setup->walls();
        walls.insert(walls.end(), s.walls.begin(), s.walls.end());
        mass = lattice_mass(s, walls);
    } else if (setup->has_release()) {
        mass = s.release.from_file.empty() ? generate_release(s) : load_release(s.release.from_file);
        double r_max = 0.0;
        for (double r : mass.radius) r_max = std::max(r_max, r);
        order_in_space(mass, 4.0 * r_max);
    }
    std::vector<int> layer, grid;
    return build_world(s, *setup, mass, false, layer, grid);
}

std::string setup_kind_of_run(const std::string& run_dir) {
    // the tables alone choose the set-up: parsed, not finished (no profile is read again)
    const std::string path = run_dir + "/scenario.toml";
    return make_setup(parse_scenario(read_input_file(path, kMaxScenarioBytes, "scenario file"), path))->kind();
}

namespace {

// A solver's run whose set-up is checked: its folder, new or resumed from its checkpoint, the
// one loop with its checkpoints (a signal, --checkpoint-every), and its files at the end.
RunSummary run_through_loop(const Scenario& s, const RunOptions& o, SolverRun& run) {
    const std::string dir = o.out_dir, checkpoint_path = dir + "/" + kCheckpointFile;
    const std::string scenario_text = resolved_toml(s);
    const std::vector<ScenarioInput> inputs = scenario_inputs(s);
    std::unique_ptr<RunFolderLock> lock;
    std::unique_ptr<BinaryReader> restore = open_run_folder(o, scenario_text, inputs, lock, run_inputs(s, o, inputs));
    std::unique_ptr<InterruptScope> interrupts;
    if (o.handle_signals && o.install_handlers) interrupts = std::make_unique<InterruptScope>();
    double wall_seconds_before = 0.0;
    if (restore) run.load(*restore, wall_seconds_before);
    else run.open();
    const auto t0 = std::chrono::steady_clock::now();
    auto elapsed = [&] { return wall_seconds_before + std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); };
    RunParts parts = run.parts(o);
    parts.write_checkpoint = [&] {
        BinaryWriter out;
        put_checkpoint_header(out, scenario_text, inputs, run.solver().time(), s.stop.t_max, run.solver().step_count(), o);
        out.tag("RUN ");
        run.save(out, elapsed());
        write_file_atomic(checkpoint_path, seal_checkpoint(out.bytes()));
    };
    const std::string stop = run_loop(run.solver(), parts, s, o, run.clock());
    const RunSummary sum = run.finish(stop, inputs, elapsed());
    std::filesystem::remove(checkpoint_path);  // the run is complete: nothing to resume
    lock->release_and_remove();
    remove_replaced_output(dir);  // a forced run's old folder, now that the new one is complete
    return sum;
}

}  // namespace

// The discs at the start: the largest radius (m), their mass (kg/m) and area (m2).
struct DiscTotals {
    double r_max = 0.0, mass = 0.0, area = 0.0;
};
static DiscTotals disc_totals(const World& w) {
    DiscTotals t;
    for (size_t i = 0; i < w.disc_count(); ++i) {
        t.r_max = std::max(t.r_max, w.radii()[i]);
        t.mass += w.masses()[i];
        t.area += kPi * w.radii()[i] * w.radii()[i];
    }
    return t;
}

RunSummary run_scenario(const Scenario& s, const RunOptions& o) {
    if (s.solver == "dan") return run_through_loop(s, o, *make_dan_run(s, o));
    if (s.solver == "dem3") return run_through_loop(s, o, *make_dem3_run(s, o));
    const std::string dir = o.out_dir;
    const std::string checkpoint_path = dir + "/" + kCheckpointFile;
    const std::string scenario_text = resolved_toml(s);
    // the files the scenario reads, hashed now: a resume compares them with the checkpoint's
    const std::vector<ScenarioInput> inputs = scenario_inputs(s);
    std::unique_ptr<RunFolderLock> lock;
    // the files a forced folder must not hold (output_dir.h)
    const std::vector<std::string> held = run_inputs(s, o, inputs);
    // A new run's folder is made only once everything that can be checked is: the release
    // mass (generated or read), the walls, the tracers; a refusal leaves no partial folder to
    // block the corrected retry. That the folder is free is checked first.
    std::unique_ptr<BinaryReader> restore;
    if (o.resume) restore = open_run_folder(o, scenario_text, inputs, lock, held);
    else check_output_dir(dir, o.force, held);
    const bool terminal = isatty(STDERR_FILENO) != 0;
    std::unique_ptr<InterruptScope> interrupts;
    if (o.handle_signals && o.install_handlers) interrupts = std::make_unique<InterruptScope>();

    const std::unique_ptr<Setup> setup = make_setup(s);
    const ReleaseMass mass = start_mass(s, *setup, restore.get(), dir, terminal);
    std::vector<int> layer, grid;
    World w = build_world(s, *setup, mass, restore != nullptr, layer, grid);
    const std::unique_ptr<BedPath> path = setup->bed_path(w);
    if (path) {
        double x_lo, x_hi;
        path->x_span(x_lo, x_hi);
        refuse_too_many_deposit_bins(s, path->length(), x_hi - x_lo);
    }
    if (!o.resume) {
        open_run_folder(o, scenario_text, inputs, lock, held);
        if (setup->has_release() && !s.lattice_release.enabled) save_release(mass, dir + "/release.csv");
    }
    DemSolver dem(w);
    Solver& solver = dem;
    const size_t n = w.disc_count();
    // the discs at the start, by id (disc_ids: a lost disc leaves the world, not these)
    const std::vector<Vec2> start_pos = w.positions();
    const std::vector<double> start_radius = w.radii();
    const DiscTotals totals = disc_totals(w);
    const double r_max = totals.r_max, total_mass = totals.mass;
    const double noise = ledger_noise(w, s.world.gravity.norm());  // (check_energy_growth)
    const MeasureContext measure{s, path.get(), path ? setup->barrier(*path) : BarrierMarks{}, setup->force_walls(),
                                 s.output.front_neighbour_gap > 0 ? s.output.front_neighbour_gap : r_max, start_pos};

    RunSeries series(dir, measure.force_walls, path != nullptr, !s.output.track.empty(), !w.bonds().empty());
    ForceExtremes extremes(measure.force_walls);
    LoadFilter filter(s.output.load_window);
    DesignLoads design(s.output.approach_length);
    ForceHistory history(dir + "/force_history.csv", measure.force_walls, s.output.force_history_steps);
    BarrierOutputs barrier(dir, w, measure);
    std::unique_ptr<SnapshotWriter> snaps;
    if (s.output.snapshot_interval > 0) snaps = std::make_unique<SnapshotWriter>(dir + "/snapshots", layer, grid, s.output.snapshot_format == "binary");
    RunSummary sum = start_summary(*setup, measure, mass, total_mass, n);
    sum.scenario_fingerprint = scenario_fingerprint(s, inputs);
    sum.dt_min = INFINITY;
    RunState st;
    st.e0 = solver.energy().balance();
    double wall_seconds_before = 0.0;
    if (restore) {
        restore_run(*restore, checkpoint_path, st, sum, wall_seconds_before, snaps.get(), series, solver, barrier, extremes, filter,
                    design, history);
        restore.reset();
    } else {
        series.open();
        barrier.open();
        history.open();
    }
    // the dissipation accounts as they are now (a resume: as restored)
    DissipationPeaks dissipation(solver.energy());
    const long steps_start = solver.step_count();
    const auto t0 = std::chrono::steady_clock::now();
    auto elapsed = [&] { return wall_seconds_before + std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); };

    double candidate_sum = 0, touching_sum = 0;
    long pair_samples = 0;
    size_t lost_seen = w.lost_discs().size();
    RunParts parts;
    parts.watch_steps = 10;
    parts.sample = [&] {
        series.sample(w, measure, st, sum, extremes, filter);
        barrier.sample(w, solver.time());
        design.sample(w, measure, filter, sum);
    };
    if (snaps)
        parts.snapshot = [&] {
            snaps->write(w);
            if (o.on_snapshot) o.on_snapshot(snaps->last_discs(), snaps->last_walls(), snaps->count() - 1);
        };
    // a lost disc or an overlap after energy was created: name the runaway as such
    parts.step_failed = [&] { check_energy_growth(solver, st.e0, s.stop.max_energy_gain, noise, st.peak_put_in, dissipation); };
    parts.after_step = [&]() -> std::string {
        extremes.step(w);
        filter.step(w, measure.force_walls);
        history.step(w);
        // a disc thrown out by created energy is a blow-up, not a stray: look at once
        if (w.lost_discs().size() != lost_seen) {
            lost_seen = w.lost_discs().size();
            check_energy_growth(solver, st.e0, s.stop.max_energy_gain, noise, st.peak_put_in, dissipation);
            // nothing left to move: not "rest" (the kinetic energy of no disc is 0)
            if (w.disc_count() == 0) return kStopAllDiscsLeft;
        }
        sum.dt_min = std::min(sum.dt_min, solver.dt());
        sum.dt_max = std::max(sum.dt_max, solver.dt());
        return "";
    };
    parts.watch = [&] {
        candidate_sum += double(w.disc_contacts().size());
        touching_sum += double(w.touching_disc_pairs());
        ++pair_samples;
        if (solver.step_count() % kEnergyWatchSteps == 0) check_energy_growth(solver, st.e0, s.stop.max_energy_gain, noise, st.peak_put_in, dissipation);
    };
    // Between two steps: everything the loop carries, written atomically. The series files
    // are flushed first and their lengths recorded, so a resume cuts off what came after.
    parts.write_checkpoint = [&] {
        BinaryWriter out;
        put_checkpoint_header(out, scenario_text, inputs, solver.time(), s.stop.t_max, solver.step_count(), o);
        out.tag("RUN ");
        save_run(out, RunStart{start_pos, start_radius, layer, grid, mass}, st, sum, elapsed(), snaps.get(), series, solver,
                 barrier, extremes, filter, design, history);
        write_file_atomic(checkpoint_path, seal_checkpoint(out.bytes()));
    };
    sum.stop_reason = run_loop(solver, parts, s, o, LoopClock{st.next_series, st.next_snap, st.peak_ke, st.rest_since});
    if (snaps) {
        // the last instant, unless the loop's last snapshot was taken at it already
        if (snaps->times().empty() || snaps->times().back() != solver.time()) parts.snapshot();
        snaps->finish();
    }
    sum.wall_seconds = elapsed();
    finish_summary(w, sum, candidate_sum, touching_sum, pair_samples);
    // of this process (a resumed run: since the resume)
    sum.particle_steps_per_second = double(n) * double(sum.steps - steps_start) /
                                    std::max(sum.wall_seconds - wall_seconds_before, 1e-9);
    const EnergyReport e = solver.energy();
    const double put_in = std::max(st.peak_put_in, energy_put_in(e, st.e0));
    sum.energy_balance_error = put_in > 0 ? std::abs(e.balance() - st.e0) / put_in : 0.0;
    series.close();
    history.close();
    take_peaks(sum, st, extremes, filter);

    barrier.finish(sum);
    write_results(s, *setup, w, measure, mass, dir, sum, [&](RunSummary& out) {
        // the deposit's bulk density: the discs' over their area, less the settled mass's porosity
        const double bulk = totals.area > 0 && out.porosity_inside_mass >= 0 ? total_mass / totals.area * (1.0 - out.porosity_inside_mass) : NAN;
        design.finish(filter, out, bulk, s.world.gravity.norm());
    });
    std::filesystem::remove(checkpoint_path);  // the run is complete: nothing to resume
    lock->release_and_remove();
    remove_replaced_output(dir);  // a forced run's old folder, now that the new one is complete
    return sum;
}

}  // namespace demlab
