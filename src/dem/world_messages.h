// Where a fault happened, as the world's error messages say it.
#pragma once
#include <sstream>
#include <string>

#include "core/vec2.h"

namespace demlab {

inline std::string where_disc(long step, double t, int i, const Vec2& p) {
    std::ostringstream s;
    s << "step " << step << ", t = " << t << " s, disc " << i << " at (" << p.x() << ", " << p.y() << ")";
    return s.str();
}

}  // namespace demlab
