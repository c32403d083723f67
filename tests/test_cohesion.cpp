// Cohesive bonds from scenarios (docs/spec/COHESION.md section 5): the Delaunay filter's bond
// counts, a chain's mode, a pair pulled apart by constant forces, the spec's snow slab
// (1,388 discs, 3,802 bonds), a bonded run's outputs and its resume, and the refusals.
#include <gtest/gtest.h>

#include <cmath>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/error.h"
#include "core/interrupt.h"
#include "dem/bonds/bond_builder.h"
#include "dem/world.h"
#include "files.h"
#include "helpers.h"
#include "output/frame.h"
#include "output/render_run.h"
#include "setups/lattice_release.h"
#include "setups/setup.h"
#include "run/run.h"
#include "scenario/scenario.h"

using namespace demlab;
using demlab::test::expect_refused;
using demlab::test::csv_column;
using demlab::test::read_file;
using demlab::test::temp_dir;
namespace fs = std::filesystem;

namespace {
// n x m nodes of a triangular lattice of side L, turned by `deg` about the origin and shifted
std::vector<Vec2> hex_lattice(int n, int m, double L, double deg = 0.0, Vec2 shift = Vec2::Zero()) {
    const double a = deg * kPi / 180.0;
    std::vector<Vec2> p;
    for (int j = 0; j < m; ++j)
        for (int i = 0; i < n; ++i) {
            const Vec2 q((i + 0.5 * (j % 2)) * L, j * L * std::sqrt(3.0) / 2.0);
            p.push_back(Vec2(std::cos(a) * q.x() - std::sin(a) * q.y(), std::sin(a) * q.x() + std::cos(a) * q.y()) + shift);
        }
    return p;
}
size_t bonds_of(const std::vector<Vec2>& p, BondFilter filter = BondFilter::Triangular) {
    BondBuildDef d;
    d.filter = filter;
    return delaunay_bonds(p, std::vector<double>(p.size(), 0.05), d).size();
}
// The demonstration's slab cut to 4 rows and 10 m, its upper end kept, run for 8 s: the spec's
// polygon from its upper bed corner A, 10 m down the slope (u) and 0.9 m up from it (n)
Scenario four_row_slab() {
    Scenario s = load_scenario(std::string(DEMLAB_SOURCE_DIR) + "/scenarios/snow-slide-2d.toml");
    apply_override(s, "lattice_release.region=[[-47.8638, 29.9086], [-39.38332, 24.60941], [-38.90639, 25.37265], "
                      "[-47.38687, 30.67184]]");
    apply_override(s, "stop.t_max=8.0");
    return s;
}
Scenario slab(const std::string& extra_overrides = "") {
    Scenario s = load_scenario(std::string(DEMLAB_SOURCE_DIR) + "/tests/data/snow-slide-slab.toml");
    if (!extra_overrides.empty()) apply_override(s, extra_overrides);
    return s;
}
}  // namespace

// 541 bonds for a 20 x 10 hex patch (3nm - 2n - 2m + 1: the hull's long triangles dropped),
// also turned by -32 deg and shifted; 56 for a 5 x 5 square (40 sides and one diagonal per
// cell); 9 for 10 collinear centres (CGAL's 1-D triangulation).
TEST(Cohesion, DelaunayFilter) {
    EXPECT_EQ(bonds_of(hex_lattice(20, 10, 0.25)), 541u);
    EXPECT_EQ(bonds_of(hex_lattice(20, 10, 0.25, -32.0, Vec2(3.7, -1.2))), 541u);
    std::vector<Vec2> square, line;
    for (int j = 0; j < 5; ++j)
        for (int i = 0; i < 5; ++i) square.emplace_back(0.25 * i, 0.25 * j);
    EXPECT_EQ(bonds_of(square), 56u);
    for (int i = 0; i < 10; ++i) line.emplace_back(1.0 * i, 0.0);
    BondBuildReport r;
    EXPECT_EQ(delaunay_bonds(line, std::vector<double>(10, 0.05), BondBuildDef{}, &r).size(), 9u);
    EXPECT_EQ(r.dimension, 1);
    // "none" keeps the hull's triangles too; the same bonds whatever the input order
    EXPECT_GT(bonds_of(hex_lattice(20, 10, 0.25), BondFilter::None), 541u);
    std::vector<Vec2> reversed = hex_lattice(20, 10, 0.25);
    std::reverse(reversed.begin(), reversed.end());
    EXPECT_EQ(bonds_of(reversed), 541u);
}

