#include "dem3/tin.h"

#include <CGAL/Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <sstream>
#include <utility>

#include "core/csv.h"
#include "core/error.h"
#include "core/fileio.h"

namespace demlab {

namespace {

// Where on a triangle its closest point to p lies: inside the face, on edge k (joining corners
// k and k + 1), or at corner k. Ericson, Real-Time Collision Detection (2005), 5.1.5: the
// Voronoi regions of the corners, then of the edges, else the face.
struct TrianglePoint {
    Vec3 point;
    enum Where { Face, Edge, Corner } where;
    int k;
};

TrianglePoint closest_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
    const Vec3 ab = b - a, ac = c - a, ap = p - a;
    const double d1 = ab.dot(ap), d2 = ac.dot(ap);
    if (d1 <= 0.0 && d2 <= 0.0) return {a, TrianglePoint::Corner, 0};
    const Vec3 bp = p - b;
    const double d3 = ab.dot(bp), d4 = ac.dot(bp);
    if (d3 >= 0.0 && d4 <= d3) return {b, TrianglePoint::Corner, 1};
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return {a + (d1 / (d1 - d3)) * ab, TrianglePoint::Edge, 0};
    const Vec3 cp = p - c;
    const double d5 = ab.dot(cp), d6 = ac.dot(cp);
    if (d6 >= 0.0 && d5 <= d6) return {c, TrianglePoint::Corner, 2};
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return {a + (d2 / (d2 - d6)) * ac, TrianglePoint::Edge, 2};
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0)
        return {b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b), TrianglePoint::Edge, 1};
    const double denom = 1.0 / (va + vb + vc);
    return {a + ab * (vb * denom) + ac * (vc * denom), TrianglePoint::Face, 0};
}

}  // namespace

Tin Tin::from_grid(const EsriGrid& g, const std::string& path) {
    Tin t;
    std::vector<std::int64_t> vertex_of(size_t(g.ncols) * size_t(g.nrows), -1);
    auto node = [&](int c, int r) -> std::int64_t {
        const size_t k = size_t(r) * size_t(g.ncols) + size_t(c);
        const double z = g.z[k];
        if ((g.has_nodata && z == g.nodata) || !std::isfinite(z)) return -1;
        if (vertex_of[k] < 0) {
            vertex_of[k] = std::int64_t(t.vertices_.size());
            t.vertices_.emplace_back(g.x0 + c * g.cellsize, g.y0 + r * g.cellsize, z);
        }
        return vertex_of[k];
    };
    for (int r = 0; r + 1 < g.nrows; ++r)
        for (int c = 0; c + 1 < g.ncols; ++c) {
            const std::int64_t v00 = node(c, r), v10 = node(c + 1, r), v01 = node(c, r + 1), v11 = node(c + 1, r + 1);
            if (v00 < 0 || v10 < 0 || v01 < 0 || v11 < 0) continue;
            const auto P = [&](std::int64_t v) { return t.vertices_[size_t(v)]; };
            // the shorter diagonal in 3-D (ties: the south-west to north-east one), so a ridge or
            // a valley across the cell is kept as the grid draws it
            const bool sw_ne = (P(v11) - P(v00)).squaredNorm() <= (P(v01) - P(v10)).squaredNorm();
            auto U = [](std::int64_t v) { return std::uint32_t(v); };
            if (sw_ne) {
                t.triangles_.push_back({U(v00), U(v10), U(v11)});
                t.triangles_.push_back({U(v00), U(v11), U(v01)});
            } else {
                t.triangles_.push_back({U(v00), U(v10), U(v01)});
                t.triangles_.push_back({U(v10), U(v11), U(v01)});
            }
        }
    if (t.triangles_.empty())
        throw InputError(path + ": the grid has no cell whose four corners hold elevations, so no terrain to triangulate");
    t.build(path);
    return t;
}

