// Discs numbered in space order: strips across x, `strip` metres wide, from left to right, and
// up each strip. The engine gives each thread a range of disc numbers and works through its
// contacts in number order, so numbers that follow space keep a thread's discs together (few
// pairs cross between threads) and a contact's two discs near in memory (docs/performance.md).
// A release mass is numbered so before it settles (release.space_order); a large world is
// renumbered so as it flows (World::order_discs_in_space, world.space_order).
#pragma once
#include <cstddef>
#include <vector>

#include "core/vec2.h"

namespace demlab {

// The order: entry k is the index of the disc that becomes number k. Deterministic: ties keep
// the old order. Empty when there is nothing to order (no discs, or a strip that is not > 0).
std::vector<size_t> space_order(const std::vector<Vec2>& pos, double strip);

}  // namespace demlab
