// Walls: arcs carry a resting disc's weight; a disc crossing tangent joints feels no spurious
// jump; the narrow phase of segment interiors, capped ends and arcs; moving and removed walls.
#include <gtest/gtest.h>

#include <algorithm>

#include "helpers.h"

using namespace demlab;
using namespace demlab::test;

TEST(ArcWall, DiscAtTheBottomCarriesExactlyItsWeight) {
    WorldDef def;
    def.rotation.model = 1;  // sticks where it lands: rolling without resistance would rock forever
    World w(def);
    const int m = w.add_material(material(0.4));
    const double R = 0.1, r = 0.003;
    w.add_wall(arc(w, Vec2(0, R), R, 200, 340, ArcSolid::Outside, 0.4));
    // a little off the bottom, so it has to roll back and settle
    w.add_disc({Vec2(0.01, R - std::sqrt((R - r) * (R - r) - 0.0001)), r, Vec2::Zero(), 0, 0, m});
    w.finalize();
    w.run(50000);
    const double weight = w.masses()[0] * 9.81;
    EXPECT_NEAR(w.wall_force(0).y(), -weight, 1e-6 * weight);
    EXPECT_NEAR(w.wall_force(0).x(), 0.0, 1e-6 * weight);
    EXPECT_LT(w.velocities()[0].norm(), 1e-6);
}

TEST(ArcWall, SlidingAcrossTangentJointsHasNoForceSpike) {
    // slope 30 deg down, a tangent arc of radius 0.5 m, slope 30 deg up: the flume's shape
    WorldDef def;
    def.rotation.model = 1;
    def.damping.beta_n = 0.5;
    def.damping.dp_mode = DashpotMode::NoShearWhileSliding;  // frictionless: always sliding
    World w(def);
    const int m = w.add_material(material(0.0));
    const double R = 0.5, th = deg_to_rad(30.0);
    const Vec2 c(0.0, R);
    const Vec2 a_start = c + R * Vec2(std::cos(deg_to_rad(240)), std::sin(deg_to_rad(240)));
    const Vec2 a_end = c + R * Vec2(std::cos(deg_to_rad(300)), std::sin(deg_to_rad(300)));
    const Vec2 down(std::cos(th), -std::sin(th)), up(std::cos(th), std::sin(th));
    // the slope's end 0.3 mm off the arc's start: joined (snapped) by the joint tolerance
    w.add_wall(segment(w, a_start - 0.3 * down, a_start + Vec2(0.0003, 0), 0.0, SegmentSolid::Right));
    w.add_wall(arc(w, c, R, 240, 300));
    w.add_wall(segment(w, a_end, a_end + 0.3 * up, 0.0, SegmentSolid::Right));
    const double r = 0.003, mass = 2672.0 * kPi * r * r, g = 9.81;
    const Vec2 nrm_slope(std::sin(th), std::cos(th));
    const double overlap = mass * g * std::cos(th) / 5e7;
    w.add_disc({a_start - 0.2 * down + (r - overlap) * nrm_slope, r, Vec2::Zero(), 0, 0, m});
    w.finalize();
    double worst_excess = 0.0, worst_deficit = 0.0;
    int steps_on_arc = 0;
    while (w.time() < 0.5 && w.positions()[0].x() < a_end.x() + 0.05) {
        w.step();
        const Vec2 p = w.positions()[0];
        Vec2 f = Vec2::Zero();
        for (int k = 0; k < 3; ++k) f += w.wall_force(k);
        const double n_force = f.norm();
        // the expected normal force: on a slope m g cos; on the arc m g cos(phi) + m v^2 / R
        const double v2 = w.velocities()[0].squaredNorm();
        const double on_slope = mass * g * std::cos(th);
        const double on_arc_max = mass * g + mass * v2 / R;
        const bool near_joint = std::abs(p.x() - a_start.x()) < 0.01 || std::abs(p.x() - a_end.x()) < 0.01;
        if (p.x() > a_start.x() && p.x() < a_end.x()) ++steps_on_arc;
        if (w.time() > 0.01 && near_joint) {
            worst_excess = std::max(worst_excess, n_force / on_arc_max - 1.0);
            worst_deficit = std::max(worst_deficit, 1.0 - n_force / on_slope);
        }
    }
    EXPECT_GT(steps_on_arc, 100);
    // a double contact at a joint would give ~ +100 %, a gap a drop to 0: allow the spring's
    // small response to the change of curvature
    EXPECT_LT(worst_excess, 0.10);
    EXPECT_LT(worst_deficit, 0.10);
}

