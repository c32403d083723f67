// A triangulated terrain (TIN), the bed of the 3-D solver: DEBRIS' relief ("the bed is a
// triangulated terrain", ../docs/spec/DEBRIS.md sec. 1) and AvaFrame's terrain. Built from an
// ESRI ASCII grid (each cell between four centres two triangles) or from x y z points
// triangulated in map view by CGAL's 2-D Delaunay triangulation. A sphere touches it on a
// face's interior, an edge or a vertex; each feature is reported once however many triangles
// share it, and a feature inside another's region is not reported beside it, so a sphere
// rolling or sliding across an edge or a vertex of a flat or gently folded TIN feels one
// continuous force (no double counting, no bump).
#pragma once
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/vec3.h"
#include "geometry/esri_grid.h"

namespace demlab {

// One touch of a sphere on the terrain: the closest point of one feature.
struct TinContact {
    Vec3 normal = Vec3::UnitZ();  // unit, from the closest point towards the sphere's centre
    double distance = 0.0;   // m, centre to the closest point (DEBRIS' d_i); < the radius
    Vec3 point = Vec3::Zero();    // m, the closest point on the terrain
    std::uint32_t feature = 0;  // the feature's id: faces [0, F), edges [F, F + E), vertices after; stable for a TIN
};

class Tin {
public:
    Tin() = default;
    // Each cell between four grid centres: two triangles, split along the diagonal that is the
    // shorter in 3-D (a fixed rule, so the same grid gives the same TIN). NODATA corners drop
    // the cell's triangles. InputError (exit 2) naming the file when no triangle is left.
    static Tin from_grid(const EsriGrid& g, const std::string& path);
    // x y z points triangulated in map view (CGAL 2-D Delaunay on x, y; z carried).
    // InputError naming the file for fewer than 3 points, repeated x y or all collinear.
    static Tin from_points(const std::vector<Vec3>& points, const std::string& path);

    // Appends to out every feature closer than `radius` to `centre` (see the header comment);
    // sorted by feature id so the order never depends on the search.
    void sphere_contacts(const Vec3& centre, double radius, std::vector<TinContact>& out) const;

    // The terrain's elevation below (x, y) in map view; false outside the TIN.
    bool height_at(double x, double y, double& z) const;

    const std::vector<Vec3>& vertices() const { return vertices_; }
    const std::vector<std::array<std::uint32_t, 3>>& triangles() const { return triangles_; }
    Vec3 lower_corner() const { return lower_; }  // m, the bounding box
    double search_bucket() const { return bucket_; }  // m, the side of the map-view search's buckets
    Vec3 upper_corner() const { return upper_; }

private:
    // edges, adjacency and the map-view search; after vertices_ and triangles_ are set. A
    // warning naming the file (path), and the point most likely stray, when the search's buckets
    // had to be made much wider than the terrain's spacing wants.
    void build(const std::string& path);
    // the triangles whose map-view boxes meet [x0, x1] x [y0, y1], ascending (out is cleared)
    void triangles_near(double x0, double y0, double x1, double y1, std::vector<std::uint32_t>& out) const;

    std::vector<Vec3> vertices_;
    std::vector<std::array<std::uint32_t, 3>> triangles_;  // counter-clockwise seen from above
    std::vector<std::array<std::uint32_t, 3>> triangle_edges_;  // edge k joins corners k and k + 1
    std::vector<std::array<std::uint32_t, 2>> edge_faces_;     // the one or two faces of an edge (a lone face: twice)
    std::vector<std::uint32_t> vertex_face_start_, vertex_faces_;  // the faces around each vertex (CSR)
    // map-view buckets of side bucket_ over the box, each listing the triangles meeting it (CSR)
    double bucket_ = 1.0;
    int buckets_x_ = 1, buckets_y_ = 1;
    std::vector<std::uint32_t> bucket_start_, bucket_items_;
    std::vector<Vec3> plane_normal_;   // unit normal of each triangle's plane
    std::vector<double> plane_offset_; // its offset: n . x = offset on the plane
    std::vector<double> bucket_top_;  // m, the highest corner of the triangles each bucket lists (-inf: none)
    // the highest corner of the triangles listed over a box in map view (-inf outside the TIN)
    double top_near(double x0, double y0, double x1, double y1) const;
    Vec3 lower_ = Vec3::Zero(), upper_ = Vec3::Zero();
};

// An "x y z" point file (DEBRIS' input: the bed and the level surface), one point a row,
// '#' comments and blank rows skipped; bounded like every input file. InputError (exit 2) with
// the file, the line and what is wrong.
std::vector<Vec3> read_xyz_points(const std::string& path, const std::string& what = "x y z point file");

}  // namespace demlab
