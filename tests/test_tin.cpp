// The terrain as a TIN (src/dem3/tin.h): a sphere feels one contact on a plane made of many
// triangles wherever it is, one across a convex fold with a continuous distance, one on each
// face of a concave fold, the same from scattered points as from a grid; bad files refused.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <random>

#include "core/error.h"
#include "dem3/tin.h"
#include "files.h"

using namespace demlab;

namespace {
constexpr double kDeg = 3.14159265358979323846 / 180.0;

// a grid of n x n cells of side `cell` with z = f(x, y) at its nodes
template <class F>
EsriGrid grid_of(int n, double cell, F f) {
    EsriGrid g;
    g.ncols = g.nrows = n + 1;
    g.cellsize = cell;
    g.x0 = 0.0;
    g.y0 = 0.0;
    for (int r = 0; r <= n; ++r)
        for (int c = 0; c <= n; ++c) g.z.push_back(f(c * cell, r * cell));
    return g;
}

// the plane of slope 20 deg falling along a direction 17 deg off the grid's x axis
const double kSlope = std::tan(20 * kDeg), kCos = std::cos(17 * kDeg), kSin = std::sin(17 * kDeg);
double plane(double x, double y) { return kSlope * (x * kCos + y * kSin); }
const Vec3 kPlaneNormal = Vec3(-kSlope * kCos, -kSlope * kSin, 1.0).normalized();
}  // namespace

TEST(Tin, OneContactOnAPlaneOfManyTrianglesAndNoJumpAcrossEdges) {
    const Tin tin = Tin::from_grid(grid_of(20, 1.0, plane), "plane.asc");
    EXPECT_EQ(tin.triangles().size(), 800u);
    const double R = 1.0, h = 0.7;
    std::vector<TinContact> out;
    double f_min = INFINITY, f_max = -INFINITY;
    // a straight line across the grid at 31 deg, through edges, diagonals and corners
    for (int k = 0; k <= 4000; ++k) {
        const double s = 2.0 + 14.0 * k / 4000.0;
        const double x = s * std::cos(31 * kDeg) + 1.5, y = s * std::sin(31 * kDeg) + 1.0;
        const Vec3 foot(x, y, plane(x, y));
        const Vec3 centre = foot + h * kPlaneNormal;
        out.clear();
        tin.sphere_contacts(centre, R, out);
        ASSERT_EQ(out.size(), 1u) << "at s = " << s;
        EXPECT_NEAR(out[0].distance, h, 1e-12 * h) << "at s = " << s;
        EXPECT_LT((out[0].normal - kPlaneNormal).norm(), 1e-12) << "at s = " << s;
        const double force = kPi * (R * R - out[0].distance * out[0].distance) * (R - out[0].distance) / R;  // E = 1
        f_min = std::min(f_min, force);
        f_max = std::max(f_max, force);
    }
    EXPECT_LT((f_max - f_min) / f_max, 1e-6);
    // exactly above a grid node and on an edge: still one
    for (const Vec3& p : {Vec3(5, 5, plane(5, 5)), Vec3(5.5, 5, plane(5.5, 5)), Vec3(5.5, 5.5, plane(5.5, 5.5))}) {
        out.clear();
        tin.sphere_contacts(p + h * kPlaneNormal, R, out);
        ASSERT_EQ(out.size(), 1u);
        EXPECT_NEAR(out[0].distance, h, 1e-12);
    }
}

TEST(Tin, OneContactAcrossAConvexFoldWithAContinuousDistance) {
    // a ridge along x = 10: z = -0.1 |x - 10|, about 5.7 deg either side
    const Tin tin = Tin::from_grid(grid_of(20, 1.0, [](double x, double) { return -0.1 * std::abs(x - 10.0); }), "ridge.asc");
    auto exact = [](const Vec3& c) {
        // the distance to the profile's two half-lines in the x-z plane
        double best = INFINITY;
        for (double side : {-1.0, 1.0}) {
            const Vec2 a(10, 0), dir = Vec2(side, -0.1).normalized();
            const Vec2 p(c.x(), c.z());
            const double t = std::max(0.0, (p - a).dot(dir));
            best = std::min(best, (p - (a + t * dir)).norm());
        }
        return best;
    };
    std::vector<TinContact> out;
    for (int k = 0; k <= 2000; ++k) {
        const double x = 8.0 + 4.0 * k / 2000.0, y = 7.3;
        const Vec3 c(x, y, -0.1 * std::abs(x - 10.0) + 0.6);
        out.clear();
        tin.sphere_contacts(c, 1.0, out);
        ASSERT_EQ(out.size(), 1u) << "at x = " << x;
        EXPECT_NEAR(out[0].distance, exact(c), 1e-12) << "at x = " << x;
    }
}

