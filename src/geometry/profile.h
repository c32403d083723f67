// A ground profile as a polyline, read from a CSV file (terrain.profile).
#pragma once
#include <string>
#include <vector>

#include "core/vec2.h"

namespace demlab {

// A terrain profile's points from a CSV file: "x,y" rows in m, x increasing; a header line
// and lines starting with '#' are skipped. InputError with the file and line otherwise; `what`
// names the file's role in the messages.
std::vector<Vec2> read_profile_csv(const std::string& path, const std::string& what = "terrain profile (terrain.profile)");

}  // namespace demlab
