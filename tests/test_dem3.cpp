// The 3-D solver (src/dem3/world3.h) against DEBRIS' closed forms in 3-D: the mass and the bed
// and pair forces (D1-D3), the normal restitution of D9 on the bed and head-on, sliding down a
// plane of many triangles (D10), an undamped pile's energy and a gas's momentum, the same bits
// on 1 and 2 threads, and a saved state resumed to the same bits.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>

#include "dem3/world3.h"

using namespace demlab;

namespace {
constexpr double kDeg = kPi / 180.0;

template <class F>
std::shared_ptr<const Tin> terrain(int n, double cell, F f, double x0 = 0.0, double y0 = 0.0) {
    EsriGrid g;
    g.ncols = g.nrows = n + 1;
    g.cellsize = cell;
    g.x0 = x0;
    g.y0 = y0;
    for (int r = 0; r <= n; ++r)
        for (int c = 0; c <= n; ++c) g.z.push_back(f(x0 + c * cell, y0 + r * cell));
    return std::make_shared<const Tin>(Tin::from_grid(g, "test.asc"));
}

std::shared_ptr<const Tin> flat(double size = 100.0, double z = 0.0) {
    return terrain(10, size / 10, [z](double, double) { return z; }, -size / 2, -size / 2);
}
}  // namespace

TEST(Dem3, MassAndTheBedAndPairForcesOfD1ToD3) {
    const double E = 1e6;
    // bed: R = 1, d = 0.9: a^2 = 0.19, F = E pi 0.19 0.1 / 1
    EXPECT_NEAR(debris::sphere_force(E, 0.1, 1.0, 0.0), E * kPi * 0.19 * 0.1, 1e-9);
    EXPECT_NEAR(debris::sphere_stiffness(E, 0.1, 1.0, 0.0), E * kPi * 0.1 * (4.0 - 0.3), 1e-9);
    EXPECT_NEAR(debris::sphere_energy(E, 0.1, 1.0, 0.0), E * kPi * (2.0 * 0.001 / 3.0 - 0.0001 / 4.0), 1e-9);
    // equal pair: R = 1, d = 1.9: x = 0.95, a^2 = 1 - 0.9025
    EXPECT_NEAR(debris::sphere_force(E, 0.1, 1.0, 1.0), E * kPi * (1.0 - 0.9025) * 0.1 / 2.0, 1e-9);
    // unequal pair: Ri = 1, Rj = 2, d = 2.8: x = (7.84 + 1 - 4)/5.6
    const double x = (2.8 * 2.8 + 1.0 - 4.0) / 5.6;
    EXPECT_NEAR(debris::sphere_force(E, 0.2, 1.0, 2.0), E * kPi * (1.0 - x * x) * 0.2 / 3.0, 1e-8);
    // the stiffness is the force's derivative, the energy its integral
    const double h = 1e-6;
    EXPECT_NEAR(debris::sphere_stiffness(E, 0.2, 1.0, 2.0),
                (debris::sphere_force(E, 0.2 + h, 1.0, 2.0) - debris::sphere_force(E, 0.2 - h, 1.0, 2.0)) / (2 * h), 1e-3);
    double u = 0.0;
    for (int k = 0; k < 200000; ++k) u += debris::sphere_force(E, (k + 0.5) * 0.2 / 200000, 1.0, 2.0) * 0.2 / 200000;
    EXPECT_NEAR(debris::sphere_energy(E, 0.2, 1.0, 2.0) / u, 1.0, 1e-9);
    // the closed forms of the bed and an equal pair against the quadrature
    for (double rj : {0.0, 1.0}) {
        const double q = debris::gauss_energy([&](double s) { return debris::sphere_force(E, s, 1.0, rj); }, 0.1);
        EXPECT_NEAR(debris::sphere_energy(E, 0.1, 1.0, rj) / q, 1.0, 1e-12) << "rj " << rj;
    }
    // D1, and a sphere resting on the bed at the overlap where E pi a^2 delta / R = m g
    World3 w(Dem3Def{}, flat());
    w.add_sphere(Vec3(0, 0, 10), Vec3::Zero(), 10.0, 2000.0);
    EXPECT_DOUBLE_EQ(w.masses()[0], 4.0 / 3.0 * kPi * 1000.0 * 2000.0);
}