Tin Tin::from_points(const std::vector<Vec3>& points, const std::string& path) {
    using K = CGAL::Exact_predicates_inexact_constructions_kernel;
    using Vb = CGAL::Triangulation_vertex_base_with_info_2<std::uint32_t, K>;
    using Tds = CGAL::Triangulation_data_structure_2<Vb>;
    using DT = CGAL::Delaunay_triangulation_2<K, Tds>;
    if (points.size() < 3) throw InputError(path + ": " + std::to_string(points.size()) + " points; a terrain needs at least 3");
    std::vector<std::pair<K::Point_2, std::uint32_t>> in;
    in.reserve(points.size());
    for (size_t i = 0; i < points.size(); ++i) in.emplace_back(K::Point_2(points[i].x(), points[i].y()), std::uint32_t(i));
    DT dt(in.begin(), in.end());
    if (dt.number_of_vertices() != points.size()) {
        std::map<std::pair<double, double>, size_t> seen;
        for (size_t i = 0; i < points.size(); ++i) {
            auto [it, fresh] = seen.emplace(std::make_pair(points[i].x(), points[i].y()), i);
            if (!fresh)
                throw InputError(path + ": points " + std::to_string(it->second + 1) + " and " + std::to_string(i + 1) +
                                 " have the same x and y: a terrain has one elevation a place");
        }
    }
    if (dt.dimension() < 2) throw InputError(path + ": all points lie on one line in map view: no terrain to triangulate");
    Tin t;
    t.vertices_ = points;
    for (auto f = dt.finite_faces_begin(); f != dt.finite_faces_end(); ++f)
        t.triangles_.push_back({f->vertex(0)->info(), f->vertex(1)->info(), f->vertex(2)->info()});  // CGAL: counter-clockwise
    // the same TIN whatever order CGAL visits its faces in
    for (auto& tri : t.triangles_) std::rotate(tri.begin(), std::min_element(tri.begin(), tri.end()), tri.end());
    std::sort(t.triangles_.begin(), t.triangles_.end());
    t.build(path);
    return t;
}

