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

}  // namespace demlab