TEST(Tin, ConcaveFoldTouchesBothFaces) {
    const double s = 0.3;  // a valley along x = 10
    const Tin tin = Tin::from_grid(grid_of(20, 1.0, [s](double x, double) { return s * std::abs(x - 10.0); }), "valley.asc");
    std::vector<TinContact> out;
    tin.sphere_contacts(Vec3(10.0, 6.4, 0.5), 1.0, out);
    ASSERT_EQ(out.size(), 2u);
    for (const TinContact& c : out) {
        EXPECT_NEAR(c.distance, 0.5 / std::sqrt(1 + s * s), 1e-12);
        EXPECT_NEAR(std::abs(c.normal.x()), s / std::sqrt(1 + s * s), 1e-12);
    }
    EXPECT_LT(out[0].normal.x() * out[1].normal.x(), 0.0);  // one from each side
}

TEST(Tin, ScatteredPointsGiveThePlaneAndItsHeights) {
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> u(0.0, 20.0);
    std::vector<Vec3> pts;
    for (double x : {0.0, 20.0})
        for (double y : {0.0, 20.0}) pts.emplace_back(x, y, plane(x, y));
    for (int i = 0; i < 300; ++i) {
        const double x = u(rng), y = u(rng);
        pts.emplace_back(x, y, plane(x, y));
    }
    const Tin tin = Tin::from_points(pts, "points.xyz");
    std::vector<TinContact> out;
    for (int k = 0; k < 500; ++k) {
        const double x = 2 + 16 * (k % 23) / 22.0, y = 2 + 16 * (k / 23) / 21.0;
        out.clear();
        tin.sphere_contacts(Vec3(x, y, plane(x, y)) + 0.4 * kPlaneNormal, 1.0, out);
        ASSERT_EQ(out.size(), 1u);
        EXPECT_NEAR(out[0].distance, 0.4, 1e-9);
        double z = 0;
        ASSERT_TRUE(tin.height_at(x, y, z));
        EXPECT_NEAR(z, plane(x, y), 1e-9);
    }
    double z = 0;
    EXPECT_FALSE(tin.height_at(-1.0, 5.0, z));
    // the grid's own nodes and the plane between them
    const Tin g = Tin::from_grid(grid_of(4, 2.5, [](double x, double y) { return x * x + y; }), "bowl.asc");
    ASSERT_TRUE(g.height_at(5.0, 7.5, z));
    EXPECT_NEAR(z, 25.0 + 7.5, 1e-12);
}

// A stray point far from the rest (a row of another coordinate system, a NODATA value) made
// the search's buckets as wide as the mean edge, which its fan of long edges had stretched to
// 115 m over a slope of 1 m spacing: a run 83 times slower. The buckets follow the median edge
// now. A point so far that its fan cannot be listed at that spacing widens them, and the
// terrain is searched all the same, with a warning naming the point.
TEST(Tin, AStrayPointIsSearchedAtTheTerrainsSpacingOrNamedInAWarning) {
    std::vector<Vec3> pts;
    for (int j = 0; j <= 40; ++j)
        for (int i = 0; i <= 150; ++i) pts.emplace_back(i, j, plane(i, j));
    auto contacts_are_right = [](const Tin& tin) {
        std::vector<TinContact> out;
        for (double x : {3.0, 75.5, 147.0}) {
            out.clear();
            tin.sphere_contacts(Vec3(x, 20.3, plane(x, 20.3)) + 0.4 * kPlaneNormal, 1.0, out);
            ASSERT_EQ(out.size(), 1u);
            EXPECT_NEAR(out[0].distance, 0.4, 1e-9);
        }
    };
    std::vector<Vec3> along = pts;
    along.emplace_back(1e5, 20.0, 0.0);
    testing::internal::CaptureStderr();
    const Tin tin = Tin::from_points(along, "stray.xyz");
    EXPECT_EQ(testing::internal::GetCapturedStderr(), "");
    EXPECT_LE(tin.search_bucket(), 2.0 * std::sqrt(2.0));
    contacts_are_right(tin);
    std::vector<Vec3> corner = pts;
    corner.emplace_back(1e5, 1e5, 0.0);
    testing::internal::CaptureStderr();
    const Tin wide = Tin::from_points(corner, "stray.xyz");
    const std::string said = testing::internal::GetCapturedStderr();
    EXPECT_NE(said.find("warning: stray.xyz: half the terrain's triangle edges are shorter than 1 m"), std::string::npos) << said;
    EXPECT_NE(said.find("point 6192 at (100000, 100000) is 141287 m from its nearest neighbour"), std::string::npos) << said;
    EXPECT_GT(wide.search_bucket(), 8.0);
    contacts_are_right(wide);
}

