// `demlab run`: builds the world of a scenario (a flume with its release mass, or explicit
// walls and discs), runs it to rest or t_max and writes the run folder:
//   scenario.toml (resolved), release.csv, forces.csv, front.csv, energy.csv, track.csv,
//   deposit.csv, summary.json, snapshots/ (VTK).
// With checkpoints it can be stopped (a signal, or killed) and resumed to the same bytes.
#pragma once
#include <cmath>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "scenario/scenario.h"

namespace demlab {

// Steps a run may take at most (`run` and `demo` refuse more): the real sand size to rest is
// about 1e7.
constexpr double kMaxRunSteps = 1e10;

struct RunOptions {
    std::string out_dir;
    bool force = false;     // replace the files of an existing folder
    // called after each snapshot is written, with the two files and the snapshot's index (a
    // DAN run: its blocks.csv so far, no walls file, the index from the time)
    std::function<void(const std::string& discs_vtp, const std::string& walls_vtp, int index)> on_snapshot;
    // Checkpoints (RUN_DIR/checkpoint.bin, replaced atomically; removed when the run ends):
    double checkpoint_every = 0.0;  // s of wall-clock time between checkpoints; 0: none on a timer
    bool handle_signals = false;    // SIGINT/SIGTERM: a final checkpoint, then Interrupted (interrupt.h)
    // with handle_signals: the run installs the handlers for its time (interrupt.h); false when
    // the caller holds them for several runs at once (a sweep's worker threads)
    bool install_handlers = true;
    bool resume = false;            // continue out_dir from its checkpoint (the scenario must be its scenario.toml)
    // run out_dir again from the start with its own scenario.toml (resume of a run stopped
    // before its first checkpoint): that file is an input the forced folder may hold
    bool rerun = false;
    // called from the run loop about four times a second of wall-clock time and once at the
    // end, with the simulated time, stop.t_max and the steps per second so far (scripting: the
    // Python module's progress callable); may throw to abandon the run
    std::function<void(double t, double t_max, double steps_per_second)> on_progress = {};
    // recorded in the checkpoint for `demlab resume` (the caller acts on them)
    bool frames = false, plots = true;
    // A 3-D run's pictures (scenario.solver = "dem3"), drawn by the output library, which the
    // engine does not link: the command line attaches them (output/terrain_view.h); without
    // them the run writes no PNG. A frame: the terrain and the spheres (centres, radii,
    // speeds) into dir/frames/{oblique,map}_TAG.png; a raster over the terrain's hillshade.
    std::function<void(const std::string& dir, const std::string& tag, const Tin& terrain, const std::vector<Vec3>& centres,
                       const std::vector<double>& radius, const std::vector<double>& speed, double speed_max)>
        terrain_frames = {};
    std::function<void(const std::string& png, const EsriGrid& terrain, const std::vector<double>& field, double field_max)>
        raster_picture = {};
};

// The checkpoint's file name inside a run folder.
inline constexpr const char* kCheckpointFile = "checkpoint.bin";

// What `demlab resume` needs to know before it restores a checkpoint.
struct CheckpointInfo {
    double time = 0, t_max = 0;     // s, simulated
    long steps = 0;
    double checkpoint_every = 0;    // s, wall-clock, as the run was started
    bool frames = false, plots = true;
};
CheckpointInfo read_checkpoint_info(const std::string& run_dir);

// Whether a checkpoint's scenario (resolved by the build that wrote it) is the run's: the
// same text, or the same once this build resolves it too, so that a key added since (with
// its default) does not strand a checkpoint written before it. A key this build does not
// read is a different scenario.
bool same_scenario(const std::string& stored, const std::string& resolved_now);

// The stop reason of a run whose every disc left the domain and was taken out (world.lost_discs
// = "remove"): nothing is left to come to rest.
inline constexpr const char* kStopAllDiscsLeft = "all discs left the domain";

struct RunSummary {
    // the content hash of the resolved scenario and the files it read (scenario/fingerprint.h):
    // summary.json's scenario_fingerprint, which a sweep's reuse compares
    std::string scenario_fingerprint;
    long n_discs = 0;                   // at the start
    long lost_discs = 0;                // taken out when they left the domain (lost.csv)
    double total_mass = 0;              // kg per metre of thickness
    // the settled release mass: the discs' area over the release box (its looser layers at the
    // walls and under the lid included), and the porosity inside the mass, 4 r_max from its
    // walls and free surface (geometry/packing.h); -1 without a release mass
    double porosity_over_release_box = 0;
    double porosity_inside_mass = -1;
    double dt = 0;                      // s, the last step (automatic steps vary)
    double dt_min = 0, dt_max = 0;
    long steps = 0;
    double t_end = 0;
    std::string stop_reason;            // "rest", "t_max", "max_steps" or kStopAllDiscsLeft
    double wall_seconds = 0;            // of the run after the release mass was ready
    double particle_steps_per_second = 0;
    double runout_s = 0;                // m along the path: the deposit's front
    // mass that left the flume (past the barrier's top or the path's ends: taken out as lost
    // discs): then the run-out and run-up are lower bounds, not the deposit's
    long left_flume_discs = 0;
    double left_flume_mass = 0;         // kg/m
    double t_left_flume = -1;           // s, the first to leave (-1: none)
    bool runout_lower_bound = false;
    double deposit_max_height = 0;      // m, the deposit's thickest point normal to the bed (deposit.csv)
    double deposit_length = 0;          // m along the path, from its first bin with mass to its last
    // m, the deposit's largest vertical depth above the bed (surface.csv; a dam break's: its
    // envelope's highest point over the floor) and its x
    double deposit_max_depth = 0, x_deposit_max_depth = 0;
    double runup_height = 0;            // m: highest point of the deposit on the barrier above its foot
    double max_runup_height_during_run = 0;
    double t_front_at_barrier = -1;     // s, -1 if never
    // the largest |x-force| on the barrier and |y-force| on the arc over every step (N/m), and
    // when; the largest of forces.csv's samples apart (_sampled: the 5 ms rows miss impacts
    // between them)
    double t_peak_fx_barrier = -1;
    double t_peak_fy_arc = -1;
    double peak_fx_barrier = 0;
    double peak_fy_arc = 0;
    double t_peak_fx_barrier_sampled = -1, t_peak_fy_arc_sampled = -1;
    double peak_fx_barrier_sampled = 0, peak_fy_arc_sampled = 0;
    // the largest mean force over output.load_window (the impulse gained over it divided by its
    // length), N/m, and when its window ended; NaN times: no whole window loaded
    double peak_fx_barrier_filtered = 0, t_peak_fx_barrier_filtered = NAN;
    double peak_fy_arc_filtered = 0, t_peak_fy_arc_filtered = NAN;
    // The barrier's design loads (run/design_loads.h; NaN: not measured, the reason in
    // `unmeasured`): the filtered load at rest on the barrier (x) and the arc (y), N/m; when the
    // barrier's filtered load came within kSteadyBand of it for good (s) and the x-impulse from
    // the front's arrival to then (N s/m); the flow within output.approach_length upstream of
    // the barrier when the front arrived: time (s), depth (m), speed (m/s), mass per length
    // (kg/m2: rho h), Froude number v / sqrt(g h); the hydrodynamic alpha = F_filtered / (q v^2) and the hydrostatic
    // K = F_static / (1/2 rho_d g H^2) with the bulk density rho_d (kg/m3)
    double static_fx_barrier = NAN, static_fy_arc = NAN, t_barrier_load_steady = NAN, impact_ix_barrier = NAN;
    double t_approach = NAN, approach_depth = NAN, approach_speed = NAN, approach_mass_per_length = NAN, approach_froude = NAN;
    double impact_coefficient_alpha = NAN, static_coefficient_k = NAN, static_bulk_density = NAN;
    // landmarks a part of the run did not measure, with the reason (summary.json's not_measured)
    std::vector<std::pair<std::string, std::string>> unmeasured;
    // Pa, the largest normal pressure in a bin of the barrier (barrier_pressure.csv), where
    // along it from its lower end (m) and when (s); -1: no barrier
    double peak_barrier_pressure = 0, s_peak_barrier_pressure = -1, t_peak_barrier_pressure = -1;
    double barrier_pressure_bin = 0;    // m, the bins' length (output.pressure_bin, at least the largest disc's diameter)
    double energy_balance_error = 0;    // |balance drift| / the largest energy put in (measures.h, energy_put_in)
    // The broad phase, of this process like wall_seconds (a resumed run counts from the resume,
    // and rebuilds its candidate lists there), sampled every 10 steps: the force pass tests
    // every candidate, so candidates per touching pair is what the margin costs
    double broadphase_margin = 0;       // m, the fat boxes' pad
    long broadphase_updates = 0;        // candidate-list rebuilds
    long broadphase_reinserts = 0;      // discs re-inserted into the tree
    double broadphase_mean_candidates = 0;    // disc-disc candidate pairs per step
    double broadphase_mean_touching = 0;      // of which touching
    double broadphase_update_seconds = 0;     // s, wall-clock in the candidate-list updates (mostly serial)
    long force_pass_one_range_cuts = 0;       // list updates whose force pass ran as one range (discs out of space order)
    long space_orderings = 0;                 // times the discs were renumbered in space order (world.space_order)
    double force_pass_busy_share = 1;         // of the threads' time in the shared force passes, the share the ranges worked (World)
    long force_pass_busy_fallbacks = 0;       // times the pass fell back to one range for a busy machine (World)
    // Which landmarks the set-up has (measures.h, not_measured): a bed path (run-out, deposit
    // along it), a deposit envelope over a floor (the dam break: run-out and deposit from it), a
    // barrier on the path (arrival, run-up), walls whose forces are the barrier's and the arc's.
    // A landmark the set-up lacks, or that did not happen, is null in summary.json with its reason.
    bool has_path = false, has_envelope = false, has_barrier = false, has_barrier_forces = false, has_arc = false;
    bool has_deposit = false;  // deposit_max_height and deposit_length (the DEM's, along its path or floor)
    long bonds = -1;                    // cohesive bonds at the start (-1: none)
    long bonds_broken = 0;              // of which broken by the end
    long bonds_lost_with_discs = 0;     // intact ones that went with a lost disc
};

RunSummary run_scenario(const Scenario& s, const RunOptions& o);

// The world a run of the scenario starts from (its release mass, discs, walls and bonds),
// finalized and ready to step, with no run folder: benchmarks and scripting.
World world_of_scenario(const Scenario& s);

// The set-up of a run folder's scenario ("flume", "dam_break", "terrain", "explicit";
// setups/setup.h), from its scenario.toml.
std::string setup_kind_of_run(const std::string& run_dir);

}  // namespace demlab