// Ten discs on a line, 1 m apart, bonded in a chain, in their first mode: omega_1 =
// 2 sqrt(k0/m) sin(pi/20) = 6.92614 rad/s, period 0.907169 s within 0.2 %.
TEST(Cohesion, ChainMode1) {
    WorldDef d;
    d.gravity = Vec2::Zero();
    d.damping.beta_n = d.damping.beta_s = 0.0;
    d.rotation.model = 1;
    World w(d);
    MaterialDef m;
    m.density = 7500.0;
    w.add_material(m);
    for (int j = 0; j < 10; ++j) w.add_disc({{double(j), 0.0}, 0.05, Vec2::Zero(), 0.0, 0.0, 0});
    std::vector<Vec2> p;
    for (int j = 0; j < 10; ++j) p.emplace_back(double(j), 0.0);
    for (const auto& [k, l] : delaunay_bonds(p, std::vector<double>(10, 0.05), BondBuildDef{})) w.add_bond(k, l);
    ASSERT_EQ(w.bonds().size(), 9u);
    w.finalize();
    for (int j = 0; j < 10; ++j) w.set_position(j, {double(j) + 1e-5 * std::cos(kPi * (j + 0.5) / 10.0), 0.0});
    w.set_dt(1e-4);
    std::vector<double> crossings;
    double last = 1e-5;
    for (int s = 0; s < 40000; ++s) {
        w.step();
        const double u0 = w.positions()[0].x();
        if (last < 0.0 && u0 >= 0.0) crossings.push_back(w.time() - w.dt() * u0 / (u0 - last));
        last = u0;
    }
    ASSERT_GE(crossings.size(), 3u);
    const double period = (crossings.back() - crossings.front()) / double(crossings.size() - 1);
    EXPECT_NEAR(period, 0.907169, 0.002 * 0.907169);
}

// A bonded pair pulled apart by +-2000 N, settled by local damping: eps (1 + eps) =
// sqrt(3) F / (E t L0) gives eps = 0.0650505 ("current"); eps = F / (k0 L0) = 0.0692820 ("rest").
TEST(Cohesion, PairStretchedByForce) {
    for (const BondArea area : {BondArea::Current, BondArea::Rest}) {
        WorldDef d;
        d.gravity = Vec2::Zero();
        d.rotation.model = 1;
        d.bond.area = area;
        World w(d);
        MaterialDef m;
        m.density = 7500.0;
        w.add_material(m);
        w.add_disc({{0.0, 0.0}, 0.05, Vec2::Zero(), 0.0, 0.0, 0, {-2000.0, 0.0}});
        w.add_disc({{1.0, 0.0}, 0.05, Vec2::Zero(), 0.0, 0.0, 0, {2000.0, 0.0}});
        w.add_bond(0, 1);
        w.finalize();
        w.set_local_damping(0.7);
        w.run(20000);
        const double eps = w.positions()[1].x() - w.positions()[0].x() - 1.0;
        EXPECT_NEAR(eps, area == BondArea::Current ? 0.0650505 : 0.0692820, 1e-6);
    }
}