namespace {
// the rebound speed over the impact speed of a sphere meeting the bed at 1 m/s without gravity
double bed_restitution(double mu) {
    Dem3Def d;
    d.mu = mu;
    d.gravity = 0.0;
    d.safety = 0.05;
    d.youngs_modulus = 1e8;
    World3 w(d, flat());
    w.add_sphere(Vec3(0.3, -0.2, 1.001), Vec3(0, 0, -1.0), 1.0, 2000.0);
    for (int k = 0; k < 2000000 && (w.positions()[0].z() < 1.0005 || w.velocities()[0].z() < 0.0); ++k) w.step();
    return w.velocities()[0].norm();
}
double pair_restitution(double mu) {
    Dem3Def d;
    d.mu = mu;
    d.gravity = 0.0;
    d.safety = 0.05;
    d.youngs_modulus = 1e8;
    World3 w(d, flat(100.0, -50.0));
    w.add_sphere(Vec3(-1.001, 0, 0), Vec3(1.0, 0, 0), 1.0, 2000.0);
    w.add_sphere(Vec3(1.001, 0, 0), Vec3(-1.0, 0, 0), 1.0, 2000.0);
    for (int k = 0; k < 2000000 && (w.positions()[1].x() - w.positions()[0].x() < 2.001 || w.velocities()[0].x() > 0.0); ++k) w.step();
    return 0.5 * (w.velocities()[1].x() - w.velocities()[0].x());
}
}  // namespace

TEST(Dem3, NormalRestitutionOfD9OnTheBedAndHeadOn) {
    for (double mu : {0.3, 0.6}) {
        const double e = std::sqrt((1.0 - mu) / (1.0 + mu));
        EXPECT_NEAR(bed_restitution(mu) / e, 1.0, 0.01) << "bed, mu " << mu;
        EXPECT_NEAR(pair_restitution(mu) / e, 1.0, 0.01) << "pair, mu " << mu;
    }
    EXPECT_NEAR(bed_restitution(0.0), 1.0, 1e-3);  // elastic without friction
}

TEST(Dem3, SlidesDownAPlaneOfManyTrianglesAtTheClosedFormWithoutAJumpAtEdges) {
    // a 30 deg plane falling along a direction 17 deg off the grid's axes, 1,800 triangles
    const double slope = 30 * kDeg, az = 17 * kDeg;
    const Vec3 down(std::cos(az) * std::cos(slope), std::sin(az) * std::cos(slope), -std::sin(slope));
    const Vec3 normal(std::cos(az) * std::sin(slope), std::sin(az) * std::sin(slope), std::cos(slope));
    auto plane = [&](double x, double y) { return -std::tan(slope) * (x * std::cos(az) + y * std::sin(az)); };
    Dem3Def d;
    d.mu = 0.3;
    d.youngs_modulus = 4e10;
    const auto tin = terrain(30, 4.0, plane, -20.0, -20.0);
    World3 w(d, tin);
    const double R = 1.0, rho = 2000.0, m = 4.0 / 3.0 * kPi * rho;
    // at rest at the overlap that carries m g cos(30 deg): E pi (2R delta - delta^2) delta / R
    double delta = 1e-4;
    for (int k = 0; k < 60; ++k) {
        const double f = d.youngs_modulus * kPi * (2 * R * delta - delta * delta) * delta / R - m * d.gravity * std::cos(slope);
        delta -= f / debris::sphere_stiffness(d.youngs_modulus, delta, R, 0.0);
    }
    const Vec3 start(-10.0, -8.0, plane(-10.0, -8.0));
    w.add_sphere(start + (R - delta) * normal, Vec3::Zero(), R, rho);
    double n_min = INFINITY, n_max = 0.0;
    while (w.time() < 2.5) {
        w.step();
        const double n = w.bed_force(0).norm();
        n_min = std::min(n_min, n);
        n_max = std::max(n_max, n);
    }
    const double a = d.gravity * (std::sin(slope) - d.mu * std::cos(slope));
    // the velocity is at the half step t - dt/2
    const double t_half = w.time() - 0.5 * w.dt();
    EXPECT_NEAR(w.velocities()[0].dot(down) / (a * t_half), 1.0, 1e-3);
    EXPECT_LT(std::abs(w.velocities()[0].dot(normal)), 1e-6);
    const double travelled = (w.positions()[0] - start).dot(down);
    EXPECT_GT(travelled, 6.0);  // across many cells
    EXPECT_LT((n_max - n_min) / n_max, 1e-6) << n_min << " " << n_max;
}

