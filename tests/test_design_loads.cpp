// The barrier's loads as a designer uses them (run/design_loads.h, measures.h): a single
// disc's every-step peak against the linear spring-dashpot's closed-form maximum, and a flume
// run's static load, steady time, impact impulse and coefficients against its own series.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "core/csv.h"
#include "files.h"
#include "helpers.h"
#include "run/design_loads.h"
#include "run/measures.h"
#include "run/run.h"
#include "run/summary_file.h"
#include "scenario/scenario.h"
#include "setups/setup.h"

using namespace demlab;
using namespace demlab::test;
namespace fs = std::filesystem;

namespace {

// The largest force of a linear spring-dashpot contact struck at v0 (mass m, stiffness k,
// critical ratio beta < 1): x = v0/wd e^(-a t) sin(wd t), a = beta w0, wd = w0 sqrt(1 - beta^2);
// the force on the wall F = k x + c x' = -m x'' = m v0/wd e^(-a t) (P sin(wd t) + Q cos(wd t))
// with P = wd^2 - a^2, Q = 2 a wd. F' = 0 where tan(wd t) = (wd P - a Q) / (a P + wd Q); the
// maximum is there (its first root in (0, pi / wd)) or at t = 0+ (F = c v0), whichever is larger.
double closed_form_peak(double m, double k, double beta, double v0) {
    const double w0 = std::sqrt(k / m), a = beta * w0, wd = w0 * std::sqrt(1.0 - beta * beta);
    const double p = wd * wd - a * a, q = 2.0 * a * wd;
    auto force = [&](double t) { return m * v0 / wd * std::exp(-a * t) * (p * std::sin(wd * t) + q * std::cos(wd * t)); };
    double t = std::atan2(wd * p - a * q, a * p + wd * q) / wd;
    if (t < 0) t += kPi / wd;
    return std::max(force(0.0), force(t));
}

// A disc strikes a vertical wall (the "barrier" group) normally at v0 with no gravity, no
// friction and no local damping; every step's extremes give the largest |fx|.
double every_step_peak(double beta, double steps_per_contact, double& expected) {
    WorldDef def;
    def.gravity = Vec2::Zero();
    def.damping.beta_n = beta;
    def.damping.beta_s = beta;
    def.rotation.model = 2;
    def.rotation.u_rr = 0.0;
    def.timestep.damping_correction = false;
    World w(def);
    const double kn = 1e8, rho = 2672.0, r = 0.002, v0 = 2.0;
    const int mat = w.add_material(material(0.0, kn, rho));
    w.add_disc({Vec2(r + 1e-6, 0.0), r, Vec2(-v0, 0.0), 0.0, 0.0, mat});
    w.add_wall(segment(w, Vec2(0.0, 0.1), Vec2(0.0, -0.1)));
    const double m = rho * kPi * r * r, k = 0.5 * kn;  // disc and wall in series
    w.set_dt(kPi * std::sqrt(m / k) / steps_per_contact);
    w.finalize();
    ForceWalls walls;
    walls.barrier = {0};
    ForceExtremes extremes(walls);
    bool touched = false;
    for (int s = 0; s < 400000; ++s) {
        w.step();
        extremes.step(w);
        if (w.touching_wall_pairs() > 0) touched = true;
        if (touched && w.touching_wall_pairs() == 0) break;
    }
    EXPECT_TRUE(touched);
    expected = closed_form_peak(m, k, beta, v0);
    return extremes.peak_fx_barrier;
}

}  // namespace

// Within 1 % at 2,000 steps per contact, for an undamped contact (v0 sqrt(m k)), the thesis'
// beta = 0.5 and a light and a heavy damping (the heavy one peaks at the first instant, c v0).
TEST(SingleDiscImpact, EveryStepPeakIsTheSpringDashpotsClosedFormMaximum) {
    for (double beta : {0.0, 0.2, 0.5, 0.85}) {
        double expected = 0;
        const double peak = every_step_peak(beta, 2000, expected);
        EXPECT_NEAR(peak / expected, 1.0, 0.01) << "beta " << beta << ": " << peak << " N/m against " << expected;
        std::printf("beta %.2f: every-step peak %.2f N/m, closed form %.2f N/m, ratio %.5f\n", beta, peak, expected, peak / expected);
    }
    // the undamped peak is v0 sqrt(m k)
    double expected = 0;
    const double undamped = every_step_peak(0.0, 2000, expected);
    EXPECT_NEAR(expected, 2.0 * std::sqrt(2672.0 * kPi * 4e-6 * 0.5e8), 1e-9 * expected);
    EXPECT_NEAR(undamped / expected, 1.0, 0.01);
}

