#include "geometry/bed_path.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.h"

namespace demlab {

BedPath::BedPath(std::vector<WallGeom> parts) : parts_(std::move(parts)) {
    if (parts_.empty()) throw InputError("bed path: no parts");
    start_.assign(parts_.size() + 1, 0.0);
    // the first start is exactly 0 and each later one the sum in order, so s at a part is
    // start + t as the path's own length adds up
    for (size_t k = 0; k < parts_.size(); ++k) start_[k + 1] = k == 0 ? wall_length(parts_[0]) : start_[k] + wall_length(parts_[k]);
}

void BedPath::project(const Vec2& p, double& s, double& h) const {
    // the nearest part; each reports its own s and h (the first part reaches back and the
    // last forward without end)
    double best = std::numeric_limits<double>::infinity();
    auto consider = [&](double dist, double s_here, double h_here) {
        if (dist < best) {
            best = dist;
            s = s_here;
            h = h_here;
        }
    };
    const size_t last = parts_.size() - 1;
    for (size_t k = 0; k < parts_.size(); ++k) {
        const WallGeom& g = parts_[k];
        if (g.shape == WallShape::Segment) {
            const double lo = k == 0 ? -1e9 : 0.0;
            // (start_[0] is exactly 0, so the first part's bound is its length itself)
            const double hi = k == last ? 1e9 : start_[k + 1] - start_[k];
            const double t = std::clamp((p - g.p0).dot(g.dir), lo, hi);
            const Vec2 q = g.p0 + t * g.dir;
            consider((p - q).norm(), k == 0 ? t : start_[k] + t, (p - g.p0).dot(g.left));
        } else {
            const Vec2 d = p - g.centre;
            double off = std::fmod(std::atan2(d.y(), d.x()) - g.angle0, 2.0 * kPi);
            if (off < 0) off += 2.0 * kPi;
            if (off <= g.extent) {
                const double dist = d.norm();
                consider(std::abs(g.radius - dist), start_[k] + g.radius * off, g.radius - dist);
            }
        }
    }
}

void BedPath::at(double s, Vec2& point, Vec2& normal) const {
    size_t k = 0;
    while (k + 1 < parts_.size() && s > start_[k + 1]) ++k;
    const WallGeom& g = parts_[k];
    const double t = s - start_[k];
    if (g.shape == WallShape::Segment) {
        point = g.p0 + t * g.dir;
        normal = g.left;
    } else {
        const double a = g.angle0 + t / g.radius;
        const Vec2 u(std::cos(a), std::sin(a));
        point = g.centre + g.radius * u;
        normal = -u;
    }
}

bool BedPath::height_at(double x, double& y) const {
    bool found = false;
    auto consider = [&](double y_here) {
        if (!found || y_here > y) y = y_here;
        found = true;
    };
    // (a tolerance of a nanometre lets x at a joint or a path's end count, as rounding puts it)
    constexpr double kTol = 1e-9;
    for (const WallGeom& g : parts_) {
        if (g.shape == WallShape::Segment) {
            const double x0 = std::min(g.p0.x(), g.p1.x()), x1 = std::max(g.p0.x(), g.p1.x());
            if (x1 - x0 <= kTol || x < x0 - kTol || x > x1 + kTol) continue;
            // y along the segment, interpolated from its lower-x end
            const Vec2& a = g.p0.x() <= g.p1.x() ? g.p0 : g.p1;
            const Vec2& b = g.p0.x() <= g.p1.x() ? g.p1 : g.p0;
            const double t = std::clamp((x - a.x()) / (b.x() - a.x()), 0.0, 1.0);
            consider(a.y() + t * (b.y() - a.y()));
        } else {
            // the circle's two points at x, angles +-acos((x - cx) / R), each if on the arc
            const double c = (x - g.centre.x()) / g.radius;
            if (c < -1.0 - kTol / g.radius || c > 1.0 + kTol / g.radius) continue;
            const double a = std::acos(std::clamp(c, -1.0, 1.0));
            for (const double angle : {a, -a}) {
                double off = std::fmod(angle - g.angle0, 2.0 * kPi);
                if (off < 0) off += 2.0 * kPi;
                // an end point of the arc within the tolerance counts (off just below 2 pi is
                // just before the start)
                const double tol = kTol / g.radius;
                if (off <= g.extent + tol || off >= 2.0 * kPi - tol) consider(g.centre.y() + g.radius * std::sin(angle));
            }
        }
    }
    return found;
}

void BedPath::x_span(double& x_lo, double& x_hi) const {
    x_lo = INFINITY;
    x_hi = -INFINITY;
    for (const WallGeom& g : parts_) {
        x_lo = std::min({x_lo, g.p0.x(), g.p1.x()});
        x_hi = std::max({x_hi, g.p0.x(), g.p1.x()});
        if (g.shape == WallShape::Arc) {
            // the arc's leftmost and rightmost points, where it passes them (angles pi and 0)
            for (const double angle : {0.0, kPi}) {
                double off = std::fmod(angle - g.angle0, 2.0 * kPi);
                if (off < 0) off += 2.0 * kPi;
                if (off <= g.extent) {
                    const double xe = g.centre.x() + g.radius * std::cos(angle);
                    x_lo = std::min(x_lo, xe);
                    x_hi = std::max(x_hi, xe);
                }
            }
        }
    }
}

}  // namespace demlab