namespace {
// a bowl z = (x^2 + y^2)/40 and 125 spheres dropped into it; centred at (x0, y0)
World3 pile(int threads, double mu, double safety = 0.8, double x0 = 0.0, double y0 = 0.0) {
    Dem3Def d;
    d.safety = safety;
    d.mu = mu;
    d.youngs_modulus = 1e9;
    d.threads = threads;
    World3 w(d, terrain(20, 2.0, [x0, y0](double x, double y) { return ((x - x0) * (x - x0) + (y - y0) * (y - y0)) / 40.0; },
                        x0 - 20.0, y0 - 20.0));
    for (int i = 0; i < 5; ++i)
        for (int j = 0; j < 5; ++j)
            for (int k = 0; k < 5; ++k)
                w.add_sphere(Vec3(x0 - 4.5 + 2.2 * i + 0.1 * k, y0 - 4.5 + 2.2 * j + 0.05 * k, 3.0 + 2.2 * k), Vec3::Zero(), 1.0, 2000.0);
    return w;
}
}  // namespace

// The same pile on a terrain in UTM coordinates (a northing of 5,000 km) runs as at the origin:
// the same contacts step by step and the same energies to rounding. The cells' keys counted the
// indices from zero in 21 bits: beyond 2^20 cells the y index ran into x's bits, and pairs
// were gathered twice (the kinetic energy off by a tenth).
TEST(Dem3, APileFarFromTheOriginRunsAsAtTheOrigin) {
    World3 here = pile(1, 0.3), there = pile(1, 0.3, 0.8, 6.0e5, 5.0e6);
    long differing = 0;
    while (here.time() < 1.0) {
        here.step();
        there.step();
        differing += here.contacts() != there.contacts() ? 1 : 0;
    }
    EXPECT_GT(here.contacts(), 0);
    EXPECT_EQ(differing, 0);
    EXPECT_NEAR(there.energy().kinetic, here.energy().kinetic, 1e-6 * std::abs(here.energy().potential));
}

