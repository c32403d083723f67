// Discs on a triangular lattice inside a polygon (`[lattice_release]`, docs/spec/COHESION.md
// section 3): the nodes origin + i s u + j (sqrt(3)/2) s w + (j mod 2)(s/2) u, u along
// angle_deg, w = u turned +90 deg, make discs where the centre lies inside the region (within
// 1e-9 s of its boundary counts) and at least r from every wall (less 0.1 % of r, for
// coordinates rounded to 0.1 mm). Radii uniform in
// [r_min, r_max] from scenario.seed. Numbered row by row (j, then i), so discs near in space
// are near in number (the force pass' ranges); a disc's layer is its row (before settling).
#pragma once
#include <vector>

#include "scenario/scenario.h"
#include "setups/release.h"

namespace demlab {

// With lattice_release.settle, the discs then settle under gravity against the walls
// (settle_lattice). Throws RunError when they do not within release.settle_max_time.
ReleaseMass lattice_mass(const Scenario& s, const std::vector<WallDef>& walls);
void settle_lattice(const Scenario& s, const std::vector<WallDef>& walls, ReleaseMass& m);

}  // namespace demlab
