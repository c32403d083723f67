// A bed path: a chain of walls (segments and arcs, as the world joined them) along which a
// flow is measured. The path coordinate s runs along the chain from the start of its first
// part; h is the height above the bed on the flow side (the segments' left, the inside of an
// arc whose solid is outside), negative below it. The first part extends backwards and the
// last forwards without end, so every point projects. The flume (slope, arc, barrier), a
// terrain profile and the continuum solver's path are bed paths.
#pragma once
#include <vector>

#include "geometry/wall.h"

namespace demlab {

class BedPath {
public:
    BedPath() = default;
    explicit BedPath(std::vector<WallGeom> parts);
    // Projects a point onto the nearest part of the path: s along it (m) and h (m).
    void project(const Vec2& p, double& s, double& h) const;
    // The point of the bed at s and the unit normal into the flow there.
    void at(double s, Vec2& point, Vec2& normal) const;
    // The bed's height at x: the highest point at x of the parts that span x with a horizontal
    // extent (a vertical segment spans none; a path that overhangs gives its upper part);
    // false where no part spans x. The flume's W1, arc and W3, a dam break's floor and a
    // terrain profile are single-valued in x, so the bed under the deposit.
    bool height_at(double x, double& y) const;
    // The x range the parts span, lowest to highest.
    void x_span(double& x_lo, double& x_hi) const;
    size_t parts() const { return parts_.size(); }
    const WallGeom& part(size_t k) const { return parts_[k]; }
    double part_start(size_t k) const { return start_[k]; }  // m, s where part k starts (k = parts(): the end)
    double length() const { return start_.back(); }

private:
    std::vector<WallGeom> parts_;
    std::vector<double> start_;  // parts() + 1 entries
};

}  // namespace demlab
