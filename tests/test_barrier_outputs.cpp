// The barrier design outputs (barrier_pressure.csv, peaks.csv, the deposit's section): the
// pressures integrate to the barrier's normal force, a disc at rest on a flat barrier presses with its weight, and
// one disc's peaks are its own track.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <algorithm>
#include <fstream>
#include <string>
#include <vector>

#include "core/csv.h"
#include "files.h"
#include "output/plot.h"
#include "core/binary_io.h"
#include "run/measures.h"
#include "run/run.h"
#include "scenario/scenario.h"

using namespace demlab;
using demlab::test::temp_dir;
namespace fs = std::filesystem;

namespace {
CsvTable table(const fs::path& p) { return read_csv_table(p.string()); }
size_t column(const CsvTable& t, const std::string& name) {
    for (size_t c = 0; c < t.names.size(); ++c)
        if (t.names[c] == name) return c;
    ADD_FAILURE() << "no column " << name;
    return 0;
}
}  // namespace

TEST(BarrierOutputs, PressuresIntegrateToTheBarriersNormalForceAtEveryRow) {
    Scenario s = load_scenario(std::string(DEMLAB_SOURCE_DIR) + "/scenarios/geometry-A.toml");
    apply_override(s, "release.scale=20");
    apply_override(s, "stop.t_max=1.3");
    apply_override(s, "output.snapshot_interval=0");
    finish_scenario(s);
    const fs::path dir = temp_dir("barrier-a20");
    fs::remove_all(dir);
    const RunSummary r = run_scenario(s, {dir.string(), false, {}});
    // W3 as the world has it (its lower end moved onto the arc)
    const World w = world_of_scenario(s);
    const WallGeom& g = w.wall_geom(2);
    const Vec2 t = (g.p1 - g.p0).normalized(), n = perp(t);
    const double length = (g.p1 - g.p0).norm();
    const CsvTable f = table(dir / "forces.csv"), p = table(dir / "barrier_pressure.csv");
    ASSERT_EQ(f.rows.size(), p.rows.size());
    const size_t bins = p.names.size() - 1;
    // bins of output.pressure_bin (0.01 m), but no shorter than the largest disc (scale 20: 2 cm)
    double r_max = 0;
    for (double ri : w.radii()) r_max = std::max(r_max, ri);
    EXPECT_GT(2.0 * r_max, 0.01);
    EXPECT_EQ(bins, size_t(std::lround(length / (2.0 * r_max))));
    EXPECT_GE(length / double(bins), 2.0 * r_max * (1.0 - 0.5 / double(bins)));
    const size_t fx = column(f, "fx_barrier_N_per_m"), fy = column(f, "fy_barrier_N_per_m");
    double largest = 0;
    for (size_t k = 0; k < f.rows.size(); ++k) {
        EXPECT_EQ(f.rows[k][0], p.rows[k][0]);
        double integral = 0;
        for (size_t b = 1; b <= bins; ++b) integral += p.rows[k][b] * length / double(bins);
        const double normal = -(f.rows[k][fx] * n.x() + f.rows[k][fy] * n.y());
        // both files keep 10 significant digits
        EXPECT_NEAR(integral, normal, 1e-8 * std::max(1.0, std::abs(normal))) << "t = " << f.rows[k][0];
        largest = std::max(largest, normal);
    }
    EXPECT_GT(largest, 100.0);  // the mass reached the barrier and loaded it
    EXPECT_GT(r.peak_barrier_pressure, 0.0);
    EXPECT_GE(r.s_peak_barrier_pressure, 0.0);
    EXPECT_LE(r.s_peak_barrier_pressure, length);
    // peaks.csv: per deposit bin of the path, finite, non-negative, with flow somewhere
    const CsvTable k = table(dir / "peaks.csv");
    ASSERT_EQ(k.names, (std::vector<std::string>{"s_m", "max_height_m", "max_mean_speed_m_per_s", "max_bed_pressure_Pa"}));
    double h_max = 0, v_max = 0;
    for (const auto& row : k.rows) {
        for (double v : row) EXPECT_TRUE(std::isfinite(v) && v >= 0);
        h_max = std::max(h_max, row[1]);
        v_max = std::max(v_max, row[2]);
    }
    EXPECT_GT(h_max, 0.02);
    EXPECT_GT(v_max, 1.0);
    // the pressure map's colours run to the 99th percentile of the loaded bins, below the peak,
    // which is marked (one bin's impact set the scale, and the field showed near zero)
    if (gnuplot_available()) {
        make_plots(dir.string(), 320, 200);
        const std::string gp = demlab::test::read_file(dir / "plots/plots.gp");
        const size_t at = gp.find("set cbrange [0:");
        ASSERT_NE(at, std::string::npos) << gp;
        const double top_kpa = std::stod(gp.substr(at + 15));
        EXPECT_GT(top_kpa, 0.0);
        EXPECT_LT(top_kpa, r.peak_barrier_pressure / 1000.0);
        EXPECT_NE(gp.find("peak "), std::string::npos);
        // the deposit's section, filled between the bed and its surface (surface.csv)
        EXPECT_TRUE(fs::exists(dir / "plots/deposit_section.png"));
        EXPECT_NE(gp.find("'../surface.csv' using 1:2:3 with filledcurves"), std::string::npos) << gp;
    }
    fs::remove_all(dir);
}

