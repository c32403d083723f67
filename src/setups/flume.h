// The flume of the study: its walls (W1 slope, W2 transition arc, W3 barrier, W4 gate,
// W5 lid) from a scenario, and the path coordinate s along W1, W2, W3 that the measurements
// use (s = 0 at W1's upper end).
#pragma once
#include <vector>

#include "scenario/scenario.h"
#include "geometry/wall.h"

namespace demlab {

// Wall indices of a flume world (walls added in this order, explicit walls after them).
enum FlumeWall : int { kW1 = 0, kW2 = 1, kW3 = 2, kGate = 3, kLid = 4, kFlumeWalls = 5 };

// The five flume walls. The gate and lid are set up for the run (Variant I: the gate is
// removed at t = 0; Variant II: lifted at gate_speed); settling keeps them (see release.cpp).
std::vector<WallDef> flume_walls(const Scenario& s, bool for_release);

// Dam-break walls (indices): floor, back wall, gate, lid.
enum DamBreakWall : int { kFloor = 0, kBack = 1, kDamGate = 2, kDamLid = 3 };
std::vector<WallDef> dam_break_walls(const Scenario& s, bool for_release);

// The release box of a lab set-up: the (convex) polygon the mass fills and the walls that
// hold it while it is generated; `lid` indexes the lid among them.
struct ReleaseBox {
    std::vector<Vec2> polygon;
    std::vector<WallDef> walls;
    int lid = -1;
};
ReleaseBox release_box(const Scenario& s);

// The walls of a run (flume: W1, W2, W3, gate, lid; dam break: floor, back, gate, lid).
std::vector<WallDef> lab_walls(const Scenario& s);

// The flume's bed as a path: W1, the arc, W3 (as joined by the world).
class FlumePath {
public:
    FlumePath(const WallGeom& w1, const WallGeom& arc, const WallGeom& w3);
    // Projects a point onto the path: s along it (m) and h, the height above the bed on the
    // flow side (m, negative below the bed).
    void project(const Vec2& p, double& s, double& h) const;
    double s_arc_start() const { return l1_; }
    double s_barrier_start() const { return l1_ + l2_; }
    double length() const { return l1_ + l2_ + l3_; }
    Vec2 barrier_foot() const { return w3_.p0; }
    // The point of the bed at s and the unit normal into the flow there.
    void at(double s, Vec2& point, Vec2& normal) const;

private:
    WallGeom w1_, arc_, w3_;
    double l1_, l2_, l3_;
};

}  // namespace demlab