TEST(Dem3, UndampedPileKeepsItsEnergyAndAGasItsMomentum) {
    for (double safety : {0.8, 0.3}) {
    World3 w = pile(1, 0.0, safety);
    w.step();
    const double e0 = w.energy().balance(), scale = std::abs(w.energy().potential);
    double worst = 0.0;
    long contact_steps = 0;
    while (w.time() < 4.0) {
        w.step();
        worst = std::max(worst, std::abs(w.energy().balance() - e0));
        contact_steps += w.contacts();
    }
    EXPECT_GT(contact_steps, 10000);  // (an elastic pile bounces: contacts come and go)
    EXPECT_LT(worst / scale, 0.01);
    RecordProperty("pile_energy_drift", std::to_string(worst / scale));
    std::printf("undamped pile, safety %.1f: %ld steps, %ld contact-steps, %zu lost, largest |balance - start| / |potential| = %.2e\n", safety, w.step_count(), contact_steps, w.lost_count(), worst / scale);
    }
    // a gas without gravity, far above the bed: the momentum stays
    Dem3Def d;
    d.mu = 0.0;
    d.gravity = 0.0;
    d.youngs_modulus = 1e9;
    World3 gas(d, flat(1000.0, -500.0));
    for (int i = 0; i < 6; ++i)
        for (int j = 0; j < 6; ++j)
            for (int k = 0; k < 3; ++k)
                gas.add_sphere(Vec3(2.1 * i, 2.1 * j, 2.1 * k), Vec3(std::sin(i + 3.0 * j), std::cos(7.0 * k + j), std::sin(5.0 * i * k)), 1.0, 2000.0);
    auto momentum = [&] {
        Vec3 p = Vec3::Zero();
        for (size_t i = 0; i < gas.size(); ++i) p += gas.masses()[i] * gas.velocities()[i];
        return p;
    };
    const Vec3 p0 = momentum();
    double scale_p = 0.0;
    for (size_t i = 0; i < gas.size(); ++i) scale_p += gas.masses()[i] * gas.velocities()[i].norm();
    long touched = 0;
    while (gas.time() < 5.0) {
        gas.step();
        touched += gas.contacts();
    }
    EXPECT_GT(touched, 0);
    EXPECT_LT((momentum() - p0).norm() / scale_p, 1e-12);
}

// A step that carries a sphere farther than half its radius stops the run (exit 3) naming the
// key: a 1 s step from rest dropped every sphere 9.8 m through the bed, and the run ended with
// exit 0 as "all spheres left the terrain"; a 0.1 s fixed step ran a blow-up to "rest".
TEST(Dem3, AStepThatCarriesASphereFartherThanHalfItsRadiusStopsTheRun) {
    for (const bool fixed : {false, true}) {
        Dem3Def d;
        d.youngs_modulus = 1e8;
        if (fixed) d.dt_fixed = 0.5;
        else d.dt_max = 1.0;
        World3 w(d, flat(100.0));
        w.add_sphere(Vec3(0.0, 0.0, 2.0), Vec3::Zero(), 0.5, 2000.0);
        try {
            w.step();
            ADD_FAILURE() << "a step of " << (fixed ? d.dt_fixed : d.dt_max) << " s was taken";
        } catch (const RunError& e) {
            const std::string m = e.what();
            EXPECT_NE(m.find(fixed ? "dem3.dt_fixed" : "dem3.dt_max"), std::string::npos) << m;
            EXPECT_NE(m.find("half its radius"), std::string::npos) << m;
        }
        // the same sphere at the default ceiling (0.01 s) falls onto the bed and stays on it
        Dem3Def sound;
        sound.youngs_modulus = 1e8;
        World3 ok(sound, flat(100.0));
        ok.add_sphere(Vec3(0.0, 0.0, 2.0), Vec3::Zero(), 0.5, 2000.0);
        while (ok.time() < 2.0) ok.step();
        EXPECT_EQ(ok.lost_count(), 0u);
    }
}

TEST(Dem3, ASphereIsLostWhereItLeavesTheTerrainAndTheLedgerStillCloses) {
    // a sphere sliding without friction off the edge of a flat 100 m terrain at 5 m/s: lost
    // within a step of its centre passing the edge by its radius, not after falling
    Dem3Def d;
    d.mu = 0.0;
    d.youngs_modulus = 1e9;
    World3 w(d, flat(100.0));
    w.add_sphere(Vec3(45.0, 0.0, 0.999), Vec3(5.0, 0.0, 0.0), 1.0, 2000.0);
    w.step();
    const double e0 = w.energy().balance();
    double worst = 0.0;
    while (w.lost_count() == 0 && w.time() < 5.0) {
        w.step();
        worst = std::max(worst, std::abs(w.energy().balance() - e0));
    }
    ASSERT_EQ(w.lost_count(), 1u);
    EXPECT_GT(w.positions()[0].x(), 51.0);
    EXPECT_LT(w.positions()[0].x(), 51.0 + 5.0 * w.dt() * 1.01);
    EXPECT_GT(w.positions()[0].z(), -1.0);  // it had barely begun to fall
    // the step it was lost in and the next: its energy counted once, at the leapfrog's level
    // (booked as m v^2 / 2 it was 7.4e-3 off)
    for (int k = 0; k < 3; ++k) {
        w.step();
        worst = std::max(worst, std::abs(w.energy().balance() - e0));
    }
    EXPECT_LT(worst / (0.5 * w.masses()[0] * 25.0), 1e-3);
}