// The spec's slab (section 6): 8 rows of 174/173 discs on the lattice, 1,388 discs, 3,802
// bonds; its run writes the bonds' ledger terms, and a checkpoint taken mid-slide resumes to
// the same bytes.
TEST(Cohesion, SnowSlabCountsOutputsAndResume) {
    Scenario s = slab("stop.t_max=1.5");
    apply_override(s, "stop.rest_duration=0.2");
    apply_override(s, "output.snapshot_interval=0.25");
    finish_scenario(s);
    const fs::path ref = temp_dir("slab-ref"), cut = temp_dir("slab-cut");
    const RunSummary r = run_scenario(s, {ref.string(), false, {}});
    EXPECT_EQ(r.n_discs, 1388);
    EXPECT_EQ(r.bonds, 3802);
    EXPECT_LT(r.energy_balance_error, 0.01);
    const std::string energy = read_file(ref / "energy.csv");
    EXPECT_NE(energy.find(",bond_elastic_J_per_m,bond_break_loss_J_per_m,bonds_intact_fraction\n"), std::string::npos);
    EXPECT_TRUE(fs::exists(ref / "bonds_broken.csv"));
    EXPECT_NE(read_file(ref / "summary.json").find("\"bonds\": 3802"), std::string::npos);
    // the snapshots carry the intact bonds as line cells and each disc's intact and broken
    // bonds; they count the same bonds, and the frames colour by them
    for (const SnapshotEntry& e : list_snapshots(ref.string())) {
        const Frame f = read_frame(e.discs, e.walls);
        long intact = 0, broken = 0;
        for (size_t i = 0; i < f.pos.size(); ++i) {
            intact += f.bonds_intact[i];
            broken += f.bonds_broken[i];
        }
        EXPECT_EQ(intact, 2 * long(f.bonds.size()));
        EXPECT_EQ(long(f.bonds.size()) + broken / 2, 3802);
    }
    RenderRunOptions render;
    render.run_dir = ref.string();
    render.last_only = true;
    render.threads = 1;
    EXPECT_EQ(render_run(render), 1);  // the default colouring of a run with bonds: "bonds"

    RunOptions ro{cut.string(), false, [](const std::string&, const std::string&, int index) {
                      if (index == 3) request_interrupt(SIGTERM);
                  }};
    ro.handle_signals = true;
    EXPECT_THROW(run_scenario(s, ro), Interrupted);
    Scenario again = load_scenario((cut / "scenario.toml").string());
    finish_scenario(again);
    RunOptions rr{cut.string(), false, {}};
    rr.resume = true;
    run_scenario(again, rr);
    for (const char* f : {"forces.csv", "energy.csv", "bonds_broken.csv"})
        EXPECT_EQ(read_file(ref / f), read_file(cut / f)) << f;
    fs::remove_all(ref);
    fs::remove_all(cut);
}

TEST(Cohesion, BadInputIsRefusedWithTheKey) {
    const std::string two = "[[discs]]\nposition = [0, 0]\nradius = 0.05\n[[discs]]\nposition = [1, 0]\nradius = 0.05\n";
    auto load = [&](const std::string& text) {
        Scenario s = parse_scenario(two + text, "c.toml");
        finish_scenario(s);
    };
    expect_refused([&] { load("[cohesion]\nmodulus = 0\n"); }, {"cohesion.modulus", "must be in (0.0, 1e+12]"});
    expect_refused([&] { load("[cohesion]\nmax_strain = 0.6\n"); }, {"cohesion.max_strain", "must be in (0.0, 0.5]"});
    expect_refused([&] { load("[cohesion]\nenabled = true\nfilter = \"length\"\n"); }, {"cohesion.max_bond_length"});
    expect_refused([&] { load("[cohesion]\nenabled = true\nbonds = [[0, 2]]\n"); }, {"cohesion.bonds", "does not exist"});
    expect_refused([&] { load("[cohesion]\nenabled = true\nbonds = [[1, 1]]\n"); }, {"cohesion.bonds", "two different discs"});
    expect_refused([&] { load("[lattice_release]\nregion = [[0, 0], [1, 0]]\norigin = [0, 0]\nr_min = 0.1\n"); },
                   {"lattice_release.region", "at least 3"});
    expect_refused([&] { load("[lattice_release]\nregion = [[0, 0], [1, 1], [1, 0], [0, 1]]\norigin = [0, 0]\nr_min = 0.1\n"); },
                   {"lattice_release.region", "simple"});
    expect_refused([&] { load("[lattice_release]\nregion = [[0, 0], [1, 0], [0, 1]]\nr_min = 0.1\n"); }, {"lattice_release.origin"});
    expect_refused([&] { load("[lattice_release]\nregion = [[0, 0], [1, 0], [0, 1]]\norigin = [0, 0]\nr_min = 0.1\nspacing = 0.1\n"); },
                   {"lattice_release.spacing"});
    expect_refused([&] { load("[flume]\n[lattice_release]\nregion = [[0, 0], [1, 0], [0, 1]]\norigin = [0, 0]\nr_min = 0.1\n"); },
                   {"[lattice_release]"});
}

