// Bonds between spheres (the 3-D solver): which pairs CGAL's 3-D Delaunay triangulation bonds
// on a close-packed lattice, a bonded pair's period and its break against the closed forms
// (docs/spec/COHESION.md C6, C7, C12 with the spheres' face), and a bonded slab run through the
// run loop, stopped and resumed to the same bytes.
#include <gtest/gtest.h>

#include <cmath>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "core/interrupt.h"
#include "dem3/close_packing.h"
#include "dem3/sphere_bonds.h"
#include "dem3/world3.h"
#include "files.h"
#include "resume.h"
#include "run/checkpoint_file.h"
#include "output/plot.h"
#include "run/run.h"

using namespace demlab;

namespace {
std::shared_ptr<const Tin> flat_bed(double size, double z) {
    EsriGrid g;
    g.ncols = g.nrows = 11;
    g.cellsize = size / 10;
    g.x0 = g.y0 = -size / 2;
    g.z.assign(121, z);
    return std::make_shared<const Tin>(Tin::from_grid(g, "flat.asc"));
}

// every pair of the lattice at 2R, by brute force
std::vector<std::pair<int, int>> touching_pairs(const std::vector<Vec3>& c, double R) {
    std::vector<std::pair<int, int>> p;
    for (size_t i = 0; i < c.size(); ++i)
        for (size_t j = i + 1; j < c.size(); ++j)
            if (std::abs((c[j] - c[i]).norm() - 2 * R) < 1e-9 * R) p.emplace_back(int(i), int(j));
    return p;
}
}  // namespace

TEST(Dem3Bonds, TheTriangulationBondsEachSphereToItsTwelveNeighbours) {
    const double R = 0.5;
    auto bed = flat_bed(40.0, 0.0);
    auto top = [](double, double, double& z) {
        z = 3.0;
        return true;
    };
    const ClosePackedRelease rel = close_packed_release(*bed, top, Vec2(-3, -3), Vec2(3, 3), R);
    ASSERT_GT(rel.centres.size(), 100u);
    const std::vector<double> radii(rel.centres.size(), R);
    BondBuildReport rep;
    const auto bonds = delaunay_bonds3(rel.centres, radii, BondBuildDef{}, &rep);
    EXPECT_EQ(rep.dimension, 3);
    // exactly the pairs at 2R: the octahedra's diagonals (2 sqrt(2) R) and the hull's long
    // edges are filtered out, no neighbour is missed, on the faces neither
    EXPECT_EQ(bonds, touching_pairs(rel.centres, R));
    std::vector<int> count(rel.centres.size(), 0);
    for (auto [k, l] : bonds) {
        ++count[size_t(k)];
        ++count[size_t(l)];
    }
    EXPECT_EQ(*std::max_element(count.begin(), count.end()), 12);
    EXPECT_NEAR(rep.mean_rest_length, 2 * R, 1e-12);
    std::printf("%zu spheres, %zu Delaunay edges (%zu kept), %zu bonds, %d inner spheres with 12\n", rel.centres.size(), rep.faces,
                rep.faces_kept, rep.bonds, int(std::count(count.begin(), count.end(), 12)));
    // one layer: coplanar centres, the triangles' sides, six neighbours inside
    std::vector<Vec3> layer;
    for (const Vec3& c : rel.centres)
        if (std::abs(c.z() - rel.centres.front().z()) < 1e-9) layer.push_back(c);
    const auto flat_bonds = delaunay_bonds3(layer, std::vector<double>(layer.size(), R), BondBuildDef{}, &rep);
    EXPECT_EQ(rep.dimension, 2);
    EXPECT_EQ(flat_bonds, touching_pairs(layer, R));
}