TEST(Dem3, SameBitsOnOneAndTwoThreadsAndAfterAResume) {
    World3 a = pile(1, 0.3), b = pile(2, 0.3);
    for (int k = 0; k < 3000; ++k) {
        a.step();
        b.step();
    }
    ASSERT_EQ(a.size(), b.size());
    EXPECT_EQ(std::memcmp(a.positions().data(), b.positions().data(), a.size() * sizeof(Vec3)), 0);
    EXPECT_EQ(std::memcmp(a.velocities().data(), b.velocities().data(), a.size() * sizeof(Vec3)), 0);
    EXPECT_GT(a.contacts(), 50);
    // saved, loaded into a fresh world, and both run on
    BinaryWriter out;
    a.save_state(out);
    World3 c = pile(2, 0.3);
    BinaryReader in(out.bytes(), "state");
    c.load_state(in);
    for (int k = 0; k < 2000; ++k) {
        a.step();
        c.step();
    }
    EXPECT_EQ(std::memcmp(a.positions().data(), c.positions().data(), a.size() * sizeof(Vec3)), 0);
    EXPECT_EQ(a.energy().balance(), c.energy().balance());
}

// ---- a 3-D run through the run loop (scenario.solver = "dem3")

#include <csignal>
#include <filesystem>
#include <fstream>

#include "core/interrupt.h"
#include "files.h"
#include "resume.h"
#include "run/checkpoint_file.h"
#include "run/run.h"

namespace {
namespace fs = std::filesystem;
using test::read_file;

// a small slope of 20 x 20 cells of 2 m falling 20 deg towards +x into a flat floor, and a
// scenario releasing a 4 m thick layer of 1 m spheres on it
fs::path small_slide(const std::string& name) {
    const fs::path dir = test::temp_dir(name);
    fs::create_directories(dir);
    std::ofstream g(dir / "bed.asc");
    g << "ncols 21\nnrows 21\nxllcenter 0\nyllcenter 0\ncellsize 2\nNODATA_value -9999\n";
    for (int r = 20; r >= 0; --r) {
        for (int c = 0; c <= 20; ++c) g << (c ? " " : "") << std::max(0.0, (24.0 - 2.0 * c) * std::tan(20 * kDeg));
        g << '\n';
    }
    g.close();
    std::ofstream(dir / "slide.toml") << "[scenario]\nname = \"small slide\"\nsolver = \"dem3\"\n[dem3]\nterrain = \"bed.asc\"\n"
                                         "release_thickness = 4.0\nrelease_lo = [2.0, 14.0]\nrelease_hi = [10.0, 26.0]\n"
                                         "radius = 1.0\nyoungs_modulus = 1e9\n[stop]\nt_max = 30.0\n[output]\n"
                                         "series_interval = 0.1\nsnapshot_interval = 1.0\n";
    return dir;
}
}  // namespace

