// Small 2D vector math on Eigen. In 2D the angular velocity and torque are scalars
// (the z component); these helpers give the planar cross products.
#pragma once
#include <Eigen/Core>

namespace demlab {

using Vec2 = Eigen::Vector2d;

// z component of a x b
inline double cross(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }
// omega_z x r = omega * (-r_y, r_x)
inline Vec2 cross(double omega, const Vec2& r) { return Vec2(-omega * r.y(), omega * r.x()); }
// the unit tangent of a contact: the normal turned 90 degrees counter-clockwise
inline Vec2 perp(const Vec2& n) { return Vec2(-n.y(), n.x()); }

constexpr double kPi = 3.14159265358979323846;
inline double deg_to_rad(double deg) { return deg * kPi / 180.0; }

}  // namespace demlab
