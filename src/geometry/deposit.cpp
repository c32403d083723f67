#include "geometry/deposit.h"

#include <cmath>
#include <fstream>
#include <sstream>

#include "core/csv.h"
#include "core/error.h"
#include "core/fileio.h"
#include <unordered_map>

namespace demlab {

std::vector<uint8_t> connected_discs(const std::vector<Vec2>& p, const std::vector<double>& radius, double gap) {
    const size_t n = p.size();
    std::vector<uint8_t> ok(n, 0);
    if (n == 0) return ok;
    double r_max = 0;
    for (double r : radius) r_max = std::max(r_max, r);
    const double cell = 2.0 * r_max + gap;
    std::unordered_map<long long, std::vector<int>> grid;
    grid.reserve(n);
    auto key = [](long long ix, long long iy) { return ix * 2000003LL + iy; };
    for (size_t i = 0; i < n; ++i)
        grid[key((long long)std::floor(p[i].x() / cell), (long long)std::floor(p[i].y() / cell))].push_back(int(i));
    for (size_t i = 0; i < n; ++i) {
        if (ok[i]) continue;
        const long long ix = (long long)std::floor(p[i].x() / cell), iy = (long long)std::floor(p[i].y() / cell);
        for (long long dx = -1; dx <= 1 && !ok[i]; ++dx)
            for (long long dy = -1; dy <= 1 && !ok[i]; ++dy) {
                auto it = grid.find(key(ix + dx, iy + dy));
                if (it == grid.end()) continue;
                for (int j : it->second) {
                    if (size_t(j) == i) continue;
                    const double reach = radius[i] + radius[size_t(j)] + gap;
                    if ((p[size_t(j)] - p[i]).squaredNorm() <= reach * reach) {
                        ok[i] = 1;
                        ok[size_t(j)] = 1;
                        break;
                    }
                }
            }
    }
    return ok;
}

namespace {
// An envelope of the grid x_from + k dx up to x_to, no sample covered yet.
Envelope empty_envelope(double x_from, double x_to, double dx) {
    Envelope e;
    e.x0 = x_from;
    e.dx = dx;
    e.y.assign(size_t(std::floor((x_to - x_from) / dx)) + 1, NAN);
    return e;
}
// Raises the samples in [a, b] to top(x) where it is higher.
template <typename Top>
void raise_over(Envelope& e, double a, double b, Top top) {
    const long k0 = std::max(0L, long(std::ceil((a - e.x0) / e.dx)));
    const long k1 = std::min(long(e.y.size()) - 1, long(std::floor((b - e.x0) / e.dx)));
    for (long k = k0; k <= k1; ++k) {
        const double t = top(e.x(size_t(k)));
        double& y = e.y[size_t(k)];
        if (std::isnan(y) || t > y) y = t;
    }
}
}  // namespace

Envelope upper_envelope(const std::vector<Vec2>& pos, const std::vector<double>& radius,
                        const std::vector<uint8_t>& use, double x_from, double x_to, double dx) {
    Envelope e = empty_envelope(x_from, x_to, dx);
    for (size_t i = 0; i < pos.size(); ++i) {
        if (!use.empty() && !use[i]) continue;
        const double r = radius[i], xc = pos[i].x(), yc = pos[i].y();
        raise_over(e, xc - r, xc + r, [&](double x) { return yc + std::sqrt(std::max(0.0, r * r - (x - xc) * (x - xc))); });
    }
    return e;
}

Envelope upper_envelope(const std::vector<Vec2>& points, double x_from, double x_to, double dx) {
    Envelope e = empty_envelope(x_from, x_to, dx);
    for (size_t k = 1; k < points.size(); ++k) {
        // the segment from its lower x (l) to its higher (r)
        const bool forward = points[k - 1].x() <= points[k].x();
        const Vec2 l = forward ? points[k - 1] : points[k], r = forward ? points[k] : points[k - 1];
        const double run = r.x() - l.x();
        raise_over(e, l.x(), r.x(), [&](double x) {
            return run > 0.0 ? l.y() + (r.y() - l.y()) * (x - l.x()) / run : std::max(l.y(), r.y());
        });
    }
    return e;
}

bool fit_line(const Envelope& e, double lo, double hi, double& slope, double& intercept) {
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    long n = 0;
    for (size_t k = 0; k < e.y.size(); ++k) {
        const double x = e.x(k);
        if (x < lo || x > hi || std::isnan(e.y[k])) continue;
        sx += x;
        sy += e.y[k];
        sxx += x * x;
        sxy += x * e.y[k];
        ++n;
    }
    const double den = double(n) * sxx - sx * sx;
    if (n < 3 || !(den > 0)) return false;
    slope = (double(n) * sxy - sx * sy) / den;
    intercept = (sy - slope * sx) / double(n);
    return true;
}

SlopeAngles slope_angles(const Envelope& e, double w, double wall_gap, double start) {
    SlopeAngles a;
    // past the toe the surface is the floor (y = 0): a section the deposit does not reach is
    // level, and one it half reaches is fitted through the floor beyond its toe, as the
    // laboratory's surface measured every 10 cm would be
    Envelope surface = e;
    size_t last = surface.y.size();
    for (size_t k = 0; k < surface.y.size(); ++k)
        if (!std::isnan(surface.y[k])) last = k;
    if (last < surface.y.size()) {
        // (an envelope read back from envelope.csv ends at its toe)
        const double reach = start + 5.0 * w;
        if (surface.dx > 0.0 && surface.x(surface.y.size() - 1) < reach)
            surface.y.resize(size_t(std::ceil((reach - surface.x0) / surface.dx)) + 1, NAN);
        for (size_t k = last + 1; k < surface.y.size(); ++k) surface.y[k] = 0.0;
    }
    for (int i = 1; i <= 5; ++i) {
        double slope = 0, intercept = 0;
        const double lo = std::max(start + (5 - i) * w, wall_gap);
        a.gamma[i - 1] = fit_line(surface, lo, start + (6 - i) * w, slope, intercept) ? std::atan(-slope) * 180.0 / kPi : NAN;
    }
    a.toe_x = NAN;
    a.h_wall = NAN;
    a.h_start = NAN;
    const double from = std::max(start, wall_gap);
    for (size_t k = 0; k < e.y.size(); ++k)
        if (!std::isnan(e.y[k])) {
            if (std::isnan(a.h_wall) && e.x(k) >= e.x0 + wall_gap) a.h_wall = e.y[k];
            if (std::isnan(a.h_start) && e.x(k) >= e.x0 + from) a.h_start = e.y[k];
            a.toe_x = e.x(k);
        }
    a.gamma_ges = std::isnan(a.toe_x) || std::isnan(a.h_start) ? NAN : std::atan(a.h_start / std::max(a.toe_x - e.x0 - from, 1e-9)) * 180.0 / kPi;
    return a;
}

Envelope read_envelope_csv(const std::string& path) {
    // read whole (a cut or malformed file: an InputError naming its line), by column name
    const CsvTable t = read_csv_table(path);
    const CsvHeader header(t.names, path);
    const size_t cx = header.column("x_m"), cy = header.column("surface_m");
    std::vector<Vec2> pts;
    for (size_t k = 0; k < t.rows.size(); ++k) {
        const double x = t.rows[k][cx], y = t.rows[k][cy];
        // the run samples a flume of metres from the back wall every 1 mm: an x beyond a
        // kilometre would ask for a grid of millions of samples
        if (!(x >= 0.0 && x <= 1000.0) || !std::isfinite(y))
            throw InputError(path + ":" + std::to_string(k + 2) + ": expected x_m in [0, 1000] and a finite surface_m");
        pts.emplace_back(x, y);
    }
    Envelope e;
    e.dx = 0.001;
    if (pts.empty()) return e;
    e.x0 = 0.0;  // the run samples from the back wall, x = 0, every 1 mm
    e.y.assign(size_t(std::lround(pts.back().x() / e.dx)) + 1, NAN);
    for (const Vec2& p : pts) {
        const long k = std::lround(p.x() / e.dx);
        if (k >= 0 && size_t(k) < e.y.size()) e.y[size_t(k)] = p.y();
    }
    return e;
}

}  // namespace demlab