void Tin::build(const std::string& path) {
    lower_ = Vec3::Constant(INFINITY);
    upper_ = Vec3::Constant(-INFINITY);
    for (const Vec3& v : vertices_) {
        lower_ = lower_.cwiseMin(v);
        upper_ = upper_.cwiseMax(v);
    }
    // edges: each unordered corner pair once, numbered in the order the faces meet them
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> edge_of;
    triangle_edges_.assign(triangles_.size(), {0, 0, 0});
    edge_faces_.clear();
    std::vector<double> edge_length;                                 // m, in map view
    std::vector<double> nearest(vertices_.size(), INFINITY);         // m, each vertex's shortest edge
    for (std::uint32_t f = 0; f < triangles_.size(); ++f)
        for (int k = 0; k < 3; ++k) {
            const std::uint32_t a = triangles_[f][size_t(k)], b = triangles_[f][size_t((k + 1) % 3)];
            const auto key = std::minmax(a, b);
            auto [it, fresh] = edge_of.emplace(std::make_pair(key.first, key.second), std::uint32_t(edge_faces_.size()));
            if (fresh) {
                edge_faces_.push_back({f, f});
                const double length = (vertices_[a] - vertices_[b]).head<2>().norm();
                edge_length.push_back(length);
                nearest[a] = std::min(nearest[a], length);
                nearest[b] = std::min(nearest[b], length);
            } else {
                edge_faces_[it->second][1] = f;
            }
            triangle_edges_[f][size_t(k)] = it->second;
        }
    // the faces around each vertex
    vertex_face_start_.assign(vertices_.size() + 1, 0);
    for (const auto& tri : triangles_)
        for (std::uint32_t v : tri) ++vertex_face_start_[v + 1];
    for (size_t v = 0; v < vertices_.size(); ++v) vertex_face_start_[v + 1] += vertex_face_start_[v];
    vertex_faces_.assign(vertex_face_start_.back(), 0);
    std::vector<std::uint32_t> fill(vertex_face_start_.begin(), vertex_face_start_.end() - 1);
    for (std::uint32_t f = 0; f < triangles_.size(); ++f)
        for (std::uint32_t v : triangles_[f]) vertex_faces_[fill[v]++] = f;
    // Buckets about two median edges wide: a few triangles each. (The median, not the mean: a
    // stray point far from the rest adds a fan of edges as long as its distance, and the mean
    // grew with them: one point 100 km off a 150 m slope of 1 m cells made the mean edge 115 m,
    // every triangle one bucket's, and the run 83 times slower.) At most four buckets a
    // triangle, or 2^21 (a mixed grid of 25 m and 0.25 m cells would want 10^8 of 12 bytes),
    // and at most 16 entries a triangle plus 2^26 (256 MB: a fan of long triangles to a far
    // point, or the long ones filling a concave outline, are listed wherever their boxes
    // reach): a terrain that would need more takes wider buckets, widened until it fits (one
    // bucket always does). Its search is slower then, and says so once the buckets are more
    // than four times as wide as its spacing wants.
    std::nth_element(edge_length.begin(), edge_length.begin() + std::ptrdiff_t(edge_length.size() / 2), edge_length.end());
    const double median_edge = edge_length.empty() ? 1.0 : edge_length[edge_length.size() / 2];
    const double wanted_bucket = std::max(2.0 * median_edge, 1e-9);
    bucket_ = wanted_bucket;
    const double sx = upper_.x() - lower_.x(), sy = upper_.y() - lower_.y();
    const double max_buckets = std::max(4.0 * double(triangles_.size()), 2097152.0);  // 12 bytes each
    const double wanted = (sx / bucket_ + 1.0) * (sy / bucket_ + 1.0);
    if (wanted > max_buckets) bucket_ *= std::sqrt(wanted / max_buckets) * (1.0 + 1e-9);
    const double max_entries = std::min(16.0 * double(triangles_.size()) + 67108864.0, 2147483648.0);
    // a triangle's box in buckets
    auto span = [&](std::uint32_t f, int& i0, int& i1, int& j0, int& j1) {
        double x0 = INFINITY, y0 = INFINITY, x1 = -INFINITY, y1 = -INFINITY;
        for (std::uint32_t v : triangles_[f]) {
            x0 = std::min(x0, vertices_[v].x());
            x1 = std::max(x1, vertices_[v].x());
            y0 = std::min(y0, vertices_[v].y());
            y1 = std::max(y1, vertices_[v].y());
        }
        i0 = std::clamp(int((x0 - lower_.x()) / bucket_), 0, buckets_x_ - 1), i1 = std::clamp(int((x1 - lower_.x()) / bucket_), 0, buckets_x_ - 1);
        j0 = std::clamp(int((y0 - lower_.y()) / bucket_), 0, buckets_y_ - 1), j1 = std::clamp(int((y1 - lower_.y()) / bucket_), 0, buckets_y_ - 1);
    };
    while (true) {
        buckets_x_ = int(sx / bucket_) + 1;
        buckets_y_ = int(sy / bucket_) + 1;
        bucket_ = std::max({bucket_, sx / buckets_x_, sy / buckets_y_});
        double entries = 0.0;
        for (std::uint32_t f = 0; f < triangles_.size() && entries <= max_entries; ++f) {
            int i0, i1, j0, j1;
            span(f, i0, i1, j0, j1);
            entries += double(i1 - i0 + 1) * double(j1 - j0 + 1);
        }
        if (entries <= max_entries || (buckets_x_ == 1 && buckets_y_ == 1)) break;
        bucket_ *= 1.25;  // (a quarter at a time: the narrowest that fits, within a quarter)
    }
    const double widened = bucket_ / wanted_bucket;
    if (widened > 4.0) {
        auto g = [](double v) {
            char text[32];
            std::snprintf(text, sizeof text, "%.6g", v);
            return std::string(text);
        };
        const size_t far = size_t(std::max_element(nearest.begin(), nearest.end()) - nearest.begin());
        const std::string cause =
            nearest[far] > 100.0 * median_edge
                ? "point " + std::to_string(far + 1) + " at (" + g(vertices_[far].x()) + ", " + g(vertices_[far].y()) + ") is " +
                      g(nearest[far]) + " m from its nearest neighbour: a stray point (a row of zeros, a NODATA value, "
                      "another coordinate system) is the usual cause; remove it"
                : "its spacings spread widely (mixed resolutions, or an outline far from convex, whose hull the "
                  "triangulation fills with long triangles); crop it, or resample it to one spacing";
        std::fprintf(stderr,
                     "demlab: warning: %s: half the terrain's triangle edges are shorter than %s m, but it spans %s by %s m: "
                     "its contact search runs with buckets %s times as wide as that spacing wants, and so slower; %s\n",
                     path.c_str(), g(median_edge).c_str(), g(sx).c_str(), g(sy).c_str(), g(widened).c_str(), cause.c_str());
    }
    // the lists in one array (CSR), each in ascending triangle order: counted, then filled
    const size_t n_buckets = size_t(buckets_x_) * size_t(buckets_y_);
    bucket_start_.assign(n_buckets + 1, 0);
    for (std::uint32_t f = 0; f < triangles_.size(); ++f) {
        int i0, i1, j0, j1;
        span(f, i0, i1, j0, j1);
        for (int j = j0; j <= j1; ++j)
            for (int i = i0; i <= i1; ++i) ++bucket_start_[size_t(j) * size_t(buckets_x_) + size_t(i) + 1];
    }
    for (size_t b = 0; b < n_buckets; ++b) bucket_start_[b + 1] += bucket_start_[b];
    bucket_items_.assign(bucket_start_.back(), 0);
    {
        std::vector<std::uint32_t> next(bucket_start_.begin(), bucket_start_.end() - 1);
        for (std::uint32_t f = 0; f < triangles_.size(); ++f) {
            int i0, i1, j0, j1;
            span(f, i0, i1, j0, j1);
            for (int j = j0; j <= j1; ++j)
                for (int i = i0; i <= i1; ++i) bucket_items_[next[size_t(j) * size_t(buckets_x_) + size_t(i)]++] = f;
        }
    }
    plane_normal_.resize(triangles_.size());
    plane_offset_.resize(triangles_.size());
    for (size_t f = 0; f < triangles_.size(); ++f) {
        const Vec3 &a = vertices_[triangles_[f][0]], &b = vertices_[triangles_[f][1]], &c = vertices_[triangles_[f][2]];
        const Vec3 n = (b - a).cross(c - a);
        const double len = n.norm();
        plane_normal_[f] = len > 0.0 ? Vec3(n / len) : Vec3::Zero();
        plane_offset_[f] = plane_normal_[f].dot(a);
    }
    bucket_top_.assign(n_buckets, -INFINITY);
    for (size_t b = 0; b < n_buckets; ++b)
        for (std::uint32_t k = bucket_start_[b]; k < bucket_start_[b + 1]; ++k)
            for (std::uint32_t v : triangles_[bucket_items_[k]]) bucket_top_[b] = std::max(bucket_top_[b], vertices_[v].z());
}