TEST(Dem3Bonds, ABondedPairOscillatesAtItsPeriodAndBreaksAtItsStrain) {
    // two spheres far above the bed without gravity, 2.5 m apart (no contact), one bond
    Dem3Def d;
    d.gravity = 0.0;
    d.mu = 0.0;
    d.dt_fixed = 1e-4;
    BondDef b;
    b.modulus = 1e5;
    b.max_strain = 0.2;
    b.area = BondArea::Rest;  // a linear spring k0 = E L0 / (2 sqrt 2)
    const double R = 1.0, L0 = 2.5, rho = 1000.0;
    const double m = 4.0 / 3.0 * kPi * R * R * R * rho, k0 = b.modulus * L0 / (2 * std::sqrt(2.0));
    auto pair = [&](double v) {
        World3 w(d, flat_bed(100.0, -50.0));
        w.add_sphere(Vec3(0, 0, 0), Vec3(-v, 0, 0), R, rho);
        w.add_sphere(Vec3(L0, 0, 0), Vec3(v, 0, 0), R, rho);
        w.set_bonds(b, {{0, 1}});
        return w;
    };
    // the period: 2 pi sqrt(m / (2 k0)) (the reduced mass m/2)
    const double period = 2 * kPi * std::sqrt(m / (2 * k0));
    World3 w = pair(0.01);
    w.step();
    const double e0 = w.energy().balance();
    double last = w.positions()[1].x() - w.positions()[0].x() - L0, first_up = -1, worst = 0;
    int ups = 0;
    while (w.time() < 6.2 * period) {
        w.step();
        const double now = w.positions()[1].x() - w.positions()[0].x() - L0;
        if (last < 0 && now >= 0) {  // upward crossings of the rest length
            if (ups == 0) first_up = w.time();
            ++ups;
            if (ups == 6) {
                EXPECT_NEAR((w.time() - first_up) / 5 / period, 1.0, 1e-3);
            }
        }
        last = now;
        worst = std::max(worst, std::abs(w.energy().balance() - e0));
    }
    EXPECT_EQ(ups, 6);
    EXPECT_LT(worst / (m * 0.01 * 0.01), 1e-3);  // the kinetic energy the pair started with
    EXPECT_EQ(w.intact_bonds(), 1u);
    // fast apart: breaks once past 20 %, holding k0 L0^2 eps^2 / 2 (C7 "rest"), the ledger closed
    World3 s = pair(3.0);
    s.step();
    const double s0 = s.energy().balance();
    while (s.time() < 1.0) s.step();
    ASSERT_EQ(s.bond_breaks().size(), 1u);
    const BondBreakEvent e = s.bond_breaks().front();
    EXPECT_GT(e.strain, 0.2);
    EXPECT_LT(e.strain, 0.2 + 2 * 3.0 * 1e-4 / L0);  // within one step's stretch
    EXPECT_NEAR(e.energy, k0 * L0 * L0 * e.strain * e.strain / 2, 1e-9 * e.energy);
    EXPECT_EQ(s.intact_bonds(), 0u);
    EXPECT_NEAR(s.energy().bond_broken, e.energy, 0.0);
    EXPECT_LT(std::abs(s.energy().balance() - s0) / s0, 1e-3);
    // after the break the spheres fly apart at a constant speed
    const double v1 = s.velocities()[1].x();
    for (int k = 0; k < 100; ++k) s.step();
    EXPECT_EQ(s.velocities()[1].x(), v1);
    // "current": the tangent k0 (1 + 2 eps) at rest, the same period at small amplitude
    b.area = BondArea::Current;
    World3 c = pair(0.001);
    double lc = -1, t_first = -1;
    int n = 0;
    while (c.time() < 3.2 * period) {
        c.step();
        const double now = c.positions()[1].x() - c.positions()[0].x() - L0;
        if (lc < 0 && now >= 0) {
            if (n == 0) t_first = c.time();
            if (++n == 4) {
                EXPECT_NEAR((c.time() - t_first) / 3 / period, 1.0, 2e-3);
            }
        }
        lc = now;
    }
    EXPECT_EQ(n, 4);
}

// ---- a bonded slab through the run loop

