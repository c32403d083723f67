#include "run/run.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <unordered_map>

#include "core/binary_io.h"
#include "geometry/deposit.h"
#include "core/error.h"
#include "core/fileio.h"
#include "core/interrupt.h"
#include "core/machine.h"
#include "setups/flume.h"
#include "core/output_dir.h"
#include "core/progress.h"
#include "setups/release.h"
#include "run/snapshot.h"
#include "core/validate.h"
#include "dem/world.h"

namespace demlab {

namespace {

std::string json_number(double v) {
    if (!std::isfinite(v)) return "null";
    std::ostringstream o;
    o.precision(10);
    o << v;
    return o.str();
}

// Checkpoint layout: header (magic, version, byte order, the resolved scenario, the options to
// resume with), the run's own state ("RUN "), then the world's (World::save_state).
constexpr char kMagic[8] = {'D', 'E', 'M', 'L', 'A', 'B', 'C', 'K'};
constexpr uint32_t kCheckpointVersion = 1;
constexpr uint32_t kByteOrder = 0x01020304;

void put_header(BinaryWriter& out, const std::string& scenario_text, double t, double t_max, long steps,
                const RunOptions& o) {
    out.put(kMagic);
    out.put(kCheckpointVersion);
    out.put(kByteOrder);
    out.put(uint32_t(sizeof(double)));
    out.put(scenario_text);
    out.put(t);
    out.put(t_max);
    out.put(int64_t(steps));
    out.put(o.checkpoint_every);
    out.put(uint8_t(o.frames));
    out.put(uint8_t(o.plots));
}

struct Header {
    std::string scenario_text;
    CheckpointInfo info;
};

Header get_header(BinaryReader& in, const std::string& path) {
    char magic[8];
    in.get(magic);
    if (std::memcmp(magic, kMagic, 8) != 0) throw InputError(path + ": not a demlab checkpoint");
    if (in.get<uint32_t>() != kCheckpointVersion) throw InputError(path + ": written by another version of demlab");
    if (in.get<uint32_t>() != kByteOrder || in.get<uint32_t>() != sizeof(double))
        throw InputError(path + ": written on a machine of another architecture (byte order or number size)");
    Header h;
    in.get(h.scenario_text);
    in.get(h.info.time);
    in.get(h.info.t_max);
    h.info.steps = long(in.get<int64_t>());
    in.get(h.info.checkpoint_every);
    h.info.frames = in.get<uint8_t>() != 0;
    h.info.plots = in.get<uint8_t>() != 0;
    return h;
}

// The scenario's settings: its text without the comment lines (the header names the file the
// scenario was read from, which is the run folder's copy when resuming).
std::string without_comments(const std::string& text) {
    std::istringstream in(text);
    std::string line, out;
    while (std::getline(in, line))
        if (line.empty() || line[0] != '#') out += line + '\n';
    return out;
}

// Energy created by the numerics (an unstable step, a disc driven through a wall): the
// ledger's balance stays at its start value in a sound run (it closes to < 1 % of the
// dissipated energy over a flume run), so a rise beyond `max_gain` times the energy turned
// over (the peak kinetic and elastic energies plus what was dissipated) is a blow-up in the
// making. The elastic energy is in the scale because the centred ledger's error on a contact
// oscillating near the critical step is a fair fraction of that contact's energy (measured:
// 20-50 % for a disc settling on a floor at 0.4-0.9 of the critical step), while a blow-up
// multiplies the energy by orders of magnitude. Checked every kEnergyWatchSteps steps.
//
// Every 100 steps, as first, the check cost 1.3 % of a 2-thread flume run: one call to
// World::energy() (a pass over the discs and the candidate pairs) took 225 us on geometry A,
// more than a step. A runaway caught 1,000 steps later has grown for 2 ms more of simulated
// time; a state that turns non-finite or a disc that leaves the domain is caught at its step
// by the integration, and an overlap beyond max_overlap_ratio by the force pass.
constexpr long kEnergyWatchSteps = 1000;
void check_energy_growth(const World& w, double e0, double peak_ke, double& peak_elastic, double max_gain) {
    const EnergyReport e = w.energy();
    peak_elastic = std::max(peak_elastic, e.elastic);
    const double gain = e.balance() - e0;
    const double turned_over =
        peak_ke + peak_elastic + e.dissipated_contacts + e.dissipated_local + e.dissipated_rotation;
    if (gain > max_gain * turned_over && gain > 1e-12 * std::abs(e0))
        throw RunError("blow-up: energy growth: the energy balance rose by " + format_number(gain) + " J/m, " +
                       format_number(turned_over > 0 ? gain / turned_over : INFINITY) +
                       " times the energy turned over (stop.max_energy_gain = " + format_number(max_gain) +
                       "), at step " + std::to_string(w.step_count()) + ", t = " + format_number(w.time()) +
                       " s, with no work put in to match. Likely cause: a time step too large for the stiffness "
                       "(use the automatic step or a smaller timestep.safety)");
}

std::string read_whole(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError("cannot read " + path);
    std::ostringstream b;
    b << in.rdbuf();
    return b.str();
}

}  // namespace

bool same_scenario(const std::string& stored, const std::string& resolved_now) {
    if (without_comments(stored) == without_comments(resolved_now)) return true;
    try {
        Scenario then = parse_scenario(stored, "the checkpoint's scenario");
        finish_scenario(then);
        return without_comments(resolved_toml(then)) == without_comments(resolved_now);
    } catch (const InputError&) {
        return false;  // a key this build no longer reads: not the same scenario
    }
}

CheckpointInfo read_checkpoint_info(const std::string& run_dir) {
    const std::string path = run_dir + "/" + kCheckpointFile;
    BinaryReader in(read_whole(path), path);
    return get_header(in, path).info;
}

RunSummary run_scenario(const Scenario& s, const RunOptions& o) {
    const std::string dir = o.out_dir;
    const std::string checkpoint_path = dir + "/" + kCheckpointFile;
    const std::string scenario_text = resolved_toml(s);
    std::unique_ptr<BinaryReader> restore;
    if (o.resume) {
        restore = std::make_unique<BinaryReader>(read_whole(checkpoint_path), checkpoint_path);
        if (!same_scenario(get_header(*restore, checkpoint_path).scenario_text, scenario_text))
            throw InputError(dir + "/scenario.toml differs from the scenario the checkpoint was written with "
                             "(was it edited?); a resumed run must continue the same scenario");
        restore->expect_tag("RUN ");
        // a write the kill interrupted left its temporary file (the target is intact)
        for (const auto& e : std::filesystem::recursive_directory_iterator(dir))
            if (e.is_regular_file() && e.path().extension() == ".tmp") std::filesystem::remove(e.path());
    } else {
        prepare_output_dir(o.out_dir, o.force);
        std::filesystem::remove(checkpoint_path);  // a stale one of a replaced run
        write_file_atomic(dir + "/scenario.toml", scenario_text);
    }
    const bool terminal = isatty(STDERR_FILENO) != 0;
    std::unique_ptr<InterruptScope> interrupts;
    if (o.handle_signals) interrupts = std::make_unique<InterruptScope>();

    // --- the release mass
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
    } else if (has_release(s)) {
        if (!s.release.from_file.empty()) {
            mass = load_release(s.release.from_file);
            // a mass settled against other walls (another geometry's W1 differs by ~0.1 mm at
            // the box) would start with overlaps of tens of micrometres: kilonewtons per disc
            const auto walls = release_box(s).walls;
            if (mass.box_walls.size() != walls.size())
                throw InputError(s.release.from_file + ": its '# wall' lines do not match this set-up: not a release mass for it");
            for (size_t k = 0; k < walls.size(); ++k) {
                const double d = std::max((mass.box_walls[k][0] - walls[k].p0).norm(), (mass.box_walls[k][1] - walls[k].p1).norm());
                if (d > 1e-6)
                    throw InputError(s.release.from_file + ": the mass was settled against other walls (" + walls[k].name +
                                     " differs by " + format_number(d) +
                                     " m): it fits another geometry. Generate it for this scenario (omit --release-from)");
            }
        } else {
            if (terminal) std::fprintf(stderr, "generating the release mass ...\n");
            mass = generate_release(s);
        }
        mass.box_walls.clear();
        for (const WallDef& wd : release_box(s).walls) mass.box_walls.push_back({wd.p0, wd.p1});
        if (!mass.settled)
            std::fprintf(stderr, "demlab: warning: the release mass did not reach settle_ratio %.3g within %.3g s (ratio %.3g)\n",
                         s.release.settle_ratio, s.release.settle_max_time, mass.settle_ratio);
        // space order (release.h): strips two of the largest diameters wide
        double r_max = 0.0;
        for (double r : mass.radius) r_max = std::max(r_max, r);
        order_in_space(mass, 4.0 * r_max);
        save_release(mass, dir + "/release.csv");
    }