void Tin::triangles_near(double x0, double y0, double x1, double y1, std::vector<std::uint32_t>& out) const {
    out.clear();
    if (x1 < lower_.x() || y1 < lower_.y() || x0 > upper_.x() || y0 > upper_.y()) return;
    const int i0 = std::clamp(int((x0 - lower_.x()) / bucket_), 0, buckets_x_ - 1), i1 = std::clamp(int((x1 - lower_.x()) / bucket_), 0, buckets_x_ - 1);
    const int j0 = std::clamp(int((y0 - lower_.y()) / bucket_), 0, buckets_y_ - 1), j1 = std::clamp(int((y1 - lower_.y()) / bucket_), 0, buckets_y_ - 1);
    for (int j = j0; j <= j1; ++j)
        for (int i = i0; i <= i1; ++i) {
            const size_t b = size_t(j) * size_t(buckets_x_) + size_t(i);
            out.insert(out.end(), bucket_items_.begin() + bucket_start_[b], bucket_items_.begin() + bucket_start_[b + 1]);
        }
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
}

double Tin::top_near(double x0, double y0, double x1, double y1) const {
    if (x1 < lower_.x() || y1 < lower_.y() || x0 > upper_.x() || y0 > upper_.y()) return -INFINITY;
    const int i0 = std::clamp(int((x0 - lower_.x()) / bucket_), 0, buckets_x_ - 1), i1 = std::clamp(int((x1 - lower_.x()) / bucket_), 0, buckets_x_ - 1);
    const int j0 = std::clamp(int((y0 - lower_.y()) / bucket_), 0, buckets_y_ - 1), j1 = std::clamp(int((y1 - lower_.y()) / bucket_), 0, buckets_y_ - 1);
    double top = -INFINITY;
    for (int j = j0; j <= j1; ++j)
        for (int i = i0; i <= i1; ++i) top = std::max(top, bucket_top_[size_t(j) * size_t(buckets_x_) + size_t(i)]);
    return top;
}