namespace {
struct FlumeRun {
    fs::path dir;
    RunSummary sum;
};

FlumeRun run_a20(const std::string& name, double t_max) {
    Scenario s = load_scenario(std::string(DEMLAB_SOURCE_DIR) + "/scenarios/geometry-A.toml");
    for (const std::string& a : {std::string("release.scale=20"), "stop.t_max=" + std::to_string(t_max), std::string("output.snapshot_interval=0"),
                                 std::string("output.force_history_steps=100")})
        apply_override(s, a);
    finish_scenario(s);
    FlumeRun r{temp_dir(name), {}};
    r.sum = run_scenario(s, {r.dir.string(), false, {}});
    return r;
}

// the value of a column at the row of time t (rows are written at the sample times)
double at_time(const std::vector<double>& t, const std::vector<double>& v, double when) {
    for (size_t k = 0; k < t.size(); ++k)
        if (std::abs(t[k] - when) < 1e-8) return v[k];
    ADD_FAILURE() << "no row at t = " << when;
    return NAN;
}
}  // namespace

// Geometry A at scale 20 to rest: each design figure as its definition computes it from the
// run's own forces.csv, the approach measured, and the dense history every 100 steps.
TEST(DesignLoads, FiguresFollowFromTheRunsOwnSeries) {
    const FlumeRun run = run_a20("design-a20", 4.0);
    const RunSummary& r = run.sum;
    ASSERT_EQ(r.stop_reason, "rest");
    const fs::path forces = run.dir / "forces.csv";
    const std::vector<double> t = csv_column(forces, "t_s"), fil = csv_column(forces, "fx_barrier_filtered_N_per_m"),
                              ix = csv_column(forces, "ix_barrier_Ns_per_m");
    // the static load: the filtered load of the last row (written at the last step)
    EXPECT_NEAR(r.static_fx_barrier, std::abs(fil.back()), 1e-8 * r.static_fx_barrier);
    EXPECT_GT(r.static_fx_barrier, 0.0);
    EXPECT_NEAR(r.static_fy_arc, std::abs(csv_column(forces, "fy_arc_filtered_N_per_m").back()), 1e-8 * r.static_fy_arc);
    // steady from t_barrier_load_steady on, and not at the row before it
    size_t first = 0;
    while (first < t.size() && t[first] < r.t_barrier_load_steady - 1e-8) ++first;  // (the file's 10 digits)
    ASSERT_GT(first, 0u);
    ASSERT_LT(first, t.size());
    for (size_t k = first; k < t.size(); ++k)
        EXPECT_LE(std::abs(std::abs(fil[k]) - r.static_fx_barrier), kSteadyBand * r.static_fx_barrier + 1e-9) << "t " << t[k];
    EXPECT_FALSE(std::abs(std::abs(fil[first - 1]) - r.static_fx_barrier) <= kSteadyBand * r.static_fx_barrier)
        << "t " << t[first - 1] << " " << fil[first - 1] << " static " << r.static_fx_barrier << " steady " << r.t_barrier_load_steady;
    EXPECT_GT(r.t_barrier_load_steady, r.t_front_at_barrier);
    // the impact's impulse: from the front's arrival to steady
    const double impulse = at_time(t, ix, r.t_barrier_load_steady) - at_time(t, ix, r.t_front_at_barrier);
    EXPECT_NEAR(r.impact_ix_barrier, std::abs(impulse), 1e-8 * std::abs(impulse));
    // the approaching flow and the coefficients by their definitions
    EXPECT_NEAR(r.t_approach, r.t_front_at_barrier, 1e-12);
    EXPECT_GT(r.approach_depth, 0.0);
    EXPECT_GT(r.approach_speed, 0.0);
    EXPECT_GT(r.approach_mass_per_length, 0.0);
    EXPECT_NEAR(r.approach_froude, r.approach_speed / std::sqrt(9.81 * r.approach_depth), 1e-12 * r.approach_froude);
    EXPECT_NEAR(r.impact_coefficient_alpha,
                r.peak_fx_barrier_filtered / (r.approach_mass_per_length * r.approach_speed * r.approach_speed), 1e-12 * r.impact_coefficient_alpha);
    EXPECT_NEAR(r.static_bulk_density, 2672.0 * (1.0 - r.porosity_inside_mass), 1e-9);
    EXPECT_NEAR(r.static_coefficient_k, r.static_fx_barrier / (0.5 * r.static_bulk_density * 9.81 * r.runup_height * r.runup_height),
                1e-9 * r.static_coefficient_k);
    // summary.json carries them, with units
    const SummaryFile j = read_summary_file((run.dir / "summary.json").string());
    EXPECT_NEAR(j.number("impact_coefficient_alpha"), r.impact_coefficient_alpha, 1e-6 * r.impact_coefficient_alpha);
    EXPECT_EQ(j.unit("impact_ix_barrier"), "N s/m");
    // the dense history: a row every 100 steps, forces.csv's barrier force where both have a row
    const std::vector<double> th = csv_column(run.dir / "force_history.csv", "t_s");
    EXPECT_EQ(long(th.size()), r.steps / 100);
    fs::remove_all(run.dir);
}