// The shipped demonstration (scenarios/snow-slide-2d.toml), to t = 5 s: the bonded slab
// slides down the slope whole (no bond breaks before its front reaches the toe, about 3.1 s)
// and breaks up at the slope break (more than 5 % of its bonds by 5 s; 12.1 % when measured).
TEST(Cohesion, ShippedSnowSlideSlidesWholeThenBreaksAtTheSlopeBreak) {
    Scenario s = load_scenario(std::string(DEMLAB_SOURCE_DIR) + "/scenarios/snow-slide-2d.toml");
    apply_override(s, "stop.t_max=5.0");
    apply_override(s, "output.snapshot_interval=0");
    s.world.threads = 2;
    finish_scenario(s);
    const fs::path dir = temp_dir("snow-slide");
    const RunSummary r = run_scenario(s, {dir.string(), false, {}});
    EXPECT_EQ(r.n_discs, 1388);
    EXPECT_EQ(r.bonds, 3802);
    const std::vector<double> breaks = csv_column(dir / "bonds_broken.csv", "t_s");
    const double first = breaks.empty() ? INFINITY : *std::min_element(breaks.begin(), breaks.end());
    const long broken = long(breaks.size());
    EXPECT_GT(first, 2.9);
    EXPECT_GT(double(broken), 0.05 * 3802);
    EXPECT_LT(r.energy_balance_error, 0.01);
    fs::remove_all(dir);
}

// The demonstration's slab cut to 4 rows and 10 m (its upper end kept), run for 8 s: it
// reaches the slope break and bonds break there; the energy they held is booked as
// bond_break_loss, and the ledger still closes to 1 % of the energy put in.
TEST(Cohesion, LedgerClosesWhileBreaking) {
    Scenario s = four_row_slab();
    apply_override(s, "output.snapshot_interval=0");
    finish_scenario(s);
    const fs::path dir = temp_dir("ledger-breaking");
    const RunSummary r = run_scenario(s, {dir.string(), false, {}});
    EXPECT_EQ(r.n_discs, 160);  // 4 rows of 40
    EXPECT_EQ(r.bonds, 3 * 160 - 2 * 40 - 2 * 4 + 1);
    EXPECT_GT(r.bonds_broken, 0);  // 178 when measured
    // energy.csv's last row: bond_break_loss > 0
    EXPECT_GT(csv_column(dir / "energy.csv", "bond_break_loss_J_per_m").back(), 0.0);
    EXPECT_LT(r.energy_balance_error, 0.01);
    fs::remove_all(dir);
}

