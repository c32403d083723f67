// The path of the continuum model (docs/spec/DAN.md section 2): a chain of segments and
// counter-clockwise arcs (a BedPath: the flume's W1, arc and W3 as the world joined them, or
// any chain for tests), with its inclination alpha (+ descending in +s), its curvature kappa
// (= -d alpha / ds: +1/R on a concave arc) and its point at every s, straight on past both
// ends. x(s) is the horizontal coordinate of the vertical columns.
#pragma once
#include "geometry/bed_path.h"

namespace demlab {

struct DanPathPoint {
    Vec2 p;              // m, the bed's point
    double alpha = 0.0;  // rad, + descending
    double kappa = 0.0;  // 1/m
    Vec2 tangent() const;  // (cos alpha, -sin alpha)
    Vec2 normal() const;   // into the flow, (sin alpha, cos alpha)
};

class DanPath {
public:
    // curvature_window > 0: kappa is its running mean over that length (exact, kappa being
    // piecewise constant)
    DanPath(BedPath path, double curvature_window = 0.0);
    DanPathPoint at(double s) const;
    // s where x(s) = x (x(s) must increase: checked by x_increasing)
    double s_of_x(double x, double s_lo, double s_hi) const;
    // cos alpha >= min_cos everywhere on [s_lo, s_hi] (the vertical columns need x(s) increasing)
    bool x_increasing(double s_lo, double s_hi, double min_cos) const;
    double length() const { return path_.length(); }
    size_t parts() const { return path_.parts(); }
    double part_start(size_t k) const { return path_.part_start(k); }
    const BedPath& bed() const { return path_; }

private:
    double curvature_over(double s0, double s1) const;  // the integral of kappa over [s0, s1]
    BedPath path_;
    double window_;
};

}  // namespace demlab
