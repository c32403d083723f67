#include "geometry/wall.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "core/validate.h"

namespace demlab {

static double arc_extent_rad(double start_deg, double end_deg) {
    double ext = std::fmod(end_deg - start_deg, 360.0);
    if (ext < 0) ext += 360.0;
    return deg_to_rad(ext);
}

void validate(const WallDef& w, const std::string& where) {
    require_finite(where + ".velocity", w.velocity, "m/s");
    require_finite(where + ".move_from", w.move_from, "s");
    if (std::isnan(w.move_until)) throw InputError(where + ".move_until: must be a time in s or never");
    if (std::isnan(w.remove_at)) throw InputError(where + ".remove_at: must be a time in s or never");
    if (w.shape == WallShape::Segment) {
        require_finite(where + ".p0", w.p0, "m");
        require_finite(where + ".p1", w.p1, "m");
        if ((w.p1 - w.p0).norm() < 1e-9)
            throw InputError(where + ": zero-length segment from (" + format_number(w.p0.x()) + ", " +
                             format_number(w.p0.y()) + ") to itself; the ends must differ by > 1e-9 m");
    } else {
        require_finite(where + ".centre", w.centre, "m");
        require_positive(where + ".radius", w.radius, "m");
        require_finite(where + ".angle_start", w.angle_start_deg, "deg");
        require_finite(where + ".angle_end", w.angle_end_deg, "deg");
        // an arc is at most a full circle: 0 to 720 deg would be drawn once and read as twice
        if (std::abs(w.angle_end_deg - w.angle_start_deg) > 360.0)
            throw InputError(where + ": arc from " + format_number(w.angle_start_deg) + " to " + format_number(w.angle_end_deg) +
                             " deg sweeps " + format_number(std::abs(w.angle_end_deg - w.angle_start_deg)) +
                             " deg; the extent must be in (0, 360] deg");
        double ext = std::fmod(w.angle_end_deg - w.angle_start_deg, 360.0);
        if (std::abs(ext) < 1e-9 && std::abs(w.angle_end_deg - w.angle_start_deg) < 1e-9)
            throw InputError(where + ": arc of zero extent (angle_start = angle_end = " +
                             format_number(w.angle_start_deg) + " deg); the extent must be in (0, 360] deg");
    }
}

WallGeom make_geom(const WallDef& w) {
    WallGeom g;
    g.shape = w.shape;
    if (w.shape == WallShape::Segment) {
        g.p0 = w.p0;
        g.p1 = w.p1;
        g.length = (w.p1 - w.p0).norm();
        g.dir = (w.p1 - w.p0) / g.length;
        g.left = perp(g.dir);
        g.solid = w.segment_solid == SegmentSolid::Both ? 0 : (w.segment_solid == SegmentSolid::Left ? +1 : -1);
    } else {
        g.centre = w.centre;
        g.radius = w.radius;
        g.angle0 = deg_to_rad(w.angle_start_deg);
        g.extent = arc_extent_rad(w.angle_start_deg, w.angle_end_deg);
        if (g.extent == 0.0) g.extent = 2.0 * kPi;  // start = end + 360k: a full circle
        const double a1 = g.angle0 + g.extent;
        g.p0 = g.centre + g.radius * Vec2(std::cos(g.angle0), std::sin(g.angle0));
        g.p1 = g.centre + g.radius * Vec2(std::cos(a1), std::sin(a1));
        g.solid = w.arc_solid == ArcSolid::Outside ? +1 : -1;
    }
    return g;
}

void translate(WallGeom& g, const Vec2& d) {
    g.p0 += d;
    g.p1 += d;
    g.centre += d;
}

Vec2 tangent_at_start(const WallGeom& g) {
    if (g.shape == WallShape::Segment) return g.dir;
    return Vec2(-std::sin(g.angle0), std::cos(g.angle0));  // counter-clockwise
}

Vec2 tangent_at_end(const WallGeom& g) {
    if (g.shape == WallShape::Segment) return g.dir;
    const double a1 = g.angle0 + g.extent;
    return Vec2(-std::sin(a1), std::cos(a1));
}

// Contact with a corner point q: the normal runs from q to the disc centre.
static bool corner_contact(const Vec2& q, const Vec2& c, double r, WallHit& hit) {
    const Vec2 d = c - q;
    const double dist2 = d.squaredNorm();
    if (dist2 >= r * r || dist2 == 0.0) return false;
    const double dist = std::sqrt(dist2);
    hit.overlap = r - dist;
    hit.normal = d / dist;
    return true;
}

bool disc_wall_contact(const WallGeom& g, const Vec2& c, double r, WallHit& hit) {
    if (g.shape == WallShape::Segment) {
        const Vec2 rel = c - g.p0;
        const double s = rel.dot(g.dir);
        if (s < 0.0) return g.cap0 && corner_contact(g.p0, c, r, hit);
        if (s > g.length) return g.cap1 && corner_contact(g.p1, c, r, hit);
        const double h = rel.dot(g.left);  // signed distance, > 0 on the left
        if (g.solid == 0) {
            const double dist = std::abs(h);
            if (dist >= r) return false;
            hit.overlap = r - dist;
            hit.normal = h >= 0.0 ? g.left : Vec2(-g.left);
            return true;
        }
        // one-sided: the free side is opposite the solid one; h_free > 0 on the free side
        const double h_free = g.solid > 0 ? -h : h;
        if (h_free >= r || h_free <= -r) return false;  // clear, or crossed by more than a radius
        hit.overlap = r - h_free;
        hit.normal = g.solid > 0 ? Vec2(-g.left) : g.left;
        return true;
    }
    // arc
    const Vec2 d = c - g.centre;
    const double dist = d.norm();
    if (dist == 0.0) return false;
    double off = std::atan2(d.y(), d.x()) - g.angle0;
    off = std::fmod(off, 2.0 * kPi);
    if (off < 0.0) off += 2.0 * kPi;
    if (off > g.extent) {
        // beyond the arc: nearer to the end point or to the start point?
        const double past_end = off - g.extent;
        const double before_start = 2.0 * kPi - off;
        if (past_end < before_start) return g.cap1 && corner_contact(g.p1, c, r, hit);
        return g.cap0 && corner_contact(g.p0, c, r, hit);
    }
    // signed distance from the arc to the disc centre, > 0 on the free side
    const double h_free = g.solid > 0 ? g.radius - dist : dist - g.radius;
    if (h_free >= r || h_free <= -r) return false;
    hit.overlap = r - h_free;
    hit.normal = g.solid > 0 ? Vec2(-d / dist) : Vec2(d / dist);
    return true;
}

Vec2 closest_point(const WallGeom& g, const Vec2& c) {
    if (g.shape == WallShape::Segment) {
        const double s = std::clamp((c - g.p0).dot(g.dir), 0.0, g.length);
        return g.p0 + s * g.dir;
    }
    const Vec2 d = c - g.centre;
    double off = std::fmod(std::atan2(d.y(), d.x()) - g.angle0, 2.0 * kPi);
    if (off < 0.0) off += 2.0 * kPi;
    if (off <= g.extent) return g.centre + g.radius * Vec2(std::cos(g.angle0 + off), std::sin(g.angle0 + off));
    return (off - g.extent < 2.0 * kPi - off) ? g.p1 : g.p0;
}

double wall_length(const WallGeom& g) {
    return g.shape == WallShape::Segment ? g.length : g.radius * g.extent;
}

void wall_piece_bounds(const WallGeom& g, double f0, double f1, Vec2& lo, Vec2& hi) {
    if (g.shape == WallShape::Segment) {
        const Vec2 a = g.p0 + f0 * g.length * g.dir;
        const Vec2 b = g.p0 + f1 * g.length * g.dir;
        lo = a.cwiseMin(b);
        hi = a.cwiseMax(b);
        return;
    }
    const double a0 = g.angle0 + f0 * g.extent;
    const double a1 = g.angle0 + f1 * g.extent;
    const Vec2 pa = g.centre + g.radius * Vec2(std::cos(a0), std::sin(a0));
    const Vec2 pb = g.centre + g.radius * Vec2(std::cos(a1), std::sin(a1));
    lo = pa.cwiseMin(pb);
    hi = pa.cwiseMax(pb);
    // include the circle's extreme points (angles k * 90 deg) that lie inside [a0, a1]
    for (int k = -8; k <= 16; ++k) {
        const double ak = k * 0.5 * kPi;
        if (ak > a0 && ak < a1) {
            const Vec2 p = g.centre + g.radius * Vec2(std::cos(ak), std::sin(ak));
            lo = lo.cwiseMin(p);
            hi = hi.cwiseMax(p);
        }
    }
}

}  // namespace demlab
