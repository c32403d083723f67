#include "dem/bonds/bond_builder.h"

#include <CGAL/Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>

#include <algorithm>
#include <cmath>

namespace demlab {

namespace {
using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Vb = CGAL::Triangulation_vertex_base_with_info_2<std::size_t, K>;  // info = disc id
using Tds = CGAL::Triangulation_data_structure_2<Vb>;
using DT = CGAL::Delaunay_triangulation_2<K, Tds>;
}  // namespace

std::vector<std::pair<int, int>> bonds_of_simplices(const std::vector<BondSimplex>& simplices, const std::vector<double>& radius,
                                                    double (*length)(const void*, size_t, size_t), const void* centres,
                                                    const BondBuildDef& def, BondBuildReport& rep) {
    auto side = [&](size_t k, size_t l) { return length(centres, k, l); };
    std::vector<double> longest(simplices.size(), 0.0);
    double shortest_longest = INFINITY;
    for (size_t s = 0; s < simplices.size(); ++s) {
        const BondSimplex& x = simplices[s];
        for (int a = 0; a < x.n; ++a)
            for (int b = a + 1; b < x.n; ++b) longest[s] = std::max(longest[s], side(x.v[a], x.v[b]));
        shortest_longest = std::min(shortest_longest, longest[s]);
    }
    rep.faces = simplices.size();
    const double limit = def.max_edge_factor * shortest_longest;
    std::vector<std::pair<int, int>> bonds;
    for (size_t s = 0; s < simplices.size(); ++s) {
        const BondSimplex& x = simplices[s];
        bool keep = true;
        switch (def.filter) {
            case BondFilter::Triangular: keep = longest[s] <= limit; break;
            case BondFilter::Length: keep = longest[s] <= def.max_bond_length; break;
            case BondFilter::Gap:
                for (int a = 0; a < x.n; ++a)
                    for (int b = a + 1; b < x.n; ++b)
                        keep = keep && side(x.v[a], x.v[b]) - radius[x.v[a]] - radius[x.v[b]] <= def.max_gap;
                break;
            case BondFilter::None: break;
        }
        if (!keep) continue;
        ++rep.faces_kept;
        for (int a = 0; a < x.n; ++a)
            for (int b = a + 1; b < x.n; ++b)
                bonds.emplace_back(int(std::min(x.v[a], x.v[b])), int(std::max(x.v[a], x.v[b])));
    }
    std::sort(bonds.begin(), bonds.end());
    bonds.erase(std::unique(bonds.begin(), bonds.end()), bonds.end());
    rep.bonds = bonds.size();
    double sum = 0.0;
    for (const auto& [k, l] : bonds) sum += side(size_t(k), size_t(l));
    rep.mean_rest_length = bonds.empty() ? 0.0 : sum / double(bonds.size());
    return bonds;
}

std::vector<std::pair<int, int>> delaunay_bonds(const std::vector<Vec2>& pos, const std::vector<double>& radius,
                                                const BondBuildDef& def, BondBuildReport* report) {
    std::vector<std::pair<K::Point_2, std::size_t>> pts;
    pts.reserve(pos.size());
    for (size_t i = 0; i < pos.size(); ++i) pts.emplace_back(K::Point_2(pos[i].x(), pos[i].y()), i);
    DT dt;
    dt.insert(pts.begin(), pts.end());  // range insert, spatially sorted inside
    BondBuildReport rep;
    rep.dimension = dt.dimension();
    // the triangles, or for collinear centres the edges between neighbours along the line (the
    // "triangular" rule then keeps edges up to max_edge_factor times the shortest)
    std::vector<BondSimplex> simplices;
    if (dt.dimension() == 2) {
        for (auto f = dt.finite_faces_begin(); f != dt.finite_faces_end(); ++f)
            simplices.push_back(BondSimplex{{f->vertex(0)->info(), f->vertex(1)->info(), f->vertex(2)->info(), 0}, 3});
    } else if (dt.dimension() == 1) {
        for (auto e = dt.finite_edges_begin(); e != dt.finite_edges_end(); ++e)
            simplices.push_back(
                BondSimplex{{e->first->vertex(DT::cw(e->second))->info(), e->first->vertex(DT::ccw(e->second))->info(), 0, 0}, 2});
    }
    auto length = [](const void* c, size_t k, size_t l) {
        const auto& p = *static_cast<const std::vector<Vec2>*>(c);
        return (p[l] - p[k]).norm();
    };
    std::vector<std::pair<int, int>> bonds = bonds_of_simplices(simplices, radius, length, &pos, def, rep);
    if (report) *report = rep;
    return bonds;
}

}  // namespace demlab
