// The settling loops before t = 0 (generate_release, settle_lattice) run in chunks of steps,
// checking the unbalanced force, progress and signals between chunks.
#pragma once
#include <algorithm>
#include <cmath>

#include "dem/world.h"

namespace demlab {

// Steps of the next chunk: at most `chunk`, and no more than reach t_end at the current step.
// Soft contacts give a large step (kn = 1e5 N/m, discs of 0.07 m: 5.7e-3 s), and 200 such
// steps ran a release settling for 1.1 s where release.settle_max_time asked 0.0075 s, long
// enough for a mass under an open top to pour out of its polygon.
inline long settle_chunk(const World& w, double t_end, long chunk = 200) {
    const double left = (t_end - w.time()) / w.dt();
    if (!(left < double(chunk))) return chunk;
    return std::max(1L, long(std::ceil(left)));
}

}  // namespace demlab
