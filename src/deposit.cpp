#include "deposit.h"

#include <cmath>
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

Envelope upper_envelope(const std::vector<Vec2>& pos, const std::vector<double>& radius,
                        const std::vector<uint8_t>& use, double x_from, double x_to, double dx) {
    Envelope e;
    e.x0 = x_from;
    e.dx = dx;
    const size_t m = size_t(std::floor((x_to - x_from) / dx)) + 1;
    e.y.assign(m, NAN);
    for (size_t i = 0; i < pos.size(); ++i) {
        if (!use.empty() && !use[i]) continue;
        const double r = radius[i], xc = pos[i].x();
        const long k0 = std::max(0L, long(std::ceil((xc - r - x_from) / dx)));
        const long k1 = std::min(long(m) - 1, long(std::floor((xc + r - x_from) / dx)));
        for (long k = k0; k <= k1; ++k) {
            const double u = e.x(size_t(k)) - xc;
            const double top = pos[i].y() + std::sqrt(std::max(0.0, r * r - u * u));
            if (std::isnan(e.y[size_t(k)]) || top > e.y[size_t(k)]) e.y[size_t(k)] = top;
        }
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

SlopeAngles slope_angles(const Envelope& e, double w) {
    SlopeAngles a;
    for (int i = 1; i <= 5; ++i) {
        double slope = 0, intercept = 0;
        a.gamma[i - 1] = fit_line(e, (5 - i) * w, (6 - i) * w, slope, intercept) ? std::atan(-slope) * 180.0 / kPi : NAN;
    }
    a.toe_x = NAN;
    a.h_wall = NAN;
    for (size_t k = 0; k < e.y.size(); ++k)
        if (!std::isnan(e.y[k])) {
            if (std::isnan(a.h_wall)) a.h_wall = e.y[k];
            a.toe_x = e.x(k);
        }
    a.gamma_ges = std::isnan(a.toe_x) ? NAN : std::atan(a.h_wall / std::max(a.toe_x - e.x0, 1e-9)) * 180.0 / kPi;
    return a;
}

}  // namespace demlab
