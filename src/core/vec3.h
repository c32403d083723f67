// Small 3-D vector math on Eigen, for the 3-D solver (src/dem3/) and its terrain.
#pragma once
#include <Eigen/Core>
#include <Eigen/Geometry>  // cross products

namespace demlab {

using Vec3 = Eigen::Vector3d;

}  // namespace demlab
