// The porosity inside a packed mass, away from its walls and its free surface, as PFC's
// measurement circles give it: the share of sample points, on a square grid, that no disc
// covers. The mass's own porosity, where the release box's figure (the discs' area over the
// whole box) also counts the looser layers against the walls and under the lid.
#pragma once
#include <array>
#include <vector>

#include "core/vec2.h"

namespace demlab {

struct PackingDef {
    double clearance = 0.0;   // m, a sample point at least this far from every wall and from the mass's edges; 0 = 4 r_max
    double spacing = 0.0;     // m, between sample points; 0 = (sqrt 5 - 2) r_min, about r_min / 4
};

struct PackingMeasure {
    double porosity = -1.0;   // -, -1 when no sample point qualifies (a mass thinner than twice the clearance)
    long samples = 0;         // sample points inside the measured region
};

// discs (centres, radii) and the walls they lie against (segments).
PackingMeasure interior_porosity(const std::vector<Vec2>& pos, const std::vector<double>& radius,
                                 const std::vector<std::array<Vec2, 2>>& walls, const PackingDef& def = {});

}  // namespace demlab
