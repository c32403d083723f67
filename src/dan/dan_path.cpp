#include "dan/dan_path.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"

namespace demlab {

Vec2 DanPathPoint::tangent() const { return {std::cos(alpha), -std::sin(alpha)}; }
Vec2 DanPathPoint::normal() const { return {std::sin(alpha), std::cos(alpha)}; }

DanPath::DanPath(BedPath path, double curvature_window) : path_(std::move(path)), window_(curvature_window) {}

namespace {
// a segment's or a counter-clockwise arc's point, inclination and curvature at t along it
DanPathPoint on_part(const WallGeom& g, double t) {
    DanPathPoint q;
    if (g.shape == WallShape::Segment) {
        q.p = g.p0 + t * g.dir;
        q.alpha = std::atan2(-g.dir.y(), g.dir.x());
        q.kappa = 0.0;
    } else {
        const double theta = g.angle0 + t / g.radius;
        q.p = g.centre + g.radius * Vec2(std::cos(theta), std::sin(theta));
        // the tangent of a counter-clockwise arc, (-sin theta, cos theta) = (cos alpha, -sin alpha)
        q.alpha = std::atan2(-std::cos(theta), -std::sin(theta));
        q.kappa = 1.0 / g.radius;
    }
    return q;
}
}  // namespace

double DanPath::curvature_over(double s0, double s1) const {
    double sum = 0.0;
    for (size_t k = 0; k < path_.parts(); ++k) {
        const WallGeom& g = path_.part(k);
        if (g.shape != WallShape::Arc) continue;
        const double a = std::max(s0, path_.part_start(k)), b = std::min(s1, path_.part_start(k + 1));
        if (b > a) sum += (b - a) / g.radius;
    }
    return sum;
}

DanPathPoint DanPath::at(double s) const {
    const double L = path_.length();
    DanPathPoint q;
    if (s < 0.0) {
        q = on_part(path_.part(0), 0.0);
        q.p += s * q.tangent();
        q.kappa = 0.0;
    } else if (s > L) {
        const size_t last = path_.parts() - 1;
        q = on_part(path_.part(last), L - path_.part_start(last));
        q.p += (s - L) * q.tangent();
        q.kappa = 0.0;
    } else {
        size_t k = 0;
        while (k + 1 < path_.parts() && s > path_.part_start(k + 1)) ++k;
        q = on_part(path_.part(k), s - path_.part_start(k));
    }
    if (window_ > 0.0) q.kappa = curvature_over(s - 0.5 * window_, s + 0.5 * window_) / window_;
    return q;
}

double DanPath::s_of_x(double x, double s_lo, double s_hi) const {
    double lo = s_lo, hi = s_hi;
    if (!(at(lo).p.x() <= x && x <= at(hi).p.x()))
        throw InputError("dan: x = " + std::to_string(x) + " m lies outside the path's stretch [" +
                         std::to_string(at(lo).p.x()) + ", " + std::to_string(at(hi).p.x()) + "] m");
    for (int it = 0; it < 200 && hi - lo > 1e-15 * std::max(1.0, std::abs(hi)); ++it) {
        const double mid = 0.5 * (lo + hi);
        (at(mid).p.x() < x ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
}

bool DanPath::x_increasing(double s_lo, double s_hi, double min_cos) const {
    // alpha is monotone on each part: its ends and, on an arc, its steepest point decide
    for (size_t k = 0; k < path_.parts(); ++k) {
        const double a = std::max(s_lo, path_.part_start(k)), b = std::min(s_hi, path_.part_start(k + 1));
        if (b < a) continue;
        for (const double s : {a, b, 0.5 * (a + b)})
            if (std::cos(at(s).alpha) < min_cos) return false;
    }
    return std::cos(at(s_lo).alpha) >= min_cos && std::cos(at(s_hi).alpha) >= min_cos;
}

}  // namespace demlab