namespace {
namespace fs = std::filesystem;

// a 30-degree slope of 2 m cells breaking to a flat floor at x = 24 m, a 3 m slab of 0.5 m
// spheres in layers along the slope, bonded with AvaFrame's defaults (E 50 kPa, 20 %)
fs::path bonded_slab(const std::string& name) {
    const fs::path dir = test::temp_dir(name);
    fs::create_directories(dir);
    std::ofstream g(dir / "bed.asc");
    g << "ncols 21\nnrows 11\nxllcenter 0\nyllcenter 0\ncellsize 2\nNODATA_value -9999\n";
    for (int r = 10; r >= 0; --r) {
        for (int c = 0; c <= 20; ++c) g << (c ? " " : "") << std::max(0.0, (24.0 - 2.0 * c) * std::tan(kPi / 6));
        g << '\n';
    }
    g.close();
    std::ofstream(dir / "slab.toml") << "[scenario]\nname = \"bonded slab\"\nsolver = \"dem3\"\n[dem3]\nterrain = \"bed.asc\"\n"
                                        "release_thickness = 3.0\nrelease_lo = [2.0, 6.0]\nrelease_hi = [12.0, 14.0]\n"
                                        "release_layers = \"bed\"\nradius = 0.5\ndensity = 400\nyoungs_modulus = 1e9\nmu = 0.1\n"
                                        "[cohesion]\nenabled = true\n"
                                        "[stop]\nt_max = 5.0\n[output]\nseries_interval = 0.1\nsnapshot_interval = 0.5\n";
    return dir;
}
}  // namespace

TEST(Dem3Bonds, ABondedSlabBreaksAtTheSlopeBreakAndResumesToTheSameBytes) {
    const fs::path dir = bonded_slab("dem3-slab");
    Scenario s = load_scenario((dir / "slab.toml").string());
    finish_scenario(s);
    const fs::path ref = dir / "ref", cut = dir / "cut";
    const RunSummary r = run_scenario(s, {ref.string(), false, {}});
    EXPECT_GT(r.n_discs, 100);
    const std::string summary = test::read_file(ref / "summary.json");
    auto number = [&](const std::string& key) {
        const size_t at = summary.find("\"" + key + "\": ");
        EXPECT_NE(at, std::string::npos) << key;
        return at == std::string::npos ? NAN : std::stod(summary.substr(at + key.size() + 4));
    };
    const double bonds = number("bonds"), broken = number("bonds_broken");
    EXPECT_GT(bonds, 4.0 * double(r.n_discs));  // close-packed: six a sphere inside, fewer on the faces
    // it slides whole down the slope (its centre 10 m on by 3 s), and breaks up where the slope
    // ends on the floor
    const std::vector<double> t = test::csv_column(ref / "series.csv", "t_s"),
                              intact = test::csv_column(ref / "series.csv", "intact_bonds"),
                              x = test::csv_column(ref / "series.csv", "centre_x_m");
    for (size_t k = 0; k < t.size(); ++k)
        if (t[k] <= 3.0) {
            EXPECT_GT(intact[k], 0.99 * bonds) << "at " << t[k] << " s";
        }
    const size_t at3 = size_t(std::lower_bound(t.begin(), t.end(), 3.0) - t.begin());
    EXPECT_GT(x[at3] - x.front(), 8.0);
    EXPECT_GT(broken, 0.2 * bonds);
    // the ledger closes with the bonds' terms in it
    const std::vector<double> balance = test::csv_column(ref / "series.csv", "balance_J"),
                              potential = test::csv_column(ref / "series.csv", "potential_J");
    const double drop = potential.front() - potential.back();
    ASSERT_GT(drop, 0.0);
    for (double b : balance) EXPECT_LT(std::abs(b - balance.front()) / drop, 0.02);
    const std::string breaks = test::read_file(ref / "bond_breaks.csv");
    EXPECT_EQ(std::count(breaks.begin(), breaks.end(), '\n'), long(broken) + 1);
    EXPECT_NE(test::read_file(ref / "snapshots/spheres_0000.vtp").find("<Lines>"), std::string::npos);
    // stopped at its third snapshot, resumed on 2 threads: the same bytes
    RunOptions ro{cut.string(), false, [](const std::string&, const std::string&, int index) {
                      if (index == 2) request_interrupt(SIGTERM);
                  }};
    ro.handle_signals = true;
    EXPECT_THROW(run_scenario(s, ro), Interrupted);
    test::resume_run(cut, 2);
    for (const char* f : {"series.csv", "bond_breaks.csv", "deposit_thickness.asc", "snapshots/spheres_0009.vtp"})
        EXPECT_EQ(test::read_file(ref / f), test::read_file(cut / f)) << f << " differs";
    // the plots of a 3-D run: its motion and its bonds
    if (gnuplot_available()) {
        const std::vector<std::string> made = make_plots(ref.string(), 320, 200);
        for (const char* f : {"plots/motion.png", "plots/bonds.png"}) EXPECT_TRUE(fs::exists(ref / f)) << f;
        EXPECT_EQ(made.size(), 2u);
    }
    // explicit pairs and the predicted length are refused before any output
    for (const char* bad : {"cohesion.predict=true", "cohesion.bonds=[[0, 1]]"}) {
        Scenario b = load_scenario((dir / "slab.toml").string());
        apply_override(b, bad);
        EXPECT_THROW(finish_scenario(b), InputError) << bad;
    }
    // a filter that keeps no bond is refused before any output, as for discs
    {
        Scenario b = load_scenario((dir / "slab.toml").string());
        apply_override(b, "cohesion.filter=\"length\"");
        apply_override(b, "cohesion.max_bond_length=0.5");
        finish_scenario(b);
        try {
            run_scenario(b, {(dir / "none").string(), false, {}});
            ADD_FAILURE() << "a slab without bonds was run";
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find("gave no bond"), std::string::npos) << e.what();
        }
        EXPECT_FALSE(fs::exists(dir / "none"));
    }
    fs::remove_all(dir);
}