// Stopped before rest: the static figures are null with their reason, the approach is not.
TEST(DesignLoads, ARunNotAtRestHasNoStaticLoad) {
    const FlumeRun run = run_a20("design-a20-tmax", 1.0);
    ASSERT_EQ(run.sum.stop_reason, "t_max");
    const SummaryFile j = read_summary_file((run.dir / "summary.json").string());
    for (const char* k : {"static_fx_barrier", "t_barrier_load_steady", "impact_ix_barrier", "static_coefficient_k"}) {
        EXPECT_TRUE(std::isnan(j.number(k))) << k;
        EXPECT_NE(j.not_measured.at(k).find("did not come to rest"), std::string::npos) << k;
    }
    EXPECT_TRUE(std::isfinite(j.number("impact_coefficient_alpha")));
    fs::remove_all(run.dir);
}

// DAN writes the same columns from its own steps: every row's extremes bracket its sample, the
// every-step peak is at least the sampled one, and its static load is the last filtered load.
TEST(DesignLoads, DanWritesTheSameColumnsFromItsSteps) {
    Scenario s = load_scenario(std::string(DEMLAB_SOURCE_DIR) + "/scenarios/geometry-A.toml");
    apply_override(s, "scenario.solver=\"dan\"");
    apply_override(s, "output.snapshot_interval=0");
    finish_scenario(s);
    const fs::path dir = temp_dir("design-dan");
    const RunSummary r = run_scenario(s, {dir.string(), false, {}});
    ASSERT_EQ(r.stop_reason, "rest");
    const fs::path forces = dir / "forces.csv";
    EXPECT_EQ(read_file_header(forces), forces_header(make_setup(s)->force_walls()));
    const std::vector<double> f = csv_column(forces, "fx_barrier_N_per_m"), hi = csv_column(forces, "fx_barrier_max_N_per_m"),
                              lo = csv_column(forces, "fx_barrier_min_N_per_m"), fil = csv_column(forces, "fx_barrier_filtered_N_per_m");
    for (size_t k = 0; k < f.size(); ++k) {
        EXPECT_GE(hi[k], f[k]);
        EXPECT_LE(lo[k], f[k]);
    }
    EXPECT_GE(r.peak_fx_barrier, r.peak_fx_barrier_sampled);
    EXPECT_GT(r.peak_fx_barrier_filtered, 0.0);
    EXPECT_NEAR(r.static_fx_barrier, std::abs(fil.back()), 1e-8 * r.static_fx_barrier);
    EXPECT_GT(r.approach_speed, 0.0);
    EXPECT_NEAR(r.approach_mass_per_length, s.dan.density * r.approach_depth, 1e-9);
    EXPECT_TRUE(std::isfinite(r.impact_coefficient_alpha));
    EXPECT_TRUE(std::isfinite(r.static_coefficient_k));
    fs::remove_all(dir);
}

// A set-up with a barrier and no arc (terrain), stopped at t_max: the arc's static load is
// unmeasured for both reasons, but summary.json lists each figure once (its first reason).
TEST(DesignLoads, EachUnmeasuredFigureIsListedOnce) {
    RunSummary sum;
    sum.has_barrier_forces = true;
    sum.has_arc = false;
    sum.stop_reason = "t_max";
    DesignLoads loads(0.1);
    loads.finish(LoadFilter(0.05), sum, NAN, 9.81);
    std::vector<std::string> keys;
    for (const NotMeasured& m : not_measured(sum)) {
        EXPECT_EQ(std::count(keys.begin(), keys.end(), m.key), 0) << m.key;
        keys.push_back(m.key);
    }
    EXPECT_EQ(not_measured_reason(sum, "static_fy_arc"), "the set-up has no arc");
    EXPECT_NE(not_measured_reason(sum, "static_fx_barrier").find("did not come to rest"), std::string::npos);
}