    // --- the world
    WorldDef def = s.world;
    // the domain: the walls' and discs' box, padded by 0.5 m; leaving it stops the run
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
    for (const WallDef& wd : lab_walls(s))
        for (const Vec2& p : {wd.p0, wd.p1}) grow(p);
    if (s.flume.enabled)
        for (const Vec2& p : {s.flume.w1_p0, s.flume.w1_p1, s.flume.w3_p0, s.flume.w3_p1}) grow(p);
    def.domain_lo = lo - Vec2(0.5, 0.5);
    def.domain_hi = hi + Vec2(0.5, 0.5);
    World w(def);
    const int mat = w.add_material(s.disc);
    std::vector<int> layer, grid;
    for (size_t i = 0; i < mass.pos.size(); ++i) {
        w.add_disc({mass.pos[i], mass.radius[i], Vec2::Zero(), 0.0, 0.0, mat});
        layer.push_back(mass.layer[i]);
        grid.push_back(mass.grid[i]);
    }
    if (!restore)  // a checkpoint's `mass` holds every disc at its start, the explicit ones too
        for (const DiscDef& d : s.discs) {
            DiscDef dd = d;
            dd.material = mat;
            w.add_disc(dd);
            layer.push_back(0);
            grid.push_back(0);
        }
    for (const WallDef& wd : lab_walls(s)) w.add_wall(wd);
    for (WallDef wd : s.walls) w.add_wall(wd);
    w.finalize();
    const size_t n = w.disc_count();
    if (n == 0) throw InputError(s.source + ": the scenario has no discs");
    for (long id : s.output.track)
        if (id >= long(n)) throw InputError(s.source + ": output.track: disc id " + std::to_string(id) + " does not exist (" + std::to_string(n) + " discs)");
    const std::vector<Vec2> start_pos = w.positions();
    // what a checkpoint needs to rebuild this world: the discs at the start
    auto put_start = [&](BinaryWriter& out) {
        out.put(start_pos);
        out.put(w.radii());
        out.put(layer);
        out.put(grid);
        out.put(mass.porosity_settled);
        out.put(mass.porosity_generated);
        out.put(mass.settle_time);
        out.put(mass.wall_seconds);
    };

