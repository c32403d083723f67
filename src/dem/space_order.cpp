// Space order (space_order.h) and the world's renumbering into it during a run.
//
// A flowing mass loses the order it was numbered in: at the real sand size (geometry A at
// scale 1, 145,615 discs), half of the touching pairs at t = 1.5 s join discs more than 540
// numbers apart (2 at the release), and the force pass fetches a contact's second disc from a
// line that the pairs before it have not brought in. Renumbering every world.space_order_steps
// steps brings the neighbours back together. It changes the order of every sum, so the bits
// (never the physics: the same law on the same contacts); it is deterministic (a step count
// decides when, positions decide the order), so the run still gives the same bits on any
// thread count and resumes from a checkpoint to the same bytes.
#include "dem/space_order.h"

#include <algorithm>
#include <cmath>

#include "dem/world.h"

namespace demlab {

std::vector<size_t> space_order(const std::vector<Vec2>& pos, double strip) {
    const size_t n = pos.size();
    if (n == 0 || !(strip > 0.0)) return {};
    double x_min = INFINITY;
    for (const Vec2& p : pos) x_min = std::min(x_min, p.x());
    std::vector<size_t> order(n);
    std::vector<long> column(n);
    for (size_t i = 0; i < n; ++i) {
        order[i] = i;
        column[i] = long(std::floor((pos[i].x() - x_min) / strip));
    }
    std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
        if (column[a] != column[b]) return column[a] < column[b];
        return pos[a].y() < pos[b].y();
    });
    return order;
}

bool World::space_order_due() const {
    return space_order_every_ > 0 && steps_ > 0 && steps_ % space_order_every_ == 0;
}

void World::order_discs_in_space() {
    // strips two of the largest diameters wide, as the release's (setups/release.cpp)
    const double r_max = radius_.empty() ? 0.0 : *std::max_element(radius_.begin(), radius_.end());
    const std::vector<size_t> order = space_order(pos_, 4.0 * r_max);
    if (order.empty()) return;
    std::vector<int32_t> from(order.size());
    for (size_t k = 0; k < order.size(); ++k) from[k] = int32_t(order[k]);
    remap_discs(from);
    ++space_orderings_;
}

}  // namespace demlab
