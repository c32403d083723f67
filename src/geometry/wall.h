// Walls: line segments (PFC "standard walls") and circular arcs (PFC "general walls").
// A wall touches discs only. It may move with a prescribed velocity and may be removed at a
// given time (the flume's gate). The narrow phase disc-wall lives here too.
#pragma once
#include <limits>
#include <string>

#include "core/vec2.h"

namespace demlab {

enum class WallShape { Segment, Arc };

// Which side of a segment is solid, looking from p0 towards p1. Both: a thin plate that
// pushes discs away on either side. Left/Right: one-sided, the disc is always pushed to the
// free side, even if its centre has crossed the line (up to one radius).
enum class SegmentSolid { Both, Left, Right };

// Which side of an arc is solid. Outside: discs run on the inside of the circle (the
// flume's transition arc). Inside: discs run on the outside (a drum, a bump).
enum class ArcSolid { Outside, Inside };

// Whether a wall end acts as a corner that discs can touch. Auto: an end that meets another
// wall's end tangentially is open (the neighbour carries the disc across the joint, so the
// normal force does not jump); every other end is capped.
enum class EndCap { Auto, Capped, Open };

constexpr double kNever = std::numeric_limits<double>::infinity();

struct WallDef {
    std::string name;                       // for messages and output columns
    WallShape shape = WallShape::Segment;
    // segment
    Vec2 p0{0.0, 0.0};                      // m, first end
    Vec2 p1{1.0, 0.0};                      // m, second end
    SegmentSolid segment_solid = SegmentSolid::Both;
    // arc: counter-clockwise from angle_start to angle_end, angles from +x
    Vec2 centre{0.0, 0.0};                  // m
    double radius = 0.0;                    // m, > 0 for an arc
    double angle_start_deg = 0.0;           // deg
    double angle_end_deg = 0.0;             // deg, the arc's extent is (end - start) mod 360, in (0, 360]
    ArcSolid arc_solid = ArcSolid::Outside;
    // the wall's material: its index in the world (World::add_material), as a disc's; its
    // kn, ks and friction are the wall's own (in series with, and combined with, the disc's).
    // -1: none given, refused by World::add_wall.
    int material = -1;
    // motion
    Vec2 velocity{0.0, 0.0};                // m/s, prescribed translation velocity
    double move_from = 0.0;                 // s, the velocity applies from this time ...
    double move_until = kNever;             // s, ... until this time
    double remove_at = kNever;              // s, the wall disappears at this time (kNever: never)
    EndCap cap_start = EndCap::Auto;        // p0 of a segment, the start angle's end of an arc
    EndCap cap_end = EndCap::Auto;
};

// Refuses a zero-length segment, an arc of zero radius or zero extent, non-finite numbers.
// (The wall's material is checked by the world it is added to.)
void validate(const WallDef& w, const std::string& where);

// The wall's geometry as the contact loop uses it (all derived from WallDef and the wall's
// current displacement).
struct WallGeom {
    WallShape shape = WallShape::Segment;
    Vec2 p0, p1;        // segment ends, or the arc's end points
    Vec2 dir;           // segment: unit vector p0 -> p1
    Vec2 left;          // segment: perp(dir)
    double length = 0;  // segment length, m
    Vec2 centre;        // arc centre
    double radius = 0;
    double angle0 = 0;  // rad, start angle
    double extent = 0;  // rad, (0, 2 pi]
    int solid = 0;      // segment: 0 both, +1 solid on the left, -1 solid on the right; arc: +1 outside, -1 inside
    bool cap0 = true, cap1 = true;
};

WallGeom make_geom(const WallDef& w);
// Translates a geometry by d.
void translate(WallGeom& g, const Vec2& d);
// Tangent direction of the wall at its start (into the wall) and at its end (out of the wall).
Vec2 tangent_at_start(const WallGeom& g);
Vec2 tangent_at_end(const WallGeom& g);

// A disc-wall contact: overlap > 0 and the unit normal pointing from the wall to the disc.
struct WallHit {
    double overlap = 0.0;
    Vec2 normal{0.0, 0.0};
};

// Narrow phase: does a disc of centre c and radius r touch the wall?
bool disc_wall_contact(const WallGeom& g, const Vec2& c, double r, WallHit& hit);

// The point of the wall (ends included) nearest to c.
Vec2 closest_point(const WallGeom& g, const Vec2& c);

// Axis-aligned box of the part of the wall between fractions f0 and f1 of its length.
void wall_piece_bounds(const WallGeom& g, double f0, double f1, Vec2& lo, Vec2& hi);
// Length of the wall (segment length or arc length), m.
double wall_length(const WallGeom& g);

}  // namespace demlab
