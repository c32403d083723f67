// The deposit's upper surface and its slope angles (dam-break calibration, thesis section
// 4.3.3, Table 7; sections as in data/dam_break_geometry.md).
//
// Envelope: the exact upper envelope of the disc outlines, sampled every dx:
//     y(x) = max over discs with |x - x_c| <= r of  y_c + sqrt(r^2 - (x - x_c)^2).
// This is what an alpha shape of the outlines gives on the upper side when alpha exceeds the
// largest gap between neighbouring surface discs, without its parameter; lone discs that left
// the mass are excluded (connected_discs).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "core/vec2.h"

namespace demlab {

// Discs with another disc within r_i + r_j + gap: the mass (lone bouncing discs excluded).
std::vector<uint8_t> connected_discs(const std::vector<Vec2>& pos, const std::vector<double>& radius, double gap);

struct Envelope {
    double x0 = 0, dx = 0;
    std::vector<double> y;  // NaN where no disc covers x
    double at(size_t k) const { return y[k]; }
    double x(size_t k) const { return x0 + dx * double(k); }
};

Envelope upper_envelope(const std::vector<Vec2>& pos, const std::vector<double>& radius,
                        const std::vector<uint8_t>& use, double x_from, double x_to, double dx);
// The same grid's upper envelope of a polyline through `points` (a continuum's free surface,
// which may fold back over x): at each x the highest of the segments over it.
Envelope upper_envelope(const std::vector<Vec2>& points, double x_from, double x_to, double dx);

// Slope angles of the surface, degrees (positive: falling towards +x).
struct SlopeAngles {
    double gamma[5];   // gamma[i - 1]: section i spans x in [start + (5 - i) w, start + (6 - i) w] from the back wall
    double gamma_ges;  // the line from the surface at the sections' start to the toe
    double toe_x;      // m, the last x the envelope covers
    double h_wall;     // m, surface height at the back wall
    double h_start;    // m, surface height where the sections start (gamma_ges' top; h_wall unless moved)
};

// Least-squares line y = intercept + slope x through the envelope points in [lo, hi];
// false when fewer than 3 points.
bool fit_line(const Envelope& e, double lo, double hi, double& slope, double& intercept);

// Least-squares line through the envelope points of each section (NaN if the section is empty).
// start (m from the back wall): section 5 spans [start, start + w], section 1
// [start + 4 w, start + 5 w], and gamma_ges runs from the surface at start to the toe.
// wall_gap (m): nothing is measured closer than this to the back wall, leaving out discs that
// cling to the wall above the deposit (0: the thesis' sections).
SlopeAngles slope_angles(const Envelope& e, double section_width = 0.1, double wall_gap = 0.0, double start = 0.0);

// An envelope written as "x_m,surface_m" rows (envelope.csv of a dam-break run), on its 1 mm grid.
Envelope read_envelope_csv(const std::string& path);

}  // namespace demlab
