#include "dem3/sphere_bonds.h"

#include <CGAL/Delaunay_triangulation_3.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_vertex_base_with_info_3.h>

namespace demlab {

namespace {
using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Vb = CGAL::Triangulation_vertex_base_with_info_3<std::size_t, K>;  // info = sphere id
using Tds = CGAL::Triangulation_data_structure_3<Vb>;
using DT = CGAL::Delaunay_triangulation_3<K, Tds>;
}  // namespace

std::vector<std::pair<int, int>> delaunay_bonds3(const std::vector<Vec3>& centres, const std::vector<double>& radius,
                                                 const BondBuildDef& def, BondBuildReport* report) {
    std::vector<std::pair<K::Point_3, std::size_t>> pts;
    pts.reserve(centres.size());
    for (size_t i = 0; i < centres.size(); ++i) pts.emplace_back(K::Point_3(centres[i].x(), centres[i].y(), centres[i].z()), i);
    DT dt;
    dt.insert(pts.begin(), pts.end());  // range insert, spatially sorted inside
    BondBuildReport rep;
    rep.dimension = dt.dimension();
    // the filters act on the triangulation's edges (as the discs' on a collinear line's): on a
    // lattice's faces a bond between two neighbours may lie only on octahedra split along their
    // long diagonal, and a tetrahedron's longest side would drop it
    std::vector<BondSimplex> simplices;
    for (auto e = dt.finite_edges_begin(); e != dt.finite_edges_end(); ++e)
        simplices.push_back(BondSimplex{{e->first->vertex(e->second)->info(), e->first->vertex(e->third)->info(), 0, 0}, 2});
    auto length = [](const void* c, size_t k, size_t l) {
        const auto& p = *static_cast<const std::vector<Vec3>*>(c);
        return (p[l] - p[k]).norm();
    };
    std::vector<std::pair<int, int>> bonds = bonds_of_simplices(simplices, radius, length, &centres, def, rep);
    if (report) *report = rep;
    return bonds;
}

}  // namespace demlab
