// The walls of the lab set-ups: the flume of the study (W1 slope, W2 transition arc, W3
// barrier, W4 gate, W5 lid) and the dam break's column, with their release boxes. The set-ups
// (setup.h) build on these.
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

}  // namespace demlab
