// The colour scale of speeds and result fields: viridis (perceptually uniform, readable in grey
// and by colour-blind readers), five stops, linear between them.
#pragma once
#include <algorithm>

namespace demlab {

struct Rgb {
    double r, g, b;  // 0..1
};

inline Rgb viridis(double v, double vmax) {
    static const Rgb stops[5] = {{0.267, 0.005, 0.329}, {0.231, 0.322, 0.545}, {0.129, 0.569, 0.549},
                                 {0.369, 0.788, 0.384}, {0.993, 0.906, 0.144}};
    double t = std::clamp(v / vmax, 0.0, 1.0) * 4.0;
    const int k = std::min(3, int(t));
    t -= k;
    return {stops[k].r + t * (stops[k + 1].r - stops[k].r), stops[k].g + t * (stops[k + 1].g - stops[k].g),
            stops[k].b + t * (stops[k + 1].b - stops[k].b)};
}

}  // namespace demlab
