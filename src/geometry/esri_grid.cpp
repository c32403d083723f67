#include "geometry/esri_grid.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <sstream>

#include "core/csv.h"
#include "core/error.h"
#include "core/fileio.h"
#include "core/validate.h"

namespace demlab {

namespace {
std::string lower(std::string s) {
    for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
    return s;
}

}  // namespace

bool EsriGrid::sample(const Vec2& p, double& out) const {
    const double u = (p.x() - x0) / cellsize, v = (p.y() - y0) / cellsize;
    // within the centres' box, with a rounding's tolerance at its edges
    const double eps = 1e-9;
    if (!(u >= -eps && v >= -eps && u <= ncols - 1 + eps && v <= nrows - 1 + eps)) return false;
    const int c = std::clamp(int(std::floor(u)), 0, std::max(ncols - 2, 0));
    const int r = std::clamp(int(std::floor(v)), 0, std::max(nrows - 2, 0));
    const int c1 = std::min(c + 1, ncols - 1), r1 = std::min(r + 1, nrows - 1);
    const double fu = std::clamp(u - c, 0.0, 1.0), fv = std::clamp(v - r, 0.0, 1.0);
    const double z00 = z[size_t(r) * size_t(ncols) + size_t(c)], z10 = z[size_t(r) * size_t(ncols) + size_t(c1)];
    const double z01 = z[size_t(r1) * size_t(ncols) + size_t(c)], z11 = z[size_t(r1) * size_t(ncols) + size_t(c1)];
    if (has_nodata)
        for (double q : {z00, z10, z01, z11})
            if (q == nodata) return false;
    out = (1 - fv) * ((1 - fu) * z00 + fu * z10) + fv * ((1 - fu) * z01 + fu * z11);
    return true;
}

EsriGrid read_esri_grid(const std::string& path, const std::string& what) {
    const std::string text = read_input_file(path, kMaxTableBytes, what);
    std::istringstream in(text);
    EsriGrid g;
    std::string line;
    int no = 0;
    // the header: keyword value lines until the first line that starts with a number
    bool corner_x = true, corner_y = true, have[5] = {false, false, false, false, false};
    const char* names[5] = {"ncols", "nrows", "xllcorner or xllcenter", "yllcorner or yllcenter", "cellsize"};
    int line_of[6] = {0, 0, 0, 0, 0, 0};  // where each of names[] (and NODATA_value) was given
    std::string first_data;
    while (std::getline(in, line)) {
        ++no;
        if (!line.empty() && line.back() == '\r') line.pop_back();
        std::istringstream row(line);
        std::string key, value, rest;
        if (!(row >> key)) continue;
        double probe = 0.0;
        if (parse_finite(key, probe)) {
            first_data = line;
            break;
        }
        const std::string where = path + ":" + std::to_string(no);
        if (!(row >> value) || (row >> rest))
            throw InputError(where + ": expected a header line 'keyword value', found '" + line + "'");
        double v = 0.0;
        if (!parse_finite(value, v)) throw InputError(where + ": " + key + " = '" + value + "' is not a number");
        const std::string k = lower(key);
        // a keyword given twice (xllcorner and xllcenter count as one): which one holds cannot be told
        const int slot = k == "ncols" ? 0 : k == "nrows" ? 1 : (k == "xllcorner" || k == "xllcenter") ? 2
                         : (k == "yllcorner" || k == "yllcenter") ? 3 : k == "cellsize" ? 4 : k == "nodata_value" ? 5 : -1;
        if (slot >= 0 && line_of[slot] > 0)
            throw InputError(where + ": " + key + " given again (line " + std::to_string(line_of[slot]) + " gave " +
                             (slot < 5 ? names[slot] : "NODATA_value") + ")");
        if (slot >= 0) line_of[slot] = no;
        // a corner beyond 1e9 m is no map coordinate (UTM with a zone prefix reaches 6.1e7);
        // NODATA_value is any number (GIS tools write -3.4028234663852886e+38)
        if ((slot == 2 || slot == 3) && !(std::abs(v) <= 1e9))
            throw InputError(where + ": " + key + " = " + value + " m must be within [-1e9, 1e9]");
        if (k == "ncols" || k == "nrows") {
            if (v != std::floor(v) || v < 2 || v > 1e6)
                throw InputError(where + ": " + k + " = " + value + " must be a whole number in [2, 1000000]");
            (k == "ncols" ? g.ncols : g.nrows) = int(v);
            have[k == "ncols" ? 0 : 1] = true;
        } else if (k == "xllcorner" || k == "xllcenter") {
            g.x0 = v;
            corner_x = k == "xllcorner";
            have[2] = true;
        } else if (k == "yllcorner" || k == "yllcenter") {
            g.y0 = v;
            corner_y = k == "yllcorner";
            have[3] = true;
        } else if (k == "cellsize") {
            if (!(v > 0.0 && v <= 1e5)) throw InputError(where + ": cellsize = " + value + " m must be in (0, 1e5]");
            g.cellsize = v;
            have[4] = true;
        } else if (k == "nodata_value") {
            g.has_nodata = true;
            g.nodata = v;
        } else {
            throw InputError(where + ": unknown header keyword '" + key +
                             "' (an ESRI ASCII grid has ncols, nrows, xllcorner/xllcenter, yllcorner/yllcenter, cellsize, NODATA_value)");
        }
    }
    for (int k = 0; k < 5; ++k)
        if (!have[k]) throw InputError(path + ": the header lacks " + std::string(names[k]));
    if (double(g.ncols) * double(g.nrows) > 5e7)
        throw InputError(path + ": " + std::to_string(g.ncols) + " x " + std::to_string(g.nrows) + " cells: more than 50 million");
    // each elevation takes two bytes at least (a digit and a separator): a header asking for more
    // than the file holds is refused before the grid is allocated
    if (2.0 * double(g.ncols) * double(g.nrows) > double(text.size()))
        throw InputError(path + ": " + std::to_string(g.ncols) + " x " + std::to_string(g.nrows) + " cells need " +
                         format_number(2.0 * double(g.ncols) * double(g.nrows)) + " bytes at least; the file has " +
                         std::to_string(text.size()) + ": ncols or nrows is wrong, or the file is cut short");
    if (corner_x) g.x0 += 0.5 * g.cellsize;
    if (corner_y) g.y0 += 0.5 * g.cellsize;
    // the rows, northernmost first; stored from the south
    g.z.assign(size_t(g.ncols) * size_t(g.nrows), 0.0);
    int row = 0;
    bool pending = !first_data.empty();
    while (pending || std::getline(in, line)) {
        if (pending) {
            line = first_data;
            pending = false;
        } else {
            ++no;
            if (!line.empty() && line.back() == '\r') line.pop_back();
        }
        std::istringstream cells(line);
        std::string cell;
        std::vector<double> values;
        while (cells >> cell) {
            double v = 0.0;
            if (!parse_finite(cell, v)) throw InputError(path + ":" + std::to_string(no) + ": '" + cell + "' is not a number");
            // an elevation beyond 10,000 km is no terrain (the nodata value aside)
            if (!(std::abs(v) <= 1e7) && !(g.has_nodata && v == g.nodata))
                throw InputError(path + ":" + std::to_string(no) + ": elevation " + cell + " must be within [-1e7, 1e7] m");
            values.push_back(v);
        }
        if (values.empty()) continue;
        if (row >= g.nrows) throw InputError(path + ":" + std::to_string(no) + ": more rows than nrows = " + std::to_string(g.nrows));
        if (int(values.size()) != g.ncols)
            throw InputError(path + ":" + std::to_string(no) + ": " + std::to_string(values.size()) + " values, ncols = " +
                             std::to_string(g.ncols));
        const size_t r = size_t(g.nrows - 1 - row);
        std::copy(values.begin(), values.end(), g.z.begin() + ptrdiff_t(r * size_t(g.ncols)));
        ++row;
    }
    if (row != g.nrows) throw InputError(path + ": " + std::to_string(row) + " rows of elevations, nrows = " + std::to_string(g.nrows));
    return g;
}

std::vector<Vec2> sample_section(const EsriGrid& g, const std::string& path, const Vec2& a, const Vec2& b, double spacing) {
    const double length = (b - a).norm();
    if (!(length > 0.0)) throw InputError(path + ": terrain.section: its two points coincide");
    if (!(spacing > 0.0)) throw InputError(path + ": terrain.spacing = " + format_number(spacing) + " m must be > 0");
    // counted in double first: a section far longer than the grid would overflow the integer
    const double samples = std::ceil(length / spacing - 1e-9);
    if (!(samples <= 1000000.0))
        throw InputError(path + ": terrain.section: " + format_number(samples) + " samples (more than 1,000,000): a larger spacing");
    const long n = long(samples);
    std::vector<Vec2> out;
    for (long k = 0; k <= n; ++k) {
        const double s = std::min(double(k) * spacing, length);
        const Vec2 p = a + (b - a) * (s / length);
        double z = 0.0;
        if (!g.sample(p, z))
            throw InputError(path + ": terrain.section: the point (" + format_number(p.x()) + ", " + format_number(p.y()) +
                             ") at " + format_number(s) + " m along the section is " +
                             (g.has_nodata && (p.x() - g.x0) / g.cellsize >= 0 && (p.y() - g.y0) / g.cellsize >= 0 &&
                                      (p.x() - g.x0) / g.cellsize <= g.ncols - 1 && (p.y() - g.y0) / g.cellsize <= g.nrows - 1
                                  ? "on NODATA cells"
                                  : "outside the grid's cell centres"));
        out.emplace_back(s, z);
    }
    return out;
}

}  // namespace demlab
