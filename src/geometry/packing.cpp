#include "geometry/packing.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>

namespace demlab {

namespace {
double distance_to_segment(const Vec2& p, const Vec2& a, const Vec2& b) {
    const Vec2 ab = b - a;
    const double len2 = ab.squaredNorm();
    const double t = len2 > 0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
    return (p - (a + t * ab)).norm();
}
}  // namespace

PackingMeasure interior_porosity(const std::vector<Vec2>& pos, const std::vector<double>& radius,
                                 const std::vector<std::array<Vec2, 2>>& walls, const PackingDef& def) {
    PackingMeasure m;
    if (pos.empty()) return m;
    double r_min = radius[0], r_max = radius[0];
    Vec2 lo = pos[0], hi = pos[0];
    for (size_t i = 0; i < pos.size(); ++i) {
        r_min = std::min(r_min, radius[i]);
        r_max = std::max(r_max, radius[i]);
        lo = lo.cwiseMin(pos[i]);
        hi = hi.cwiseMax(pos[i]);
    }
    const double clearance = def.clearance > 0 ? def.clearance : 4.0 * r_max;
    // an irrational share of r_min: a grid commensurate with a regular packing would sample it
    // at the same few places of each cell (a square lattice at spacing 2 r read 0.25 with
    // r / 4)
    const double h = def.spacing > 0 ? def.spacing : (std::sqrt(5.0) - 2.0) * r_min;
    // the mass's vertical extent in columns 2 r_max wide: a point counts only between the
    // lowest disc bottom and the highest disc top of its column and of the columns within the
    // clearance, less the clearance (the free surface and an edge without a wall)
    const double w = 2.0 * r_max;
    const long columns = long(std::floor((hi.x() - lo.x()) / w)) + 1;
    std::vector<double> top(size_t(columns), -INFINITY), bottom(size_t(columns), INFINITY);
    for (size_t i = 0; i < pos.size(); ++i) {
        const size_t c = size_t(std::floor((pos[i].x() - lo.x()) / w));
        top[c] = std::max(top[c], pos[i].y() + radius[i]);
        bottom[c] = std::min(bottom[c], pos[i].y() - radius[i]);
    }
    const long reach = long(std::ceil(clearance / w));
    // the discs by cells of 2 r_max: a point is covered by a disc of its own or a next cell
    const double cell = 2.0 * r_max;
    auto key = [&](long cx, long cy) { return (cx << 32) ^ (cy & 0xffffffffL); };
    std::unordered_map<long, std::vector<int>> cells;
    for (size_t i = 0; i < pos.size(); ++i)
        cells[key(long(std::floor((pos[i].x() - lo.x()) / cell)), long(std::floor((pos[i].y() - lo.y()) / cell)))].push_back(int(i));
    long covered = 0;
    for (double x = lo.x() + 0.5 * h; x <= hi.x(); x += h) {
        const long c = long(std::floor((x - lo.x()) / w));
        if (c - reach < 0 || c + reach >= columns) continue;
        double y_lo = -INFINITY, y_hi = INFINITY;
        for (long k = c - reach; k <= c + reach; ++k) {
            y_lo = std::max(y_lo, bottom[size_t(k)]);
            y_hi = std::min(y_hi, top[size_t(k)]);
        }
        for (double y = y_lo + clearance; y <= y_hi - clearance; y += h) {
            const Vec2 p(x, y);
            bool near_wall = false;
            for (const auto& s : walls)
                if (distance_to_segment(p, s[0], s[1]) < clearance) near_wall = true;
            if (near_wall) continue;
            ++m.samples;
            const long cx = long(std::floor((x - lo.x()) / cell)), cy = long(std::floor((y - lo.y()) / cell));
            bool in_disc = false;
            for (long dx = -1; dx <= 1 && !in_disc; ++dx)
                for (long dy = -1; dy <= 1 && !in_disc; ++dy) {
                    const auto it = cells.find(key(cx + dx, cy + dy));
                    if (it == cells.end()) continue;
                    for (int i : it->second)
                        if ((pos[size_t(i)] - p).squaredNorm() < radius[size_t(i)] * radius[size_t(i)]) {
                            in_disc = true;
                            break;
                        }
                }
            covered += in_disc ? 1 : 0;
        }
    }
    if (m.samples > 0) m.porosity = 1.0 - double(covered) / double(m.samples);
    return m;
}

}  // namespace demlab