void Tin::sphere_contacts(const Vec3& centre, double radius, std::vector<TinContact>& out) const {
    // a sphere whose lowest point is above every corner of the triangles below it touches none
    // of them (most of a thick mass): no search (the same contacts, found sooner)
    if (centre.z() - radius > top_near(centre.x() - radius, centre.y() - radius, centre.x() + radius, centre.y() + radius)) return;
    // Each face near the sphere gives its closest point and the feature it lies on. A feature is
    // the sphere's contact only when every face it bounds finds its closest point on it (the
    // centre is in the feature's Voronoi region): a face's interior always; an edge when both
    // its faces end on it; a vertex when all its faces do. So a sphere above a face's inside has
    // no second contact on that face's edge or corner or on a farther edge of a flat fan; over a
    // convex edge one, its normal turning smoothly from one face's to the other's; in a
    // concave fold one on each face it touches. The globally closest point always qualifies.
    thread_local std::vector<std::uint32_t> near;
    struct Found {
        std::uint32_t feature, face;
        Vec3 point;
        double distance;
    };
    thread_local std::vector<Found> found;
    found.clear();
    triangles_near(centre.x() - radius, centre.y() - radius, centre.x() + radius, centre.y() + radius, near);
    const std::uint32_t F = std::uint32_t(triangles_.size()), E = std::uint32_t(edge_faces_.size());
    for (std::uint32_t f : near) {
        // a face whose plane is a radius away or more is as far from all its points: it and the
        // features on it cannot be a contact, and a feature within the radius lies only on
        // faces nearer than that, so leaving it out changes no contact
        if (std::abs(plane_normal_[f].dot(centre) - plane_offset_[f]) > radius * (1.0 + 1e-9)) continue;  // (a hair of margin for rounding)
        const auto& t = triangles_[f];
        const TrianglePoint q = closest_on_triangle(centre, vertices_[t[0]], vertices_[t[1]], vertices_[t[2]]);
        const double d = (centre - q.point).norm();
        std::uint32_t feature = f;
        if (q.where == TrianglePoint::Edge) feature = F + triangle_edges_[f][size_t(q.k)];
        if (q.where == TrianglePoint::Corner) feature = F + E + t[size_t(q.k)];
        found.push_back({feature, f, q.point, d});
    }
    // which faces found which feature: a feature qualifies when all its faces found it
    auto face_found = [&](std::uint32_t face, std::uint32_t feature) {
        for (const Found& x : found)
            if (x.face == face) return x.feature == feature;
        return false;  // (a face too far to be searched did not find it)
    };
    auto qualifies = [&](const Found& x) {
        if (x.feature < F) return true;
        if (x.feature < F + E) {
            const auto& ef = edge_faces_[x.feature - F];
            return face_found(ef[0], x.feature) && face_found(ef[1], x.feature);
        }
        const std::uint32_t v = x.feature - F - E;
        for (std::uint32_t k = vertex_face_start_[v]; k < vertex_face_start_[v + 1]; ++k)
            if (!face_found(vertex_faces_[k], x.feature)) return false;
        return true;
    };
    const size_t first = out.size();
    double closest = INFINITY;
    const Found* best = nullptr;
    for (const Found& x : found) {
        if (!(x.distance < radius)) continue;
        if (x.distance < closest) {
            closest = x.distance;
            best = &x;
        }
        if (!qualifies(x)) continue;
        // the same feature from two faces, or two features at one point (a centre exactly
        // above an edge or a corner, where rounding puts the point inside a face for one face
        // and on its border for the next): one contact
        bool seen = false;
        for (size_t k = first; k < out.size() && !seen; ++k)
            seen = out[k].feature == x.feature || (out[k].point - x.point).norm() <= 1e-9 * radius;
        if (seen) continue;
        TinContact c;
        c.feature = x.feature;
        c.point = x.point;
        c.distance = x.distance;
        out.push_back(c);
    }
    // a tie at a region's border (the closest point rounded onto an edge by one face and onto
    // its corner by another) may leave no feature qualified: the closest point is the contact
    if (out.size() == first && best) {
        TinContact c;
        c.feature = best->feature;
        c.point = best->point;
        c.distance = best->distance;
        out.push_back(c);
    }
    for (size_t k = first; k < out.size(); ++k) {
        TinContact& c = out[k];
        if (c.distance > 0.0) {
            c.normal = (centre - c.point) / c.distance;
        } else {
            // the centre on the surface: the normal of a face that holds the point, upwards
            std::uint32_t face = c.feature < F ? c.feature : 0;
            for (const Found& x : found)
                if (x.feature == c.feature) face = x.face;
            const auto& t = triangles_[face];
            c.normal = (vertices_[t[1]] - vertices_[t[0]]).cross(vertices_[t[2]] - vertices_[t[0]]).normalized();
        }
    }
    std::sort(out.begin() + std::ptrdiff_t(first), out.end(), [](const TinContact& a, const TinContact& b) { return a.feature < b.feature; });
}

