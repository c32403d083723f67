// Which discs a cohesive slab bonds: the edges of a Delaunay triangulation of the disc centres
// (CGAL), filtered as AvaFrame does (docs/spec/COHESION.md section 4.1).
//
//   "triangular"  keep a face whose longest side Lf <= max_edge_factor * min over faces of Lf
//                 (AvaFrame: maxRadius = 1.1 * the shortest longest side; a lattice's hull
//                 triangles are longer and dropped)
//   "length"      keep a face with Lf <= max_bond_length
//   "gap"         keep a face whose every side has L - r_k - r_l <= max_gap (disordered packings)
//   "none"        keep every face
// Bonds are the sides of the kept faces, (min id, max id), sorted and unique. Collinear centres
// (a 1-D triangulation) give the edges between neighbours, each with the same test on the
// edge itself; a single point gives none. Exact predicates make the triangulation independent
// of rounding; for cocircular points CGAL's choice depends on the input order only, so the
// same scenario gives the same bonds.
#pragma once
#include <array>
#include <cstddef>
#include <utility>
#include <vector>

#include "core/vec2.h"

namespace demlab {

enum class BondFilter { Triangular, Length, Gap, None };

struct BondBuildDef {
    BondFilter filter = BondFilter::Triangular;
    double max_edge_factor = 1.1;   // -, "triangular", in [1, 3]
    double max_bond_length = 0.0;   // m, "length" (> 0 needed there)
    double max_gap = 0.0;           // m, "gap"; the caller resolves 0 to 0.25 r_min
};

// "gap" with max_gap = 0 means a quarter of the smallest radius (COHESION.md section 3)
inline BondBuildDef with_default_gap(BondBuildDef d, double r_min) {
    if (d.max_gap == 0.0) d.max_gap = 0.25 * r_min;
    return d;
}

struct BondBuildReport {
    int dimension = 0;              // of the triangulation: 3 (spheres), 2, 1 (collinear), 0 or -1
    size_t faces = 0, faces_kept = 0, bonds = 0;  // faces: the simplices (triangles, tetrahedra)
    double mean_rest_length = 0.0;  // m
};

// A simplex of a Delaunay triangulation: 2 (an edge), 3 (a triangle) or 4 (a tetrahedron) ids.
struct BondSimplex {
    std::array<size_t, 4> v{};
    int n = 0;
};

// The filter on the simplices, then their sides as bonds (min id, max id), sorted and unique;
// `length(k, l)` is the distance between two centres. The discs' and the spheres' builders share it.
std::vector<std::pair<int, int>> bonds_of_simplices(const std::vector<BondSimplex>& simplices, const std::vector<double>& radius,
                                                    double (*length)(const void*, size_t, size_t), const void* centres,
                                                    const BondBuildDef& def, BondBuildReport& report);

std::vector<std::pair<int, int>> delaunay_bonds(const std::vector<Vec2>& pos, const std::vector<double>& radius,
                                                const BondBuildDef& def, BondBuildReport* report = nullptr);

}  // namespace demlab
