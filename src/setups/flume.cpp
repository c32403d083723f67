#include "setups/flume.h"

#include <cmath>
#include <limits>

namespace demlab {

static void open_gate(const Scenario& s, WallDef& gate);

std::vector<WallDef> flume_walls(const Scenario& s, bool for_release) {
    const FlumeDef& f = s.flume;
    WallDef base;
    base.material = kWallMaterial;
    std::vector<WallDef> w(kFlumeWalls, base);
    // W1 runs down to the right: the flow is on its left, the solid on its right
    w[kW1].name = "W1_slope";
    w[kW1].p0 = f.w1_p0;
    w[kW1].p1 = f.w1_p1;
    w[kW1].segment_solid = SegmentSolid::Right;
    w[kW2].name = "W2_arc";
    w[kW2].shape = WallShape::Arc;
    w[kW2].centre = f.arc_centre;
    w[kW2].radius = f.arc_radius;
    w[kW2].angle_start_deg = f.arc_start_deg;
    w[kW2].angle_end_deg = f.arc_end_deg;
    w[kW2].arc_solid = ArcSolid::Outside;
    // W3 rises to the right: the flow is on its left (above)
    w[kW3].name = "W3_barrier";
    w[kW3].p0 = f.w3_p0;
    w[kW3].p1 = f.w3_p1;
    w[kW3].segment_solid = SegmentSolid::Right;
    // Join the slope and the barrier to the arc here (Table 2 is rounded to 0.1 mm), so the
    // release mass is generated against exactly the walls it will run on.
    const WallGeom arc = make_geom(w[kW2]);
    if ((w[kW1].p1 - arc.p0).norm() <= s.world.joint_tolerance) w[kW1].p1 = arc.p0;
    if ((w[kW3].p0 - arc.p1).norm() <= s.world.joint_tolerance) w[kW3].p0 = arc.p1;
    w[kGate].name = "W4_gate";
    w[kGate].p0 = f.gate_p0;
    w[kGate].p1 = f.gate_p1;
    w[kGate].cap_start = EndCap::Capped;
    w[kLid].name = "W5_lid";
    w[kLid].p0 = f.lid_p0;
    w[kLid].p1 = f.lid_p1;
    if (!for_release) {
        w[kLid].remove_at = 0.0;  // the lid goes: it only held the mass while it was generated
        open_gate(s, w[kGate]);
    }
    return w;
}

// The gate opens as in the flume: Variant I deletes it at t = 0, Variant II lifts it along its
// own direction at gate_speed and deletes it once it is a gate's height clear.
static void open_gate(const Scenario& s, WallDef& gate) {
    if (s.release.variant == "I") {
        gate.remove_at = 0.0;
    } else {
        const Vec2 up = (gate.p1 - gate.p0).normalized();
        gate.velocity = s.release.gate_speed * up;
        gate.move_from = 0.0;
        gate.remove_at = 2.0 * (gate.p1 - gate.p0).norm() / s.release.gate_speed;
    }
}

std::vector<WallDef> dam_break_walls(const Scenario& s, bool for_release) {
    const DamBreakDef& d = s.dam_break;
    WallDef base;
    base.material = kWallMaterial;
    std::vector<WallDef> w(4, base);
    w[kFloor].name = "floor";
    w[kFloor].p0 = Vec2(0.0, 0.0);
    w[kFloor].p1 = Vec2(d.floor_length, 0.0);
    w[kFloor].segment_solid = SegmentSolid::Right;  // free side up
    w[kBack].name = "back_wall";
    w[kBack].p0 = Vec2(0.0, d.height + 0.1);
    w[kBack].p1 = Vec2(0.0, 0.0);
    w[kBack].segment_solid = SegmentSolid::Right;  // free side +x
    w[kDamGate].name = "gate";
    w[kDamGate].p0 = Vec2(d.width, 0.0);
    w[kDamGate].p1 = Vec2(d.width, d.height);
    w[kDamGate].cap_start = EndCap::Capped;
    w[kDamLid].name = "lid";
    w[kDamLid].p0 = Vec2(d.width, d.height);
    w[kDamLid].p1 = Vec2(0.0, d.height);
    if (!for_release) {
        w[kDamLid].remove_at = 0.0;
        open_gate(s, w[kDamGate]);
    }
    return w;
}

ReleaseBox release_box(const Scenario& s) {
    ReleaseBox b;
    if (s.flume.enabled) {
        const auto w = flume_walls(s, true);
        b.polygon = {s.flume.w1_p0, s.flume.gate_p0, s.flume.gate_p1};
        b.walls = {w[kW1], w[kGate], w[kLid]};
        b.lid = 2;
    } else {
        const auto w = dam_break_walls(s, true);
        const DamBreakDef& d = s.dam_break;
        b.polygon = {Vec2(0, 0), Vec2(d.width, 0), Vec2(d.width, d.height), Vec2(0, d.height)};
        b.walls = w;
        b.lid = kDamLid;
    }
    return b;
}

}  // namespace demlab