bool Tin::height_at(double x, double y, double& z) const {
    thread_local std::vector<std::uint32_t> near;
    triangles_near(x, y, x, y, near);
    for (std::uint32_t f : near) {
        const Vec3 &a = vertices_[triangles_[f][0]], &b = vertices_[triangles_[f][1]], &c = vertices_[triangles_[f][2]];
        // barycentric coordinates in map view
        const double det = (b.x() - a.x()) * (c.y() - a.y()) - (c.x() - a.x()) * (b.y() - a.y());
        if (det == 0.0) continue;
        const double l1 = ((x - a.x()) * (c.y() - a.y()) - (c.x() - a.x()) * (y - a.y())) / det;
        const double l2 = ((b.x() - a.x()) * (y - a.y()) - (x - a.x()) * (b.y() - a.y())) / det;
        const double l0 = 1.0 - l1 - l2, eps = -1e-12;
        if (l0 >= eps && l1 >= eps && l2 >= eps) {
            z = l0 * a.z() + l1 * b.z() + l2 * c.z();
            return true;
        }
    }
    return false;
}

}  // namespace demlab

namespace demlab {

std::vector<Vec3> read_xyz_points(const std::string& path, const std::string& what) {
    std::istringstream in(read_input_file(path, kMaxTableBytes, what));
    std::vector<Vec3> points;
    std::string line;
    int no = 0;
    while (std::getline(in, line)) {
        ++no;
        if (!line.empty() && line.back() == '\r') line.pop_back();
        const size_t hash = line.find('#');
        if (hash != std::string::npos) line.resize(hash);
        std::istringstream row(line);
        std::vector<std::string> cells;
        std::string cell;
        while (row >> cell) cells.push_back(cell);
        if (cells.empty()) continue;
        if (cells.size() != 3)
            throw InputError(path + ":" + std::to_string(no) + ": " + std::to_string(cells.size()) +
                             " values; each row is 'x y z' (m)");
        double v[3];
        for (int k = 0; k < 3; ++k) {
            // beyond these is no terrain (and the triangles' areas would overflow): x and y map
            // coordinates within 1e9 m, z an elevation within 10,000 km
            const double bound = k < 2 ? 1e9 : 1e7;
            if (!parse_number(cells[size_t(k)], v[k]) || !(std::abs(v[k]) <= bound))
                throw InputError(path + ":" + std::to_string(no) + ": '" + cells[size_t(k)] + "' is not a finite number in [" +
                                 (k < 2 ? "-1e9, 1e9" : "-1e7, 1e7") + "] (" + std::string(k == 0 ? "x" : k == 1 ? "y" : "z") + ", m)");
        }
        points.emplace_back(v[0], v[1], v[2]);
    }
    return points;
}

}  // namespace demlab