TEST(Tin, BadFilesAreRefusedWithTheirNames) {
    auto refused = [](const std::string& text, const std::string& needle) {
        test::TempFile f("terrain.xyz", text);
        try {
            const std::vector<Vec3> p = read_xyz_points(f.path());
            (void)Tin::from_points(p, f.path());
        } catch (const InputError& e) {
            const std::string what = e.what();
            EXPECT_NE(what.find(f.path()), std::string::npos) << what;
            EXPECT_NE(what.find(needle), std::string::npos) << what;
            return;
        }
        ADD_FAILURE() << "not refused: " << text;
    };
    refused("0 0 0\n1 0 x\n0 1 0\n", "'x' is not a finite number");
    refused("0 0 0\n1 0\n0 1 0\n", "2 values");
    refused("0 0 0\n1 0 nan\n0 1 0\n", "not a finite number");
    refused("# a comment\n0 0 0\n1 0 1\n0 1 0\n1 0 2\n", "the same x and y");
    refused("0 0 0\n1 1 0\n2 2 5\n", "one line");
    refused("0 0 0\n1 1 0\n", "at least 3");
    EsriGrid g = grid_of(3, 1.0, [](double, double) { return -9999.0; });
    g.has_nodata = true;
    try {
        (void)Tin::from_grid(g, "holes.asc");
        ADD_FAILURE() << "an all-NODATA grid was not refused";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("holes.asc"), std::string::npos);
    }
}

#include "dem3/close_packing.h"

TEST(ClosePack, TwelveNeighboursAtTwoRadiiAndTheLatticesDensity) {
    // a flat bed at z = 0 and a top 20 R above it over a 40 R x 40 R box
    const double R = 1.0;
    const Tin bed = Tin::from_grid(grid_of(10, 5.0, [](double, double) { return 0.0; }), "flat.asc");
    const auto top = [](double, double, double& z) {
        z = 20.0;
        return true;
    };
    const ClosePackedRelease r = close_packed_release(bed, top, Vec2(5.0, 5.0), Vec2(45.0, 45.0), R);
    ASSERT_GT(r.centres.size(), 1000u);
    EXPECT_NEAR(r.bulk_volume, 40.0 * 40.0 * 20.0, 1e-6);
    EXPECT_NEAR(r.solid_volume, double(r.centres.size()) * 4.0 / 3.0 * kPi, 1e-6);
    // no two closer than 2R, and every sphere well inside the box has twelve neighbours at 2R
    size_t inner = 0;
    for (size_t i = 0; i < r.centres.size(); ++i) {
        const Vec3& p = r.centres[i];
        EXPECT_GE(p.z(), R - 1e-9);
        EXPECT_LE(p.z(), 20.0 - R + 1e-9);
        int touching = 0;
        for (size_t j = 0; j < r.centres.size(); ++j) {
            if (j == i) continue;
            const double d = (r.centres[j] - p).norm();
            EXPECT_GE(d, 2.0 * R - 1e-9);
            touching += d < 2.0 * R + 1e-9;
        }
        const bool deep = p.x() > 10 && p.x() < 40 && p.y() > 10 && p.y() < 40 && p.z() > 4 && p.z() < 16;
        if (deep) {
            EXPECT_EQ(touching, 12) << "sphere " << i;
            ++inner;
        }
    }
    EXPECT_GT(inner, 200u);
    // the face-centred cubic lattice's number density, 1 / (4 sqrt(2) R^3), inside
    size_t in_core = 0;
    for (const Vec3& p : r.centres) in_core += p.x() >= 10 && p.x() < 40 && p.y() >= 10 && p.y() < 40 && p.z() >= 4 && p.z() < 16;
    EXPECT_NEAR(double(in_core) / (30.0 * 30.0 * 12.0) * 4.0 * std::sqrt(2.0), 1.0, 0.06);
}
