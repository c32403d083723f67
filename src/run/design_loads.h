// The barrier's loads as design guidelines use them (docs/barrier-loads.md): the static load
// once the mass is at rest, when the loads became steady, the impulse of the impact, the flow
// that arrives (its depth, speed and mass per length just upstream of the barrier when the
// front reaches it), and from them the two coefficients of the guidelines' load models:
//
//   hydrodynamic:  F = alpha rho h v^2      alpha = F_peak / (q v^2),   q = rho h (kg/m2)
//   hydrostatic:   F = K 1/2 rho_d g H^2    K = F_static / (1/2 rho_d g H^2)
//
// per metre of width. F_peak is the impulse-filtered peak on the barrier (LoadFilter, over
// output.load_window), F_static the filtered load at rest; both the x-forces the thesis reads
// (a sloping barrier's horizontal thrust is what a fluid's pressure gives on its vertical
// projection, so K keeps its meaning there). q is the mass per length of bed of the connected
// discs within output.approach_length upstream of the barrier's foot: rho h at once, with no
// assumed porosity; h, the flow's depth, is those discs' highest top normal to the bed, and v
// their mean velocity's magnitude (the mass-weighted mean); the Froude number v / sqrt(g h). H is the deposit's height on the
// barrier above its foot (summary's runup_height) and rho_d the release's bulk density, the
// discs' density times one less the porosity inside the settled mass.
//
// DAN (dan_run.cpp) gives the same figures from its own steps: h and v of the last block
// before the barrier's foot when the front reaches it, q = dan.density h, rho_d = dan.density.
#pragma once
#include <cmath>
#include <vector>

#include "core/binary_io.h"
#include "run/run.h"

namespace demlab {

class World;
class LoadFilter;
struct MeasureContext;

// The filtered loads differ from the static load by at most this share from "steady" on.
constexpr double kSteadyBand = 0.1;

class DesignLoads {
public:
    explicit DesignLoads(double approach_length) : approach_length_(approach_length) {}
    // At each series sample: the filtered loads and the barrier's impulse, and at the first
    // sample with the front at the barrier (sum.t_front_at_barrier) the approaching flow.
    void sample(const World& w, const MeasureContext& m, const LoadFilter& filter, const RunSummary& sum);
    // the same for another solver (DAN): a sample's time, filtered barrier x-load and x-impulse,
    // and once the flow that arrives (mass per length q = rho h; discs: how many measured it)
    void record(double t, double fx_filtered, double ix_barrier);
    void record_approach(double t, double depth, double speed, double mass_per_length, long discs);
    bool approach_measured() const { return !std::isnan(t_approach_); }
    // The summary's design figures (NaN where not measured, the reason in sum.unmeasured).
    // bulk_density: kg/m3 of the deposit, rho_d (NaN: not known).
    void finish(const LoadFilter& filter, RunSummary& sum, double bulk_density, double gravity) const;
    void save(BinaryWriter& out) const;
    void load(BinaryReader& in);

private:
    double approach_length_;
    std::vector<double> t_, fx_, ix_;  // per sample: time, filtered barrier x-load (NaN: no whole window), x-impulse
    // the approaching flow (NaN: not measured yet)
    double t_approach_ = NAN, depth_ = NAN, speed_ = NAN, mass_per_length_ = NAN, approach_discs_ = 0;
};

}  // namespace demlab