// One disc on a flat top of a terrain barrier (up 0.2 m from its foot, then 0.5 m level):
// at rest it presses with its weight m g on the bin under it, per the bin's length; its
// peaks along the path are its own track's height and speed.
TEST(BarrierOutputs, ADiscAtRestOnAFlatBarrierPressesWithItsWeight) {
    const fs::path dir = temp_dir("barrier-flat");
    fs::remove_all(dir);
    fs::create_directories(dir);
    std::ofstream(dir / "ground.csv") << "x,y\n0,0\n2,0\n";
    const double r = 0.01, density = 2672.0, g = 9.81;
    std::ofstream(dir / "flat.toml") << R"([scenario]
name = "flat-barrier"
[terrain]
profile = "ground.csv"
barrier = [[1.0, 0.0], [1.0, 0.2], [1.5, 0.2]]
[material]
density = 2672.0
[[discs]]
position = [1.2525, 0.2102]
radius = 0.01
[output]
track = [0]
series_interval = 0.002
snapshot_interval = 0
[stop]
t_max = 0.8
rest_duration = 0.5
)";
    Scenario s = load_scenario((dir / "flat.toml").string());
    finish_scenario(s);
    const fs::path out = dir / "run";
    run_scenario(s, {out.string(), false, {}});
    const CsvTable p = table(out / "barrier_pressure.csv");
    const size_t bins = p.names.size() - 1;
    ASSERT_EQ(bins, 35u);  // 0.7 m in bins of the disc's diameter, 0.02 m (output.pressure_bin: 0.01 m)
    const double bin = 0.7 / 35.0;
    // the disc's foot on the top: 0.2 m up the face, then 0.2525 m along the top
    const size_t expected = size_t((0.2 + 0.2525) / bin);
    const std::vector<double>& last = p.rows.back();
    const double weight = density * kPi * r * r * g;
    for (size_t b = 1; b <= bins; ++b) {
        if (b - 1 == expected) EXPECT_NEAR(last[b] * bin, weight, 1e-6 * weight);
        else EXPECT_EQ(last[b], 0.0) << "bin " << b - 1;
    }
    // its peaks: the track's largest height above the bed and speed (one disc: the mean is its own)
    const CsvTable track = table(out / "track.csv"), peaks = table(out / "peaks.csv");
    double v_track = 0, h_track = 0;
    for (const auto& row : track.rows) {
        v_track = std::max(v_track, std::hypot(row[column(track, "vx_m_per_s")], row[column(track, "vy_m_per_s")]));
        // the bed path runs over the barrier: the height is above its top, y = 0.2 m
        h_track = std::max(h_track, row[column(track, "y_m")] + r - 0.2);
    }
    double v_peak = 0, h_peak = 0;
    long bins_with_disc = 0;
    for (const auto& row : peaks.rows) {
        v_peak = std::max(v_peak, row[2]);
        h_peak = std::max(h_peak, row[1]);
        bins_with_disc += row[1] > 0 ? 1 : 0;
    }
    EXPECT_GT(v_track, 0.01);  // it fell onto the barrier first
    EXPECT_NEAR(v_peak, v_track, 1e-9 * v_track);
    EXPECT_NEAR(h_peak, h_track, 1e-9);
    EXPECT_EQ(bins_with_disc, 1);
    fs::remove_all(dir);
}