TEST(NarrowPhase, SegmentInteriorEndsAndOneSidedness) {
    WallDef d = segment(Vec2(0, 0), Vec2(1, 0));
    WallGeom g = make_geom(d);
    WallHit hit;
    ASSERT_TRUE(disc_wall_contact(g, Vec2(0.5, 0.004), 0.005, hit));
    EXPECT_NEAR(hit.overlap, 0.001, 1e-15);
    EXPECT_EQ(hit.normal, Vec2(0, 1));
    ASSERT_TRUE(disc_wall_contact(g, Vec2(0.5, -0.004), 0.005, hit));  // two-sided
    EXPECT_EQ(hit.normal, Vec2(0, -1));
    // beyond the end: the end point is a corner, the normal points from it to the centre
    ASSERT_TRUE(disc_wall_contact(g, Vec2(1.003, 0.003), 0.005, hit));
    EXPECT_NEAR(hit.overlap, 0.005 - std::sqrt(2.0) * 0.003, 1e-15);
    EXPECT_NEAR(hit.normal.x(), std::sqrt(0.5), 1e-12);
    EXPECT_FALSE(disc_wall_contact(g, Vec2(1.004, 0.004), 0.005, hit));
    // an open end has no corner
    g.cap1 = false;
    EXPECT_FALSE(disc_wall_contact(g, Vec2(1.003, 0.003), 0.005, hit));
    // one-sided (solid on the right = below): a disc whose centre crossed is pushed back up
    d.segment_solid = SegmentSolid::Right;
    g = make_geom(d);
    ASSERT_TRUE(disc_wall_contact(g, Vec2(0.5, -0.002), 0.005, hit));
    EXPECT_NEAR(hit.overlap, 0.007, 1e-15);
    EXPECT_EQ(hit.normal, Vec2(0, 1));
}

TEST(NarrowPhase, ArcInsideAndOutside) {
    WallGeom g = make_geom(arc(Vec2(0, 0), 1.0, 180, 360, ArcSolid::Outside));
    WallHit hit;
    ASSERT_TRUE(disc_wall_contact(g, Vec2(0, -0.996), 0.005, hit));
    EXPECT_NEAR(hit.overlap, 0.001, 1e-12);
    EXPECT_NEAR(hit.normal.y(), 1.0, 1e-12);  // towards the centre
    EXPECT_FALSE(disc_wall_contact(g, Vec2(0, 0.996), 0.005, hit));  // upper half: no arc there
    g = make_geom(arc(Vec2(0, 0), 1.0, 180, 360, ArcSolid::Inside));
    ASSERT_TRUE(disc_wall_contact(g, Vec2(0, -1.004), 0.005, hit));
    EXPECT_NEAR(hit.overlap, 0.001, 1e-12);
    EXPECT_NEAR(hit.normal.y(), -1.0, 1e-12);
    // the arc's end point (1, 0) is a corner
    ASSERT_TRUE(disc_wall_contact(g, Vec2(1.003, 0.003), 0.005, hit));
    EXPECT_NEAR(hit.normal.x(), std::sqrt(0.5), 1e-12);
}

TEST(MovingWalls, RemovedGateReleasesAndLiftedGateMoves) {
    WorldDef def;
    def.rotation.model = 1;
    World w(def);
    const int m = w.add_material(material(0.3));
    w.add_disc({Vec2(0.0, 0.0), 0.005, Vec2(1.0, 0.0), 0, 0, m});
    WallDef gate = segment(w, Vec2(0.0052, -0.1), Vec2(0.0052, 0.1));
    gate.remove_at = 0.001;
    w.add_wall(gate);
    WallDef lifter = segment(w, Vec2(-0.5, -0.1), Vec2(-0.5, 0.1));
    lifter.velocity = Vec2(0.0, 2.25);
    w.add_wall(lifter);
    w.set_gravity(Vec2::Zero());
    w.finalize();
    while (w.time() < 0.0009) w.step();
    EXPECT_LT(w.velocities()[0].x(), 0.0);  // bounced off the gate
    // the lifted wall moved at 2.25 m/s
    EXPECT_NEAR(w.wall_geom(1).p0.y(), -0.1 + 2.25 * w.time(), 1e-9);
    World w2(def);
    const int m2 = w2.add_material(material(0.3));
    w2.add_disc({Vec2(0.0, 0.0), 0.005, Vec2(1.0, 0.0), 0, 0, m2});
    gate.remove_at = 0.0;
    gate.material = wall_material(w2, 0.0);
    w2.add_wall(gate);
    w2.set_gravity(Vec2::Zero());
    w2.finalize();
    w2.run(1000);
    EXPECT_DOUBLE_EQ(w2.velocities()[0].x(), 1.0);  // the gate was never there
    EXPECT_FALSE(w2.wall_active(0));
}
