// The peak rasters (src/dem3/peak_rasters.h): AvaFrame's thickness (mass over bulk density and
// area) keeps the spheres' bulk volume exactly, cells own the squares around their nodes, the
// speed is mass-weighted, and the files read back as ESRI grids.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <random>

#include "dem3/peak_rasters.h"
#include "files.h"

using namespace demlab;

namespace {
EsriGrid grid(int cols, int rows, double cell) {
    EsriGrid g;
    g.ncols = cols;
    g.nrows = rows;
    g.x0 = 100.0;
    g.y0 = -50.0;
    g.cellsize = cell;
    g.z.assign(size_t(cols) * size_t(rows), 0.0);
    return g;
}
}  // namespace

TEST(PeakRasters, VolumeIsTheSpheresBulkVolumeAtAnyCellSize) {
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> ux(100.0 - 5.0 + 1e-6, 100.0 + 39 * 10.0 + 5.0 - 1e-6), uy(-55.0 + 1e-6, -50.0 + 29 * 10.0 + 5.0 - 1e-6),
        um(1e5, 9e5);
    std::vector<Vec3> p, v;
    std::vector<double> m;
    double total = 0.0;
    for (int i = 0; i < 2000; ++i) {
        p.emplace_back(ux(rng), uy(rng), 0.0);
        v.emplace_back(1.0, 2.0, 2.0);
        m.push_back(um(rng));
        total += m.back();
    }
    const double rho_bulk = 2000.0 * 0.7405;
    for (double cell : {10.0, 7.3, 41.0}) {
        // cells covering x [95, 495], y [-55, 245], where the spheres are
        EsriGrid g = grid(int(std::ceil(400.0 / cell)) + 1, int(std::ceil(300.0 / cell)) + 1, cell);
        g.x0 = 95.0 + 0.5 * cell;
        g.y0 = -55.0 + 0.5 * cell;
        PeakRasters r(g, rho_bulk);
        r.finish(p, v, m);
        EXPECT_NEAR(r.volume(r.deposit_thickness()) / (total / rho_bulk), 1.0, 1e-12) << "cell " << cell;
        EXPECT_NEAR(r.volume(r.peak_thickness()) / (total / rho_bulk), 1.0, 1e-12);
        for (double s : r.peak_speed()) EXPECT_TRUE(s == 0.0 || std::abs(s - 3.0) < 1e-12);
    }
}

TEST(PeakRasters, CellsOwnTheSquaresAroundTheirNodesAndSpeedIsMassWeighted) {
    PeakRasters r(grid(3, 2, 10.0), 1000.0);
    // node (1, 0) is at (110, -50): its cell spans x [105, 115), y [-55, -45)
    const std::vector<Vec3> p{Vec3(105.0, -50.0, 0), Vec3(114.999, -45.001, 3), Vec3(115.0, -50.0, 0), Vec3(0, 0, 0)};
    const std::vector<Vec3> v{Vec3(2, 0, 0), Vec3(0, 0, 4), Vec3(1, 0, 0), Vec3(9, 0, 0)};
    const std::vector<double> m{1000.0, 3000.0, 500.0, 7.0};
    r.sample(p, v, m);
    EXPECT_DOUBLE_EQ(r.peak_thickness()[1], 4000.0 / (1000.0 * 100.0));
    EXPECT_DOUBLE_EQ(r.peak_speed()[1], (1000.0 * 2 + 3000.0 * 4) / 4000.0);
    EXPECT_DOUBLE_EQ(r.peak_thickness()[2], 500.0 / (1000.0 * 100.0));
    EXPECT_DOUBLE_EQ(r.volume(r.peak_thickness()), 4.5);  // the sphere far outside is not counted
    // a later, thinner and faster sample raises the speed's peak, not the thickness'
    r.finish({Vec3(110, -50, 0)}, {Vec3(0, 8, 0)}, {100.0});
    EXPECT_DOUBLE_EQ(r.peak_thickness()[1], 0.04);
    EXPECT_DOUBLE_EQ(r.peak_speed()[1], 8.0);
    EXPECT_DOUBLE_EQ(r.deposit_thickness()[1], 0.001);
    EXPECT_DOUBLE_EQ(r.deposit_thickness()[2], 0.0);
}

TEST(PeakRasters, FilesReadBackAsGridsOnTheTerrainsCells) {
    PeakRasters r(grid(4, 3, 5.0), 1000.0);
    r.finish({Vec3(100, -50, 0), Vec3(115, -40, 0)}, {Vec3(3, 0, 0), Vec3(0, 1, 0)}, {25000.0, 50000.0});
    const auto dir = test::temp_dir("rasters");
    std::filesystem::create_directories(dir);
    r.write(dir.string());
    for (const char* name : {"peak_thickness.asc", "peak_speed.asc", "deposit_thickness.asc"}) {
        const EsriGrid g = read_esri_grid((dir / name).string());
        ASSERT_EQ(g.ncols, 4);
        ASSERT_EQ(g.nrows, 3);
        EXPECT_DOUBLE_EQ(g.x0, 100.0);
        EXPECT_DOUBLE_EQ(g.y0, -50.0);
        const std::vector<double>& want = std::string(name) == "peak_speed.asc" ? r.peak_speed() : std::string(name) == "peak_thickness.asc" ? r.peak_thickness() : r.deposit_thickness();
        for (size_t c = 0; c < want.size(); ++c) EXPECT_NEAR(g.z[c], want[c], 1e-6 * std::max(1.0, want[c])) << name << " cell " << c;
    }
    EXPECT_DOUBLE_EQ(r.peak_thickness()[0], 1.0);           // 25,000 kg / (1000 kg/m3 x 25 m2)
    EXPECT_DOUBLE_EQ(r.peak_thickness()[2 * 4 + 3], 2.0);   // node (3, 2) at (115, -40)
    std::filesystem::remove_all(dir);
}
