// The discs' space order: strips of width `strip` across x, left to right, and in each strip
// the discs from the bottom up. Neighbours in space are then neighbours in memory (a disc's
// contacts lie in its own strip or the next ones), and the force pass' index ranges are
// slabs of the mass with few contacts between them (force_pass_ranges.cpp). The release mass
// is put in this order (order_in_space) and a large world is renumbered in it during the run
// (World::reorder_discs).
#pragma once
#include <cstddef>
#include <vector>

#include "core/vec2.h"

namespace demlab {

// order[k] = the index of the disc that comes k-th; ties keep the present order
std::vector<size_t> space_order(const std::vector<Vec2>& pos, double strip);

}  // namespace demlab
