// Which spheres a cohesive slab bonds (the 3-D solver): the edges of CGAL's 3-D Delaunay
// triangulation of the sphere centres, filtered as the discs' (dem/bonds/bond_builder.h) with
// tetrahedra for triangles. On a close-packed lattice of spacing L the triangulation is made of
// regular tetrahedra (sides L) and octahedra split along a diagonal of sqrt(2) L: "triangular"
// with max_edge_factor < sqrt(2) keeps the tetrahedra, i.e. each inner sphere's twelve
// neighbours. Coplanar or collinear centres fall back to triangles or edges; exact predicates
// and CGAL's symbolic perturbation of cospherical points make the bonds the same for the same
// centres in the same order.
#pragma once
#include <utility>
#include <vector>

#include "core/vec3.h"
#include "dem/bonds/bond_builder.h"

namespace demlab {

std::vector<std::pair<int, int>> delaunay_bonds3(const std::vector<Vec3>& centres, const std::vector<double>& radius,
                                                 const BondBuildDef& def, BondBuildReport* report = nullptr);

}  // namespace demlab
