// The deposit's surface over x (surface.csv): the bed's height at x over segments and a concave
// arc, and the surface of a mass filling a flume-like valley, against their closed forms; where
// deposit.csv's height normal to the bed stops at the arc's radius, surface.csv's depth does not.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "files.h"
#include "geometry/bed_path.h"
#include "helpers.h"
#include "run/measures.h"
#include "run/run.h"
#include "scenario/scenario.h"

using namespace demlab;
using namespace demlab::test;
namespace fs = std::filesystem;

namespace {

// The flume's shape: a slope 30 deg down, a tangent arc of radius R (centre (0, R), its bottom
// at the origin, 240 to 300 deg), a slope 30 deg up; each slope `len` long.
struct Valley {
    double R = 0.1, len = 0.4, th = deg_to_rad(30.0);
    Vec2 centre() const { return Vec2(0.0, R); }
    Vec2 arc_start() const { return centre() + R * Vec2(std::cos(deg_to_rad(240)), std::sin(deg_to_rad(240))); }
    Vec2 arc_end() const { return centre() + R * Vec2(std::cos(deg_to_rad(300)), std::sin(deg_to_rad(300))); }
    Vec2 top_left() const { return arc_start() - len * Vec2(std::cos(th), -std::sin(th)); }
    Vec2 top_right() const { return arc_end() + len * Vec2(std::cos(th), std::sin(th)); }
    // the bed's height at x, in closed form
    double bed(double x) const {
        if (x < arc_start().x()) return arc_start().y() + (arc_start().x() - x) * std::tan(th);
        if (x > arc_end().x()) return arc_end().y() + (x - arc_end().x()) * std::tan(th);
        return R - std::sqrt(R * R - x * x);
    }
    std::vector<WallGeom> parts() const {
        return {make_geom(segment(top_left(), arc_start())), make_geom(arc(centre(), R, 240, 300)),
                make_geom(segment(arc_end(), top_right()))};
    }
};

}  // namespace

TEST(BedPathHeight, FollowsTheSegmentsAndTheArcInClosedForm) {
    const Valley v;
    const BedPath path(v.parts());
    double lo, hi;
    path.x_span(lo, hi);
    EXPECT_NEAR(lo, v.top_left().x(), 1e-12);
    EXPECT_NEAR(hi, v.top_right().x(), 1e-12);
    for (double x = lo; x <= hi; x += 0.0037) {
        double y;
        ASSERT_TRUE(path.height_at(x, y)) << x;
        EXPECT_NEAR(y, v.bed(x), 1e-12) << x;
    }
    // the joints and the path's ends themselves
    for (const double x : {lo, v.arc_start().x(), 0.0, v.arc_end().x(), hi}) {
        double y;
        ASSERT_TRUE(path.height_at(x, y)) << x;
        EXPECT_NEAR(y, v.bed(x), 1e-12) << x;
    }
    double y;
    EXPECT_FALSE(path.height_at(lo - 0.01, y));
    EXPECT_FALSE(path.height_at(hi + 0.01, y));
}

TEST(BedPathHeight, AVerticalPartSpansNoXAndAnOverhangGivesItsUpperPart) {
    // a floor to x = 1, a vertical wall up to y = 0.5, and a ledge back over the floor to x = 0.6
    const BedPath path({make_geom(segment(Vec2(0, 0), Vec2(1, 0))), make_geom(segment(Vec2(1, 0), Vec2(1, 0.5))),
                        make_geom(segment(Vec2(1, 0.5), Vec2(0.6, 0.5)))});
    double y;
    ASSERT_TRUE(path.height_at(0.3, y));
    EXPECT_EQ(y, 0.0);
    ASSERT_TRUE(path.height_at(0.8, y));
    EXPECT_EQ(y, 0.5);
    EXPECT_FALSE(path.height_at(1.2, y));
}