// Every step's extremes (issue 51): each forces.csv row's max and min of every group and
// component bound the row's own sample; the summary's peaks are of every step, at least the
// largest sample (kept as *_sampled), and the same bits for two series intervals and for 1
// and 2 threads.
TEST(BarrierOutputs, EveryStepExtremesBoundTheSamplesAndDoNotDependOnSampling) {
    auto run = [](const std::string& name, const std::string& interval, int threads) {
        Scenario s = load_scenario(std::string(DEMLAB_SOURCE_DIR) + "/scenarios/geometry-A.toml");
        for (const std::string& a : {std::string("release.scale=20"), std::string("stop.t_max=1.2"),
                                     std::string("output.snapshot_interval=0"), "output.series_interval=" + interval})
            apply_override(s, a);
        finish_scenario(s);
        s.world.threads = threads;
        const fs::path dir = temp_dir(name);
        fs::remove_all(dir);
        RunSummary r = run_scenario(s, {dir.string(), false, {}});
        return std::make_pair(dir, r);
    };
    const auto [dir, r] = run("extremes-5ms", "0.005", 1);
    const CsvTable f = table(dir / "forces.csv");
    size_t checked = 0;
    for (const std::string g : {"slope", "arc", "barrier", "total"})
        for (const char* c : {"x", "y"}) {
            const size_t v = column(f, std::string("f") + c + "_" + g + "_N_per_m");
            const size_t hi = column(f, std::string("f") + c + "_" + g + "_max_N_per_m");
            const size_t lo = column(f, std::string("f") + c + "_" + g + "_min_N_per_m");
            for (const auto& row : f.rows) {
                EXPECT_GE(row[hi], row[v]) << g << c << " t = " << row[0];
                EXPECT_LE(row[lo], row[v]) << g << c << " t = " << row[0];
                ++checked;
            }
        }
    EXPECT_GT(checked, 1000u);
    EXPECT_GE(r.peak_fx_barrier, r.peak_fx_barrier_sampled);
    EXPECT_GE(r.peak_fy_arc, r.peak_fy_arc_sampled);
    EXPECT_GT(r.peak_fx_barrier, 0.0);
    // the largest of the rows' maxima of |fx| on the barrier is the summary's peak
    double largest = 0;
    for (const auto& row : f.rows)
        largest = std::max({largest, row[column(f, "fx_barrier_max_N_per_m")], -row[column(f, "fx_barrier_min_N_per_m")]});
    EXPECT_NEAR(largest, r.peak_fx_barrier, 1e-9 * r.peak_fx_barrier);  // forces.csv keeps 10 digits
    const auto [dir2, r2] = run("extremes-2ms", "0.002", 1);
    const auto [dir3, r3] = run("extremes-2-threads", "0.005", 2);
    for (const RunSummary* o : {&r2, &r3}) {
        EXPECT_EQ(o->peak_fx_barrier, r.peak_fx_barrier);
        EXPECT_EQ(o->t_peak_fx_barrier, r.t_peak_fx_barrier);
        EXPECT_EQ(o->peak_fy_arc, r.peak_fy_arc);
        EXPECT_EQ(o->t_peak_fy_arc, r.t_peak_fy_arc);
    }
    EXPECT_EQ(demlab::test::read_file(dir / "forces.csv"), demlab::test::read_file(dir3 / "forces.csv"));
    // the impulse-filtered peak (output.load_window 0.05 s): below the every-step one, the same
    // bits for any sampling and thread count, and bracketed by what forces.csv's impulses give
    // over its rows (5 ms apart)
    EXPECT_GT(r.peak_fx_barrier_filtered, 0.0);
    EXPECT_LT(r.peak_fx_barrier_filtered, r.peak_fx_barrier);
    for (const RunSummary* o : {&r2, &r3}) {
        EXPECT_EQ(o->peak_fx_barrier_filtered, r.peak_fx_barrier_filtered);
        EXPECT_EQ(o->t_peak_fx_barrier_filtered, r.t_peak_fx_barrier_filtered);
        EXPECT_EQ(o->peak_fy_arc_filtered, r.peak_fy_arc_filtered);
    }
    // The barrier is only pushed, so its x-impulse is monotone. The filter divides the impulse
    // gained from the last step at or before t - W to t by that span (W to W + dt): at a row's
    // time it is at least the gain over the 10 rows before over their span, less a step's share;
    // between rows it is at most the gain over the 12 rows around the window (W, a row's grain
    // at each end, and a step) over W.
    const size_t ix = column(f, "ix_barrier_Ns_per_m");
    const double W = 0.05;
    double over_10 = 0, over_12 = 0;
    for (size_t b = 10; b < f.rows.size(); ++b)
        over_10 = std::max(over_10, std::abs(f.rows[b][ix] - f.rows[b - 10][ix]) / (f.rows[b][0] - f.rows[b - 10][0]));
    for (size_t b = 12; b < f.rows.size(); ++b) over_12 = std::max(over_12, std::abs(f.rows[b][ix] - f.rows[b - 12][ix]) / W);
    EXPECT_GE(r.peak_fx_barrier_filtered, over_10 * (1.0 - 1e-3));
    EXPECT_LE(r.peak_fx_barrier_filtered, over_12);
    for (const fs::path& d : {dir, dir2, dir3}) fs::remove_all(d);
}