// Variant C of the spec's section 6, small: a disordered 4-row slab (r in [0.1, 0.125] m on
// the 0.25 m lattice) settled under gravity behind a gate removed at t = 0, bonded by the
// "gap" filter. The discs leave their nodes, the bonds are built from the settled positions
// (no bond energy at t = 0), the mass starts at rest, and 1 and 2 threads give the same bytes.
TEST(Cohesion, LatticeSettlesBehindAGate) {
    const std::string text = std::string(R"(
[terrain]
profile = ")") + DEMLAB_SOURCE_DIR + R"(/data/snow-slide-profile.csv"
[[walls]]
name = "gate"
start = [-39.38332, 24.60941]
end = [-38.74742, 25.62707]
remove_at = 0.0
kn = 1e7
ks = 1e7
[lattice_release]
region = [[-47.8638, 29.9086], [-39.38332, 24.60941], [-38.90639, 25.37265], [-47.38687, 30.67184]]
origin = [-47.7425, 29.9802]
angle_deg = -32.0
r_min = 0.1
r_max = 0.125
spacing = 0.25
settle = true
[cohesion]
enabled = true
filter = "gap"
max_gap = 0.06
[material]
density = 330.8
kn = 1e7
ks = 1e7
friction_disc_deg = 18.0042
friction_wall_deg = 18.0042
wall_kn = 1e7
wall_ks = 1e7
[rotation]
model = 1
[release]
settle_max_time = 5.0
[stop]
t_max = 0.5
[output]
series_interval = 0.05
snapshot_interval = 0.5
)";
    std::string bytes[2];
    for (const int threads : {1, 2}) {
        Scenario s = parse_scenario(text, "settle.toml");
        s.world.threads = threads;
        finish_scenario(s);
        const fs::path dir = temp_dir("lattice-settle-" + std::to_string(threads));
        const RunSummary r = run_scenario(s, {dir.string(), false, {}});
        EXPECT_GT(r.bonds, 300);
        // energy.csv's first row: no kinetic energy, no bond energy (bonds from the settled state)
        EXPECT_EQ(csv_column(dir / "energy.csv", "kinetic_translation_J_per_m").front(), 0.0);
        // bond_elastic: round-off of the lengths only
        EXPECT_LT(csv_column(dir / "energy.csv", "bond_elastic_J_per_m").front(), 1e-20);
        const std::string summary = read_file(dir / "summary.json");
        EXPECT_EQ(summary.find("\"release_settle_time\": null"), std::string::npos) << summary;
        // the discs left their nodes: the first snapshot is not the lattice
        const Frame f = read_frame((dir / "snapshots/discs_00000.vtp").string(), (dir / "snapshots/walls_00000.vtp").string());
        Scenario unsettled = parse_scenario(text, "settle.toml");
        apply_override(unsettled, "lattice_release.settle=false");
        finish_scenario(unsettled);
        std::vector<WallDef> walls = make_setup(unsettled)->walls();
        walls.insert(walls.end(), unsettled.walls.begin(), unsettled.walls.end());
        const ReleaseMass nodes = lattice_mass(unsettled, walls);
        ASSERT_EQ(nodes.pos.size(), f.pos.size());
        double moved = 0.0;
        for (size_t i = 0; i < f.pos.size(); ++i) moved = std::max(moved, (f.pos[i] - nodes.pos[i]).norm());
        EXPECT_GT(moved, 0.01);
        bytes[threads - 1] = read_file(dir / "forces.csv") + read_file(dir / "energy.csv") + read_file(dir / "snapshots/discs_00001.vtp");
        fs::remove_all(dir);
    }
    EXPECT_EQ(bytes[0], bytes[1]);
    // a mass that cannot settle in the time allowed is refused with the keys to change
    Scenario s = parse_scenario(text, "settle.toml");
    apply_override(s, "release.settle_max_time=0.05");
    finish_scenario(s);
    const fs::path dir = temp_dir("lattice-unsettled");
    try {
        run_scenario(s, {dir.string(), false, {}});
        ADD_FAILURE() << "an unsettled lattice was run";
    } catch (const RunError& e) {
        EXPECT_NE(std::string(e.what()).find("release.settle_max_time"), std::string::npos) << e.what();
    }
    fs::remove_all(dir);
}

// A checkpoint taken while bonds are breaking (the 4-row slab breaks from 6.12 s to 7.30 s)
// resumes to the same bytes: the broken flags, the break events and the loss are state.
TEST(Cohesion, CheckpointWhileBreakingResumesToTheBytes) {
    Scenario s = four_row_slab();
    finish_scenario(s);
    const fs::path ref = temp_dir("breaking-ref"), cut = temp_dir("breaking-cut");
    run_scenario(s, {ref.string(), false, {}});
    RunOptions ro{cut.string(), false, [](const std::string&, const std::string&, int index) {
                      if (index == 13) request_interrupt(SIGTERM);  // the snapshot at 6.5 s
                  }};
    ro.handle_signals = true;
    EXPECT_THROW(run_scenario(s, ro), Interrupted);
    // the interrupted run had broken some bonds, not all that break: its energy series' last
    // intact fraction lies between 1 and the end's
    auto last_fraction = [](const fs::path& energy) { return csv_column(energy, "bonds_intact_fraction").back(); };
    fs::path partial;
    for (const auto& e : fs::directory_iterator(cut))
        if (e.path().filename().string().rfind("energy.csv", 0) == 0) partial = e.path();
    ASSERT_FALSE(partial.empty());
    const double at_cut = last_fraction(partial);
    EXPECT_LT(at_cut, 1.0);
    EXPECT_GT(at_cut, last_fraction(ref / "energy.csv"));
    Scenario again = load_scenario((cut / "scenario.toml").string());
    finish_scenario(again);
    RunOptions rr{cut.string(), false, {}};
    rr.resume = true;
    run_scenario(again, rr);
    for (const char* f : {"forces.csv", "energy.csv", "bonds_broken.csv", "deposit.csv", "snapshots/discs_00015.vtp"})
        EXPECT_EQ(read_file(ref / f), read_file(cut / f)) << f;
    fs::remove_all(ref);
    fs::remove_all(cut);
}