TEST(Dem3Bonds, ALatticeAlongTheBedRestsItsFirstLayerOnAPlaneSlope) {
    // a 30-degree plane whose fall line runs 20 degrees off the grid's x axis
    const double a = kPi / 6, phi = kPi / 9, R = 0.5;
    EsriGrid g;
    g.ncols = g.nrows = 41;
    g.cellsize = 1.0;
    for (int r = 0; r < 41; ++r)
        for (int c = 0; c < 41; ++c) g.z.push_back(30.0 - std::tan(a) * (c * std::cos(phi) + r * std::sin(phi)));
    const Tin bed = Tin::from_grid(g, "plane.asc");
    auto top = [&](double x, double y, double& z) {
        if (!bed.height_at(x, y, z)) return false;
        z += 3.0;
        return true;
    };
    const ClosePackedRelease rel = close_packed_release(bed, top, Vec2(10, 10), Vec2(30, 30), R, LatticeLayers::Bed);
    ASSERT_GT(rel.centres.size(), 300u);
    // distances from the plane: R and whole layers above it, the first layer full
    const Vec3 n = Vec3(std::tan(a) * std::cos(phi), std::tan(a) * std::sin(phi), 1.0).normalized();
    const double layer = 2.0 * std::sqrt(2.0 / 3.0) * R;
    size_t first = 0;
    for (const Vec3& p : rel.centres) {
        const double d = (p - Vec3(0, 0, 30.0)).dot(n) - R * (1.0 + 1e-6);
        const double k = std::round(d / layer);
        EXPECT_NEAR(d, k * layer, 1e-9);
        first += k == 0.0;
    }
    // the first layer covers the box's slope area at the close-packed layer's density
    const double area = 400.0 / n.z();
    EXPECT_NEAR(double(first) * 2.0 * std::sqrt(3.0) * R * R / area, 1.0, 0.1);
    // and the neighbours stay 2R apart (a rotation of the lattice)
    const auto pairs = touching_pairs(rel.centres, R);
    EXPECT_GT(pairs.size(), 4 * rel.centres.size());
    for (size_t i = 0; i < rel.centres.size(); ++i)
        for (size_t j = i + 1; j < rel.centres.size(); ++j) ASSERT_GT((rel.centres[j] - rel.centres[i]).norm(), 2 * R * (1 - 1e-9));
}
