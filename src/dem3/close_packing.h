// The release as Mikhailov fills it: equal spheres "packed as densely as possible, each interior
// particle touching twelve neighbours" (DEBRIS.md sec. 1), i.e. on a face-centred cubic lattice
// of spacing 2R, in the space between the bed and the mass's top inside a box in map view.
// The lattice: a1 = (2R, 0, 0), a2 = (R, sqrt(3) R, 0), a3 = (R, R/sqrt(3), 2 sqrt(2/3) R):
// close-packed layers stacked ABC, solid fraction pi/(3 sqrt 2) = 0.7405.
#pragma once
#include <functional>
#include <vector>

#include "core/vec2.h"
#include "core/vec3.h"
#include "dem3/tin.h"

namespace demlab {

struct ClosePackedRelease {
    std::vector<Vec3> centres;  // m, in lattice order (layer, row, column): the same for the same inputs
    double bulk_volume = 0.0;   // m3, between the bed and the top inside the box
    double solid_volume = 0.0;  // m3, the spheres'
};

// Spheres of radius R on the lattice, with the lattice's origin at (lo.x, lo.y, lowest bed in
// the box), kept when inside the box, clear of the bed (no TIN contact) and with the centre at
// least R below the top (top(x, y) gives the top's elevation, false outside it).
//
// LatticeLayers::Bed tilts the lattice so that its layers lie parallel to the plane fitted to the
// bed in the box (least squares), the first layer a radius above it: a slab on a planar slope
// then rests on the bed everywhere instead of on a staircase of level layers, and is not shaken
// apart as its spheres drop onto the slope at the start.
enum class LatticeLayers { Level, Bed };

ClosePackedRelease close_packed_release(const Tin& bed, const std::function<bool(double, double, double&)>& top, const Vec2& lo,
                                        const Vec2& hi, double R, LatticeLayers layers = LatticeLayers::Level);

}  // namespace demlab