    std::unique_ptr<FlumePath> path;
    if (s.flume.enabled) path = std::make_unique<FlumePath>(w.wall_geom(kW1), w.wall_geom(kW2), w.wall_geom(kW3));
    double r_max = 0, total_mass = 0;
    for (size_t i = 0; i < n; ++i) {
        r_max = std::max(r_max, w.radii()[i]);
        total_mass += w.masses()[i];
    }
    const double gap = s.output.front_neighbour_gap > 0 ? s.output.front_neighbour_gap : r_max;

    // --- output files
    SeriesFile forces, front, energy, track;
    std::unique_ptr<SnapshotWriter> snaps;
    if (s.output.snapshot_interval > 0) snaps = std::make_unique<SnapshotWriter>(dir + "/snapshots", layer, grid);

    RunSummary sum;
    sum.n_discs = long(n);
    sum.total_mass = total_mass;
    sum.porosity = has_release(s) ? mass.porosity_settled : -1.0;
    sum.dt_min = INFINITY;
    double peak_fx_barrier = -1, peak_fy_arc = -1, peak_ke = 0, peak_elastic = 0, rest_since = -1;
    double e0 = w.energy().balance();
    double next_series = 0.0, next_snap = 0.0, wall_seconds_before = 0.0;
    // the run's own state between two steps: measurements so far and what is due next
    auto run_state = [&](auto& io, auto&& field) {
        for (double* v : {&peak_fx_barrier, &peak_fy_arc, &peak_ke, &peak_elastic, &rest_since, &e0, &next_series, &next_snap,
                          &sum.dt_min, &sum.dt_max, &sum.t_peak_fx_barrier, &sum.t_peak_fy_arc,
                          &sum.max_runup_height_during_run, &sum.t_front_at_barrier})
            field(io, *v);
    };
    const char* forces_header =
        "t,fx_slope,fy_slope,fx_arc,fy_arc,fx_barrier,fy_barrier,fx_total,fy_total,"
        "ix_slope,iy_slope,ix_arc,iy_arc,ix_barrier,iy_barrier,ix_total,iy_total,fx_gate,fy_gate,ix_gate,iy_gate\n";
    const char* energy_header =
        "t,kinetic_translation,kinetic_rotation,potential,elastic,dissipated_contacts,dissipated_local,"
        "dissipated_rotation,work_by_walls,removed_with_walls,balance\n";
    if (restore) {
        // the series files are cut back to what they held at the checkpoint
        run_state(*restore, [](BinaryReader& in, double& v) { in.get(v); });
        restore->get(wall_seconds_before);
        std::vector<double> snap_times;
        restore->get(snap_times);
        if (snaps) snaps->restore_times(std::move(snap_times));
        uint64_t size[4];
        for (uint64_t& z : size) restore->get(z);
        forces.reopen(dir + "/forces.csv", size[0]);
        energy.reopen(dir + "/energy.csv", size[1]);
        if (path) front.reopen(dir + "/front.csv", size[2]);
        if (!s.output.track.empty()) track.reopen(dir + "/track.csv", size[3]);
        w.load_state(*restore);
        if (!restore->at_end()) throw InputError(checkpoint_path + ": corrupt checkpoint (trailing bytes)");
        restore.reset();
    } else {
        forces.open(dir + "/forces.csv");
        forces.out() << forces_header;
        energy.open(dir + "/energy.csv");
        energy.out() << energy_header;
        if (path) {
            front.open(dir + "/front.csv");
            front.out() << "t,s_front,displacement\n";
        }
        if (!s.output.track.empty()) {
            track.open(dir + "/track.csv");
            track.out() << "t,id,x,y,vx,vy,angle,omega\n";
        }
    }
    const double t_start = w.time();
    const long steps_start = w.step_count();
    Progress progress(s.stop.t_max, "s", t_start, steps_start);
    const auto t0 = std::chrono::steady_clock::now();
    auto last_checkpoint = t0;
    auto elapsed = [&] { return wall_seconds_before + std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); };

    // Between two steps: everything the loop carries, written atomically. The series files
    // are flushed first and their lengths recorded, so a resume cuts off what came after.
    auto write_checkpoint = [&]() {
        BinaryWriter out;
        put_header(out, scenario_text, w.time(), s.stop.t_max, w.step_count(), o);
        out.tag("RUN ");
        put_start(out);
        run_state(out, [](BinaryWriter& b, double& v) { b.put(v); });
        out.put(elapsed());
        out.put(snaps ? snaps->times() : std::vector<double>{});
        for (SeriesFile* f : {&forces, &energy, &front, &track}) out.put(f->flush());
        w.save_state(out);
        write_file_atomic(checkpoint_path, out.bytes());
    };

    auto sample = [&]() {
        const double t = w.time();
        Vec2 f[3] = {Vec2::Zero(), Vec2::Zero(), Vec2::Zero()}, imp[3] = {Vec2::Zero(), Vec2::Zero(), Vec2::Zero()};
        if (path)
            for (int k = 0; k < 3; ++k) {
                f[k] = w.wall_force(k);
                imp[k] = w.wall_impulse(k);
            }
        const Vec2 ft = f[0] + f[1] + f[2], it = imp[0] + imp[1] + imp[2];
        std::ostream& fo = forces.out();
        fo << t;
        for (const Vec2& v : {f[0], f[1], f[2], ft, imp[0], imp[1], imp[2], it}) fo << ',' << v.x() << ',' << v.y();
        const Vec2 fg = path ? w.wall_force(kGate) : Vec2::Zero(), ig = path ? w.wall_impulse(kGate) : Vec2::Zero();
        fo << ',' << fg.x() << ',' << fg.y() << ',' << ig.x() << ',' << ig.y() << '\n';
        if (std::abs(f[2].x()) > peak_fx_barrier) {
            peak_fx_barrier = std::abs(f[2].x());
            sum.t_peak_fx_barrier = t;
        }
        if (std::abs(f[1].y()) > peak_fy_arc) {
            peak_fy_arc = std::abs(f[1].y());
            sum.t_peak_fy_arc = t;
        }
        const EnergyReport e = w.energy();
        energy.out() << t << ',' << e.kinetic_translation << ',' << e.kinetic_rotation << ',' << e.potential << ','
                     << e.elastic << ',' << e.dissipated_contacts << ',' << e.dissipated_local << ','
                     << e.dissipated_rotation << ',' << e.work_by_walls << ',' << e.removed_with_walls << ','
                     << e.balance() << '\n';
        if (path) {
            const auto conn = connected_discs(w.positions(), w.radii(), gap);
            double s_front = -INFINITY, disp = 0, runup = 0;
            for (size_t i = 0; i < n; ++i) {
                if (!conn[i]) continue;
                double si, hi_;
                path->project(w.positions()[i], si, hi_);
                if (si > s_front) {
                    s_front = si;
                    disp = (w.positions()[i] - start_pos[i]).norm();
                }
                if (si > path->s_barrier_start())
                    runup = std::max(runup, w.positions()[i].y() + w.radii()[i] - path->barrier_foot().y());
            }
            front.out() << t << ',' << s_front << ',' << disp << '\n';
            sum.max_runup_height_during_run = std::max(sum.max_runup_height_during_run, runup);
            if (sum.t_front_at_barrier < 0 && s_front >= path->s_barrier_start()) sum.t_front_at_barrier = t;
        }
        for (long id : s.output.track) {
            const size_t i = size_t(id);
            track.out() << t << ',' << id << ',' << w.positions()[i].x() << ',' << w.positions()[i].y() << ','
                        << w.velocities()[i].x() << ',' << w.velocities()[i].y() << ',' << w.angles()[i] << ','
                        << w.omegas()[i] << '\n';
        }
    };

    sum.stop_reason = "t_max";
    double candidate_sum = 0, touching_sum = 0;
    long pair_samples = 0;
    while (true) {
        if (w.time() >= next_series - 1e-12) {
            sample();
            next_series += s.output.series_interval;
        }
        if (snaps && w.time() >= next_snap - 1e-12) {
            snaps->write(w);
            if (o.on_snapshot) o.on_snapshot(snaps->last_discs(), snaps->last_walls(), snaps->count() - 1);
            next_snap += s.output.snapshot_interval;
        }
        if (w.time() >= s.stop.t_max) break;
        w.step();
        sum.dt_min = std::min(sum.dt_min, w.dt());
        sum.dt_max = std::max(sum.dt_max, w.dt());
        if (w.step_count() % 10 == 0) {
            candidate_sum += double(w.disc_contacts().size());
            touching_sum += double(w.touching_disc_pairs());
            ++pair_samples;
            // summed by the integration, in parallel (a pass over the discs here was 2 % of the
            // calling thread's time on 2 threads, with the other one waiting)
            const double ke = w.kinetic_energy();
            peak_ke = std::max(peak_ke, ke);
            if (w.step_count() % kEnergyWatchSteps == 0) check_energy_growth(w, e0, peak_ke, peak_elastic, s.stop.max_energy_gain);
            if (ke < s.stop.rest_ke_fraction * peak_ke) {
                if (rest_since < 0) rest_since = w.time();
                if (w.time() - rest_since >= s.stop.rest_duration) {
                    sum.stop_reason = "rest";
                    break;
                }
            } else {
                rest_since = -1;
            }
            progress.update(w.time(), w.step_count());
        }
        if (const int sig = o.handle_signals ? pending_interrupt() : 0) {
            progress.finish();
            write_checkpoint();
            throw Interrupted("signal " + std::to_string(sig) + " at t = " + format_number(w.time()) + " s (step " +
                              std::to_string(w.step_count()) + "): checkpoint written; continue with: demlab resume " + dir);
        }
        if (o.checkpoint_every > 0 && w.step_count() % 10 == 0) {
            const auto now = std::chrono::steady_clock::now();
            if (std::chrono::duration<double>(now - last_checkpoint).count() >= o.checkpoint_every) {
                write_checkpoint();
                last_checkpoint = now;
            }
        }
    }
    progress.finish();
    sample();
    if (snaps) {
        if (std::abs(w.time() - (next_snap - s.output.snapshot_interval)) > 1e-12) {
            snaps->write(w);
            if (o.on_snapshot) o.on_snapshot(snaps->last_discs(), snaps->last_walls(), snaps->count() - 1);
        }
        snaps->finish();
    }
    sum.wall_seconds = elapsed();
    sum.broadphase_margin = w.broad_phase_margin();
    sum.broadphase_updates = w.broad_phase_stats().updates;
    sum.broadphase_reinserts = w.broad_phase_stats().disc_reinserts;
    sum.broadphase_mean_candidates = pair_samples > 0 ? candidate_sum / double(pair_samples) : 0.0;
    sum.broadphase_mean_touching = pair_samples > 0 ? touching_sum / double(pair_samples) : 0.0;
    sum.broadphase_update_seconds = w.list_update_seconds();
    sum.force_pass_one_range_cuts = w.force_pass_one_range_cuts();
    sum.force_pass_busy_share = w.force_pass_busy_share();
    sum.force_pass_busy_fallbacks = w.force_pass_busy_fallbacks();
    sum.steps = w.step_count();
    sum.t_end = w.time();
    sum.dt = w.dt();
    // of this session (a resumed run: since the resume)
    sum.particle_steps_per_second = double(n) * double(sum.steps - steps_start) /
                                    std::max(sum.wall_seconds - wall_seconds_before, 1e-9);
    const EnergyReport e = w.energy();
    const double dissipated = e.dissipated_contacts + e.dissipated_local + e.dissipated_rotation;
    sum.energy_balance_error = dissipated > 0 ? std::abs(e.balance() - e0) / dissipated : 0.0;
    forces.close();
    energy.close();
    front.close();
    track.close();

    // --- the deposit
    if (path) {
        const auto conn = connected_discs(w.positions(), w.radii(), gap);
        const int bins = int(std::ceil(path->length() / s.output.deposit_bin)) + 1;
        std::vector<double> top(size_t(bins), 0.0);
        for (size_t i = 0; i < n; ++i) {
            if (!conn[i]) continue;
            double si, hi_;
            path->project(w.positions()[i], si, hi_);
            sum.runout_s = std::max(sum.runout_s, si + w.radii()[i]);
            const int b = int(std::floor(si / s.output.deposit_bin + 0.5));
            if (b >= 0 && b < bins) top[size_t(b)] = std::max(top[size_t(b)], hi_ + w.radii()[i]);
            if (si > path->s_barrier_start())
                sum.runup_height = std::max(sum.runup_height, w.positions()[i].y() + w.radii()[i] - path->barrier_foot().y());
        }
        std::ostringstream d;
        d << "s_m,height_m\n";
        for (int b = 0; b < bins; ++b) d << b * s.output.deposit_bin << ',' << top[size_t(b)] << '\n';
        write_file_atomic(dir + "/deposit.csv", d.str());
    }

    SlopeAngles angles{};
    if (s.dam_break.enabled) {
        const auto conn = connected_discs(w.positions(), w.radii(), gap);
        const Envelope env = upper_envelope(w.positions(), w.radii(), conn, 0.0, s.dam_break.floor_length, 0.001);
        angles = slope_angles(env);
        sum.runout_s = angles.toe_x;
        std::ostringstream d;
        d << "x_m,surface_m\n";
        for (size_t k = 0; k < env.y.size(); ++k)
            if (!std::isnan(env.y[k])) d << env.x(k) << ',' << env.y[k] << '\n';
        write_file_atomic(dir + "/envelope.csv", d.str());
    }
    std::ostringstream j;
    j << "{\n"
      << "  \"scenario\": \"" << s.name << "\",\n"
      << "  \"n_discs\": " << sum.n_discs << ",\n"
      << "  \"total_mass\": " << json_number(sum.total_mass) << ",\n"
      << "  \"porosity\": " << json_number(sum.porosity) << ",\n"
      << "  \"release_porosity_generated\": " << json_number(has_release(s) ? mass.porosity_generated : NAN) << ",\n"
      << "  \"release_settle_time\": " << json_number(has_release(s) ? mass.settle_time : NAN) << ",\n"
      << "  \"release_wall_seconds\": " << json_number(has_release(s) ? mass.wall_seconds : NAN) << ",\n"
      << "  \"dt\": " << json_number(sum.dt) << ",\n"
      << "  \"dt_min\": " << json_number(sum.dt_min) << ",\n"
      << "  \"dt_max\": " << json_number(sum.dt_max) << ",\n"
      << "  \"steps\": " << sum.steps << ",\n"
      << "  \"t_end\": " << json_number(sum.t_end) << ",\n"
      << "  \"stop_reason\": \"" << sum.stop_reason << "\",\n"
      << "  \"wall_seconds\": " << json_number(sum.wall_seconds) << ",\n"
      << "  \"particle_steps_per_second\": " << json_number(sum.particle_steps_per_second) << ",\n"
      // the machine the timings above come from (a resumed run: the one that finished it)
      << "  \"machine\": " << json_string(machine_summary(machine_info())) << ",\n"
      << "  \"runout_s\": " << json_number(sum.runout_s) << ",\n"
      << "  \"runup_height\": " << json_number(sum.runup_height) << ",\n"
      << "  \"max_runup_height_during_run\": " << json_number(sum.max_runup_height_during_run) << ",\n"
      << "  \"t_front_at_barrier\": " << json_number(sum.t_front_at_barrier) << ",\n"
      << "  \"t_peak_fx_barrier\": " << json_number(sum.t_peak_fx_barrier) << ",\n"
      << "  \"t_peak_fy_arc\": " << json_number(sum.t_peak_fy_arc) << ",\n"
      << "  \"energy_balance_error\": " << json_number(sum.energy_balance_error) << ",\n"
      << "  \"broadphase_margin\": " << json_number(sum.broadphase_margin) << ",\n"
      << "  \"broadphase_updates\": " << sum.broadphase_updates << ",\n"
      << "  \"broadphase_reinserts\": " << sum.broadphase_reinserts << ",\n"
      << "  \"broadphase_mean_candidates\": " << json_number(sum.broadphase_mean_candidates) << ",\n"
      << "  \"broadphase_mean_touching\": " << json_number(sum.broadphase_mean_touching) << ",\n"
      << "  \"broadphase_update_seconds\": " << json_number(sum.broadphase_update_seconds) << ",\n"
      << "  \"force_pass_one_range_cuts\": " << sum.force_pass_one_range_cuts << ",\n"
      << "  \"force_pass_busy_share\": " << json_number(sum.force_pass_busy_share) << ",\n"
      << "  \"force_pass_busy_fallbacks\": " << sum.force_pass_busy_fallbacks;
    if (s.dam_break.enabled) {
        j << ",\n  \"gamma_ges\": " << json_number(angles.gamma_ges);
        for (int i = 0; i < 5; ++i) j << ",\n  \"gamma_" << i + 1 << "\": " << json_number(angles.gamma[i]);
        j << ",\n  \"toe_x\": " << json_number(angles.toe_x) << ",\n  \"surface_at_back_wall\": " << json_number(angles.h_wall);
    }
    j << "\n}\n";
    write_file_atomic(dir + "/summary.json", j.str());
    std::filesystem::remove(checkpoint_path);  // the run is complete: nothing to resume
    return sum;
}

}  // namespace demlab