// The filtered load is exactly the impulse gained over the window divided by its span: from
// the last step at or before t - W to t. Synthetic impulses I(t) = 3 t^2 + t on steps of 0.01 s
// (W = 0.05 s); a filter saved and loaded mid-run (a checkpoint) goes on to the same bits.
TEST(BarrierOutputs, FilteredLoadIsTheImpulseGainedOverTheWindow) {
    const double W = 0.05, dt = 0.01;
    LoadFilter filter(W), first_half(W);
    auto impulse = [](double t) { return 3.0 * t * t + t; };
    std::vector<double> times;
    for (int k = 0; k <= 100; ++k) times.push_back(double(k) * dt);
    BinaryWriter saved;
    for (size_t k = 0; k < times.size(); ++k) {
        const double t = times[k];
        filter.step(t, impulse(t), -2.0 * impulse(t));
        if (k <= 40) first_half.step(t, impulse(t), -2.0 * impulse(t));
        if (k == 40) first_half.save(saved);
        // the window's start: the last step at or before t - W
        size_t a = 0;
        bool whole = false;
        for (size_t j = 0; j <= k; ++j)
            if (times[j] <= t - W) {
                a = j;
                whole = true;
            }
        if (!whole) {
            EXPECT_TRUE(std::isnan(filter.fx_barrier)) << "t = " << t;
            continue;
        }
        const double expected = (impulse(t) - impulse(times[a])) / (t - times[a]);
        EXPECT_EQ(filter.fx_barrier, expected) << "t = " << t;
        EXPECT_EQ(filter.fy_arc, (-2.0 * impulse(t) - -2.0 * impulse(times[a])) / (t - times[a])) << "t = " << t;
        EXPECT_GE(t - times[a], W - 1e-12);
        EXPECT_LT(t - times[a], W + dt);
    }
    EXPECT_EQ(filter.t_peak_fx_barrier, 1.0);  // the load grows: its largest at the end
    EXPECT_GT(filter.peak_fy_arc, filter.peak_fx_barrier);
    // the checkpointed half, restored into a new filter, ends as the uninterrupted one
    LoadFilter resumed(W);
    BinaryReader in(saved.bytes(), "test");
    resumed.load(in);
    for (size_t k = 41; k < times.size(); ++k) resumed.step(times[k], impulse(times[k]), -2.0 * impulse(times[k]));
    EXPECT_EQ(resumed.peak_fx_barrier, filter.peak_fx_barrier);
    EXPECT_EQ(resumed.t_peak_fx_barrier, filter.t_peak_fx_barrier);
    EXPECT_EQ(resumed.fx_barrier, filter.fx_barrier);
    EXPECT_EQ(resumed.peak_fy_arc, filter.peak_fy_arc);
}
