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

std::vector<std::pair<int, int>> delaunay_bonds(const std::vector<Vec2>& pos, const std::vector<double>& radius,
                                                const BondBuildDef& def, BondBuildReport* report) {
    std::vector<std::pair<K::Point_2, std::size_t>> pts;
    pts.reserve(pos.size());
    for (size_t i = 0; i < pos.size(); ++i) pts.emplace_back(K::Point_2(pos[i].x(), pos[i].y()), i);
    DT dt;
    dt.insert(pts.begin(), pts.end());  // range insert, spatially sorted inside
    BondBuildReport rep;
    rep.dimension = dt.dimension();
    auto length = [&](size_t k, size_t l) { return (pos[l] - pos[k]).norm(); };
    auto gap_ok = [&](size_t k, size_t l) { return length(k, l) - radius[k] - radius[l] <= def.max_gap; };
    std::vector<std::pair<int, int>> bonds;
    auto add = [&](size_t a, size_t b) { bonds.emplace_back(int(std::min(a, b)), int(std::max(a, b))); };
    if (dt.dimension() == 2) {
        struct Face {
            size_t v[3];
            double longest;
        };
        std::vector<Face> faces;
        for (auto f = dt.finite_faces_begin(); f != dt.finite_faces_end(); ++f) {
            Face face{{f->vertex(0)->info(), f->vertex(1)->info(), f->vertex(2)->info()}, 0.0};
            face.longest = std::max({length(face.v[0], face.v[1]), length(face.v[1], face.v[2]), length(face.v[2], face.v[0])});
            faces.push_back(face);
        }
        rep.faces = faces.size();
        double shortest_longest = INFINITY;
        for (const Face& f : faces) shortest_longest = std::min(shortest_longest, f.longest);
        const double limit = def.max_edge_factor * shortest_longest;
        for (const Face& f : faces) {
            bool keep = true;
            switch (def.filter) {
                case BondFilter::Triangular: keep = f.longest <= limit; break;
                case BondFilter::Length: keep = f.longest <= def.max_bond_length; break;
                case BondFilter::Gap:
                    keep = gap_ok(f.v[0], f.v[1]) && gap_ok(f.v[1], f.v[2]) && gap_ok(f.v[2], f.v[0]);
                    break;
                case BondFilter::None: break;
            }
            if (!keep) continue;
            ++rep.faces_kept;
            add(f.v[0], f.v[1]);
            add(f.v[1], f.v[2]);
            add(f.v[2], f.v[0]);
        }
    } else if (dt.dimension() == 1) {
        // collinear centres: each finite edge joins neighbours along the line
        std::vector<std::pair<size_t, size_t>> edges;
        double shortest = INFINITY;
        for (auto e = dt.finite_edges_begin(); e != dt.finite_edges_end(); ++e) {
            const size_t a = e->first->vertex(DT::cw(e->second))->info();
            const size_t b = e->first->vertex(DT::ccw(e->second))->info();
            edges.emplace_back(a, b);
            shortest = std::min(shortest, length(a, b));
        }
        for (const auto& [a, b] : edges) {
            bool keep = true;
            switch (def.filter) {
                case BondFilter::Triangular: keep = length(a, b) <= def.max_edge_factor * shortest; break;
                case BondFilter::Length: keep = length(a, b) <= def.max_bond_length; break;
                case BondFilter::Gap: keep = gap_ok(a, b); break;
                case BondFilter::None: break;
            }
            if (keep) add(a, b);
        }
    }
    std::sort(bonds.begin(), bonds.end());
    bonds.erase(std::unique(bonds.begin(), bonds.end()), bonds.end());
    rep.bonds = bonds.size();
    double sum = 0.0;
    for (const auto& [k, l] : bonds) sum += length(size_t(k), size_t(l));
    rep.mean_rest_length = bonds.empty() ? 0.0 : sum / double(bonds.size());
    if (report) *report = rep;
    return bonds;
}

}  // namespace demlab