// A hexagonal packing of discs (radius r, touching) fills the valley with the centres of its top
// row at y_top = 0.15 m, half as high again as the arc's radius above its bottom.
TEST(DepositSurface, AMassFillingTheArcStandsAtItsTopRowOverTheWholeValley) {
    const Valley v;
    WorldDef def;
    World w(def);
    const int m = w.add_material(material(0.5));
    const BedPath path(v.parts());
    const double r = 0.004, row = std::sqrt(3.0) * r, y_top = 0.15;
    const int rows = int(std::floor((y_top - r) / row));
    const double y0 = y_top - rows * row;  // the lowest row's centres
    std::vector<double> top_row_x;
    for (int j = 0; j <= rows; ++j) {
        const double y = y0 + j * row, shift = ((rows - j) % 2) * r;  // the top row has a disc at x = 0
        for (int i = -200; i <= 200; ++i) {
            const double x = shift + 2.0 * r * i;
            double s, h;
            path.project(Vec2(x, y), s, h);
            // inside the valley: at least a radius from the bed and above it
            if (h < r * 1.001 || y < v.bed(x)) continue;
            w.add_disc({Vec2(x, y), r, Vec2::Zero(), 0, 0, m});
            if (j == rows) top_row_x.push_back(x);
        }
    }
    ASSERT_GT(top_row_x.size(), 60u);  // the top row spans some 0.5 m
    Scenario s;
    s.output.deposit_bin = 0.002;
    const std::vector<Vec2> start = w.positions();
    const MeasureContext mc{s, &path, BarrierMarks{path.part_start(2), v.arc_end()}, ForceWalls{}, r, start};
    const fs::path dir = temp_dir("surface");
    fs::create_directories(dir);
    RunSummary sum;
    write_surface(w, mc, dir.string(), sum);
    write_deposit(w, mc, dir.string(), sum);

    const fs::path f = dir / "surface.csv";
    EXPECT_EQ(read_file_header(f), "x_m,bed_m,surface_m,depth_m");
    const std::vector<double> xs = csv_column(f, "x_m"), bed = csv_column(f, "bed_m"), surf = csv_column(f, "surface_m"),
                              depth = csv_column(f, "depth_m");
    const double lo = v.top_left().x();
    ASSERT_EQ(xs.size(), size_t(std::floor((v.top_right().x() - lo) / 0.002)) + 1);
    int over_top_row = 0, bare = 0;
    double depth_at_bottom = 0.0, deepest = 0.0, x_deepest = NAN;
    for (size_t k = 0; k < xs.size(); ++k) {
        const double x = lo + 0.002 * double(k);  // the grid (the file has 10 digits)
        EXPECT_NEAR(xs[k], x, 1e-9);
        EXPECT_NEAR(bed[k], v.bed(x), 1e-9) << x;
        EXPECT_NEAR(depth[k], surf[k] - bed[k], 1e-9) << x;
        // the top row's outline, where one of its discs covers x: no lower disc reaches it
        double top = -1.0;
        for (const double xc : top_row_x)
            if (std::abs(x - xc) <= r) top = std::max(top, y_top + std::sqrt(r * r - (x - xc) * (x - xc)));
        if (top > 0.0 && x > top_row_x.front() + r && x < top_row_x.back() - r) {
            EXPECT_NEAR(surf[k], top, 1e-9) << x;
            ++over_top_row;
        }
        if (std::abs(x) < 0.001) depth_at_bottom = depth[k];
        if (depth[k] > deepest) {
            deepest = depth[k];
            x_deepest = xs[k];
        }
        // above the mass on either slope: the bed itself, no depth
        if (v.bed(x) > y_top + 2.0 * r) {
            EXPECT_EQ(depth[k], 0.0) << x;
            EXPECT_EQ(surf[k], bed[k]) << x;
            ++bare;
        }
    }
    EXPECT_GT(over_top_row, 200);
    EXPECT_GT(bare, 80);  // some 47 samples on each slope
    // at the arc's bottom the mass is y_top + r deep (to rounding in the x grid)
    EXPECT_NEAR(depth_at_bottom, y_top + r, 1e-4);
    // deposit.csv's height normal to the bed cannot pass the arc's radius over the arc
    const std::vector<double> ss = csv_column(dir / "deposit.csv", "s_m"), hs = csv_column(dir / "deposit.csv", "height_m");
    for (size_t k = 0; k < ss.size(); ++k) {
        if (ss[k] > path.part_start(1) && ss[k] < path.part_start(2)) {
            EXPECT_LE(hs[k], v.R + 1e-6) << ss[k];
        }
    }
    EXPECT_GT(depth_at_bottom, 1.4 * v.R);
    // the summary's deepest point is the file's, at the arc's bottom
    EXPECT_NEAR(sum.deposit_max_depth, deepest, 1e-9);
    EXPECT_NEAR(sum.x_deposit_max_depth, x_deepest, 1e-9);
    EXPECT_LT(std::abs(sum.x_deposit_max_depth), r);
    fs::remove_all(dir);
}
