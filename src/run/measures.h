// The measurements of a run, each a part the run loop calls (run.cpp): the series sampled
// every output.series_interval (forces.csv, energy.csv, front.csv, track.csv) with the
// landmarks they find (force peaks, the front's arrival, the run-up), the deposit along the
// bed path (deposit.csv), the envelope and slope angles of a dam break (envelope.csv), the
// energy watch, and summary.json.
#pragma once
#include <cmath>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/binary_io.h"
#include "core/fileio.h"
#include "dem/world.h"
#include "geometry/deposit.h"
#include "run/run.h"
#include "setups/setup.h"

namespace demlab {

// What the measurements read of the set-up, fixed for the run.
struct MeasureContext {
    const Scenario& scenario;
    const BedPath* path;           // null: no front, deposit or run-up
    BarrierMarks barrier;
    ForceWalls force_walls;
    double front_gap;              // m, a front disc's neighbour gap (output.front_neighbour_gap)
    const std::vector<Vec2>& start_pos;  // the discs at the start (the front's displacement)
};

// The loop's own state between two steps, saved in checkpoints (in this order).
struct RunState {
    // peak_put_in: the largest energy put in at a series sample (energy_put_in), the scale of
    // the ledger's closure (it holds the slot of the peak elastic energy of earlier builds);
    // peak_fx_barrier and peak_fy_arc: the largest of the samples (the every-step ones are
    // ForceExtremes')
    double peak_fx_barrier = -1, peak_fy_arc = -1, peak_ke = 0, peak_put_in = 0, rest_since = -1, e0 = 0;
    double next_series = 0.0, next_snap = 0.0;
    template <typename IO, typename Field>
    void fields(IO& io, Field&& field, RunSummary& sum) {
        for (double* v : {&peak_fx_barrier, &peak_fy_arc, &peak_ke, &peak_put_in, &rest_since, &e0, &next_series,
                          &next_snap, &sum.dt_min, &sum.dt_max, &sum.t_peak_fx_barrier_sampled, &sum.t_peak_fy_arc_sampled,
                          &sum.max_runup_height_during_run, &sum.t_front_at_barrier})
            field(io, *v);
    }
};

// forces.csv's header for a set-up's wall groups: t_s, the groups' forces and the total, their
// impulses and the total, then the gate's force and impulse where there is a gate (the flume's
// is series_columns.h's kForcesColumns), then each group's and the total's every-step extremes
// since the previous row: fx_<g>_max, fx_<g>_min, fy_<g>_max, fy_<g>_min (N/m), then the
// barrier's and the arc's impulse-filtered loads (LoadFilter) where the set-up has them.
std::string forces_header(const ForceWalls& walls);

// The forces of every step, not only of the sampled ones (issue 51): each group's largest and
// smallest x- and y-force since forces.csv's previous row, and over the run the largest |fx| on
// the barrier and |fy| on the arc with their times. A few adds and compares per wall group per
// step; the same bits for any series interval and thread count; carried by checkpoints.
class ForceExtremes {
public:
    explicit ForceExtremes(const ForceWalls& walls);
    void step(const World& w);           // after each step (and at t = 0)
    // a step of another solver (DAN): its time and each group's force, in written() order
    void step(double t, const Vec2* group_forces);
    const std::vector<double>& row() const { return row_; }  // per group then total: fx max, fx min, fy max, fy min
    void reset_row();                    // after forces.csv's row is written
    double peak_fx_barrier = 0, t_peak_fx_barrier = NAN, peak_fy_arc = 0, t_peak_fy_arc = NAN;
    void save(BinaryWriter& out) const;
    void load(BinaryReader& in);

private:
    std::vector<ForceGroup> groups_;
    int barrier_ = -1, arc_ = -1;  // the barrier's and the arc's index in groups_ (-1: none)
    std::vector<double> row_;
    std::vector<Vec2> forces_;  // the step's group forces (World steps)
};

// Loads filtered by their impulse (issue 51): at each step t, the mean force over the window
// before it, exactly the impulse gained from the last step at or before t - W to t divided by
// that span (W <= span < W + one step); the largest |x| of the barrier's and |y| of the arc's
// with their times. A ring of the impulses of the last W (about W / dt entries: 16,000 at scale
// 4), carried by checkpoints.
class LoadFilter {
public:
    // the step of a world: its time, the barrier walls' x- and the arc walls' y-impulse
    void step(const World& w, const ForceWalls& walls);
    explicit LoadFilter(double window) : window_(window) {}
    // the step's time and the barrier's x- and the arc's y-impulse so far (N s/m)
    void step(double t, double ix_barrier, double iy_arc);
    double peak_fx_barrier = 0, t_peak_fx_barrier = NAN, peak_fy_arc = 0, t_peak_fy_arc = NAN;
    // the last step's filtered loads (NaN before a whole window has passed)
    double fx_barrier = NAN, fy_arc = NAN;
    void save(BinaryWriter& out) const;
    void load(BinaryReader& in);

private:
    double window_;
    std::vector<double> t_, ix_, iy_;  // the entries since `first_` are the window's
    size_t first_ = 0;
};

// The barrier's and the arc's every-step and filtered peaks, with their times, into the
// summary (a DEM or DAN run's).
void take_load_peaks(RunSummary& sum, const ForceExtremes& extremes, const LoadFilter& filter);

// forces.csv (the set-up's wall groups: ForceWalls), energy.csv, front.csv (with a bed path),
// track.csv (with tracers).
class RunSeries {
public:
    RunSeries(std::string dir, const ForceWalls& walls, bool front, bool track, bool bonds)
        : dir_(std::move(dir)), groups_(walls.written()), has_gate_(walls.gate >= 0), has_front_(front), has_track_(track),
          has_bonds_(bonds), forces_header_(forces_header(walls)) {}
    void open();                                        // new files with their headers
    void reopen(const std::array<uint64_t, 4>& sizes);  // a resumed run's, cut back to these sizes
    std::array<uint64_t, 4> flush();                    // their sizes now
    void sample(const World& w, const MeasureContext& m, RunState& st, RunSummary& sum, ForceExtremes& extremes,
                const LoadFilter& filter);
    void close();

private:
    std::string dir_;
    std::vector<ForceGroup> groups_;
    bool has_gate_, has_front_, has_track_, has_bonds_;
    std::string forces_header_;
    SeriesFile forces_, energy_, front_, track_;
};

// The dissipation accounts' largest values so far: the energy watch's memory of them (not in a
// checkpoint: a resumed run starts it from the restored accounts).
struct DissipationPeaks {
    double contacts = 0, local = 0, rotation = 0;
    DissipationPeaks() = default;
    explicit DissipationPeaks(const EnergyReport& e)
        : contacts(e.dissipated_contacts), local(e.dissipated_local), rotation(e.dissipated_rotation) {}
};
// Energy created by the numerics: throws RunError (run.cpp's watch, measures.cpp): the balance
// grown beyond max_gain times the energy put in, or a dissipation account fallen below its
// largest value so far by more than kDissipationDrop times it.
constexpr long kEnergyWatchSteps = 1000;
// (1e-5 of the energy put in: a hundredth of the ledger's measured closure, 0.04-0.1 %, and far
// above the rounding of the accounts' sums; no run of the suite lowers an account at all)
constexpr double kDissipationDrop = 1e-5;
class Solver;
void check_energy_growth(const Solver& w, double e0, double max_gain, double noise, double& peak_put_in,
                         DissipationPeaks& dissipation);
// The ledger's resolution, below which no gain counts (check_energy_growth): a thousandth of
// the energy that lifts every disc by its radius at this gravity (m/s2).
double ledger_noise(const World& w, double gravity);
// A ledger with an infinite or NaN term ends the run (RunError): no series row or summary
// is written from it.
void require_finite_ledger(const EnergyReport& e, long step, double t);
// The energy a run had and was given by time t (J/m): e0 less the potential now plus the
// walls' work; the scale of the ledger's closure and of the energy watch
double energy_put_in(const EnergyReport& e, double e0);

// deposit.csv: the deposit's top, normal to the bed, in bins along the path; the run-out and
// final run-up into the summary.
void write_deposit(const World& w, const MeasureContext& m, const std::string& dir, RunSummary& sum);
// The most bins output.deposit_bin may make along a bed path (deposit.csv, peaks.csv) or over its
// span in x (surface.csv): ten million rows, some 300 MB of text.
constexpr double kMaxDepositBins = 1e7;
// An InputError naming the scenario file, the key, its value and the smallest bin allowed when
// a path `along` metres long, or spanning `span_x` metres in x, would get more bins: refused
// before the run writes anything (a bin of a nanometre over a flume asked for 1e9 rows and
// ended the run in an allocation failure).
void refuse_too_many_deposit_bins(const Scenario& s, double along, double span_x);
// surface.csv: the deposit's surface over x (the upper envelope of the connected discs'
// outlines) above the bed's height there, every output.deposit_bin of x over the bed path's
// span: the section a designer draws. Unlike deposit.csv's height normal to the bed, it does
// not stop at a concave arc's radius.
// Its deepest sample into the summary (deposit_max_depth, x_deposit_max_depth).
void write_surface(const World& w, const MeasureContext& m, const std::string& dir, RunSummary& sum);
// surface.csv's text for a top sampled over x (NaN where no mass stands) above a bed path, a
// DEM run's or DAN's; its deepest sample into sum.
std::string surface_csv(const BedPath& path, const Envelope& top, RunSummary& sum);
// envelope.csv and the slope angles of a dam break's deposit over [0, length].
SlopeAngles write_envelope(const World& w, double gap, double length, double sections_start, const std::string& dir, RunSummary& sum);

// summary.json's landmarks of a flow, the same keys for DEM and DAN runs (`demlab compare`):
// run-up, arrival at the barrier, the force peaks and their times
class SummaryJson;
// The landmarks a run did not measure, each with its reason: the set-up has no such thing
// (a dam break has no barrier, a terrain no arc), or it did not happen (the front never reached
// the barrier, the barrier carried no load). Their values are null in summary.json (never the
// -1 or 0 a sweep would average), and the console says the reason.
struct NotMeasured {
    std::string key, reason;
};
std::vector<NotMeasured> not_measured(const RunSummary& sum);
// The reason `key` was not measured, or "" when it was.
std::string not_measured_reason(const RunSummary& sum, const std::string& key);
// The landmarks into summary.json: null for those not measured, and their reasons in its
// "not_measured" object.
void put_landmarks(SummaryJson& j, const RunSummary& sum);
// lost.csv: each disc taken out when it left the domain (world.lost_discs): when, its id,
// where, its velocity and spin, mass and kinetic energy then.
void write_lost_discs(const World& w, const std::string& dir);
// bonds_broken.csv: t_s, k, l, strain, energy_J_per_m of each bond that broke, in order.
void write_bond_breaks(const World& w, const std::string& dir);

// summary.json.
struct ReleaseFigures {
    bool generated = false;  // a release mass (not explicit discs)
    double porosity_generated = 0, settle_time = 0, wall_seconds = 0;
    double settle_ratio = NAN;  // the unbalanced force ratio the settling reached (NaN: not known, a resumed run)
};
void write_summary(const std::string& path, const Scenario& s, const RunSummary& sum, const ReleaseFigures& release,
                   const SlopeAngles* angles);
// Every number a DEM or DAN run's summary.json can hold (a set-up writes a subset: the dam
// break's gamma_*, a barrier's pressure, bonds): what a sweep's `columns` may name.
std::vector<std::string> summary_number_keys();

}  // namespace demlab