TEST(Dem3, ARunToRestWritesItsFolderAndResumesToTheSameBytes) {
    const fs::path dir = small_slide("dem3-run");
    Scenario s = load_scenario((dir / "slide.toml").string());
    finish_scenario(s);
    const fs::path ref = dir / "ref", cut = dir / "cut";
    const RunSummary r = run_scenario(s, {ref.string(), false, {}});
    EXPECT_EQ(r.stop_reason, "rest");
    EXPECT_GT(r.n_discs, 30);
    // one row an instant: the series' times rise strictly to the last
    const std::vector<double> t = test::csv_column(ref / "series.csv", "t_s");
    ASSERT_GT(t.size(), 10u);
    for (size_t k = 1; k < t.size(); ++k) EXPECT_LT(t[k - 1], t[k]) << "row " << k;
    for (const char* f : {"series.csv", "summary.json", "scenario.toml", "peak_thickness.asc", "peak_speed.asc", "deposit_thickness.asc",
                          "snapshots/terrain.vtp", "snapshots/spheres.pvd", "snapshots/spheres_0000.vtp"})
        EXPECT_TRUE(fs::exists(ref / f)) << f;
    // the deposit raster holds the release's bulk volume
    const EsriGrid deposit = read_esri_grid((ref / "deposit_thickness.asc").string());
    double volume = 0.0;
    for (double h : deposit.z) volume += h * 4.0;
    const std::string summary = read_file(ref / "summary.json");
    const size_t at = summary.find("\"release_bulk_volume\": ");
    ASSERT_NE(at, std::string::npos);
    EXPECT_NEAR(volume / std::stod(summary.substr(at + 23)), 1.0, 1e-5);
    // stopped by a signal at its third snapshot, resumed on 2 threads: the same bytes
    RunOptions ro{cut.string(), false, [](const std::string&, const std::string&, int index) {
                      if (index == 2) request_interrupt(SIGTERM);
                  }};
    ro.handle_signals = true;
    EXPECT_THROW(run_scenario(s, ro), Interrupted);
    ASSERT_TRUE(fs::exists(cut / kCheckpointFile));
    const RunSummary resumed = test::resume_run(cut, 2);
    EXPECT_EQ(resumed.stop_reason, "rest");
    for (const char* f : {"series.csv", "peak_thickness.asc", "peak_speed.asc", "deposit_thickness.asc", "snapshots/spheres_0005.vtp"})
        EXPECT_EQ(read_file(ref / f), read_file(cut / f)) << f << " differs";
    fs::remove_all(dir);
}

TEST(Dem3, BadScenariosAreRefusedBeforeAnyOutput) {
    const fs::path dir = small_slide("dem3-bad");
    auto refused = [&](const std::string& key_value, const std::string& needle) {
        Scenario s = load_scenario((dir / "slide.toml").string());
        try {
            for (size_t a = 0, b; a <= key_value.size(); a = b + 1) {  // overrides split by ';'
                b = std::min(key_value.find(';', a), key_value.size());
                apply_override(s, key_value.substr(a, b - a));
            }
            finish_scenario(s);
            run_scenario(s, {(dir / "out").string(), false, {}});
            ADD_FAILURE() << key_value << " was not refused";
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
        }
        EXPECT_FALSE(fs::exists(dir / "out")) << key_value;
    };
    refused("dem3.terrain=\"missing.asc\"", "missing.asc");
    // a missing file is named with the key that gave it (the message said terrain.grid)
    refused("dem3.terrain=\"missing.asc\"", "(dem3.terrain)");
    refused("dem3.terrain=\"missing.xyz\"", "(dem3.terrain)");
    refused("dem3.release_top=\"missing.asc\"", "(dem3.release_top)");
    refused("dem3.release_hi=[1.0, 26.0]", "release box");
    refused("dem3.release_lo=[100.0, 100.0]", "release box");
    refused("dem3.radius=-1", "dem3.radius");
    refused("dem3.release_thickness=0", "release_thickness");
    // a release too large to set up in a minute is refused at once (it ran for hours, or a box
    // of 1e9 m overflowed the counts into "holds no sphere")
    refused("dem3.radius=0.0001", "samples, more than");
    refused("dem3.release_lo=[-1e9, -1e9]", "samples, more than");
    refused("dem3.radius=0.05;dem3.release_thickness=400", "sites to test");
    fs::remove_all(dir);
}
