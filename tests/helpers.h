// Small builders shared by the tests.
#pragma once
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "core/error.h"
#include "dem/world.h"
#include "scenario/scenario.h"

// The sanitizer pass (scripts/test.sh) runs the suite several times slower than the Release
// pass (eight times for DB-9k). A test that only repeats at length what lighter tests also
// take through the sanitizers is left to the Release pass there, naming the tests that cover
// its code under the sanitizers.
#ifdef DEMLAB_SANITIZED
#define DEMLAB_RELEASE_PASS_ONLY(covered_by) \
    GTEST_SKIP() << "left to the Release pass: under the sanitizers " covered_by " take the same code"
#else
#define DEMLAB_RELEASE_PASS_ONLY(covered_by) static_cast<void>(0)
#endif

namespace demlab::test {

// A wall's geometry only (no material: for make_geom, or to be given one).
inline WallDef segment(Vec2 p0, Vec2 p1, SegmentSolid solid = SegmentSolid::Both) {
    WallDef w;
    w.shape = WallShape::Segment;
    w.p0 = p0;
    w.p1 = p1;
    w.segment_solid = solid;
    return w;
}

inline WallDef arc(Vec2 centre, double radius, double a0_deg, double a1_deg, ArcSolid solid = ArcSolid::Outside) {
    WallDef w;
    w.shape = WallShape::Arc;
    w.centre = centre;
    w.radius = radius;
    w.angle_start_deg = a0_deg;
    w.angle_end_deg = a1_deg;
    w.arc_solid = solid;
    return w;
}

// A wall material of world w: stiffnesses k (a wall's default, 1e8 N/m) and a friction
// coefficient; its index.
inline int wall_material(World& w, double friction, double k = 1e8) {
    MaterialDef m;
    m.kn = k;
    m.ks = k;
    m.friction = friction;
    return w.add_material(m);
}

// The same walls with a material of their own added to world w (add the discs' materials first).
inline WallDef segment(World& world, Vec2 p0, Vec2 p1, double friction = 0.0, SegmentSolid solid = SegmentSolid::Both) {
    WallDef w = segment(p0, p1, solid);
    w.material = wall_material(world, friction);
    return w;
}

inline WallDef arc(World& world, Vec2 centre, double radius, double a0_deg, double a1_deg, ArcSolid solid = ArcSolid::Outside,
                   double friction = 0.0) {
    WallDef w = arc(centre, radius, a0_deg, a1_deg, solid);
    w.material = wall_material(world, friction);
    return w;
}

inline MaterialDef material(double friction, double k = 1e8, double density = 2672.0) {
    MaterialDef m;
    m.friction = friction;
    m.kn = k;
    m.ks = k;
    m.density = density;
    return m;
}

// Runs f and expects an InputError whose message contains every fragment; the message (empty
// when f went ahead), for further checks.
inline std::string expect_refused(const std::function<void()>& f, const std::vector<std::string>& fragments) {
    try {
        f();
        ADD_FAILURE() << "accepted, expected an InputError";
    } catch (const InputError& e) {
        const std::string msg = e.what();
        for (const std::string& frag : fragments) EXPECT_NE(msg.find(frag), std::string::npos) << "message: " << msg;
        return msg;
    }
    return "";
}

// Restitution coefficient of the linear spring-dashpot for a damping ratio beta.
inline double restitution(double beta) { return std::exp(-kPi * beta / std::sqrt(1.0 - beta * beta)); }

// Geometry A at scale 20 (364 discs) for 0.01 s without snapshots: a run of a fraction of a
// second with a generated release mass, for the checks of saved masses.
inline Scenario short_geometry_a() {
    Scenario s = load_scenario(std::string(DEMLAB_SOURCE_DIR) + "/scenarios/geometry-A.toml");
    apply_override(s, "release.scale=20");
    apply_override(s, "stop.t_max=0.01");
    apply_override(s, "stop.rest_duration=0.005");
    apply_override(s, "output.snapshot_interval=0");
    finish_scenario(s);
    return s;
}

}  // namespace demlab::test
