// Terrain from an elevation model: an ESRI ASCII grid (".asc") sampled along a section line
// into a profile polyline (distance along the section as x, elevation as y), the form every
// GIS exports. Header (keywords in any case, in this order as written by ArcGIS and GDAL):
//   ncols N, nrows M, xllcorner|xllcenter X, yllcorner|yllcenter Y, cellsize C[, NODATA_value V]
// then M rows of N elevations, the northernmost row first. A value is taken at its cell's
// centre (xllcorner + (col + 1/2) C, ...) and sampled bilinearly between the four centres around
// a point; a sample needs all four (no extrapolation past the outer centres).
#pragma once
#include <string>
#include <vector>

#include "core/vec2.h"

namespace demlab {

struct EsriGrid {
    int ncols = 0, nrows = 0;
    double x0 = 0.0, y0 = 0.0;  // m, the centre of the south-west cell
    double cellsize = 0.0;      // m
    bool has_nodata = false;
    double nodata = -9999.0;
    std::vector<double> z;      // m, row-major from the south: z[row * ncols + col], row 0 the southernmost

    // the elevation at p (bilinear); false when p is outside the cell centres' box or a
    // corner is NODATA
    bool sample(const Vec2& p, double& out) const;
};

// Reads an .asc file (bounded like every input file); InputError (exit 2) with the file,
// line and what is wrong for a malformed header, a short or long row, a non-number.
EsriGrid read_esri_grid(const std::string& path, const std::string& what = "elevation grid (terrain.grid)");

// The section from a to b sampled every `spacing` m (and at b): points (distance from a,
// elevation). InputError naming the point for a sample outside the grid or on NODATA.
std::vector<Vec2> sample_section(const EsriGrid& g, const std::string& path, const Vec2& a, const Vec2& b, double spacing);

}  // namespace demlab
