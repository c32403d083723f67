// Parameter checks done where parameters are read (MercuryDPM style): each throws
// InputError with the parameter's name, its value, its unit and the accepted range.
#pragma once
#include <string>

#include "core/vec2.h"

namespace demlab {

void require_finite(const std::string& name, double value, const char* unit);
void require_positive(const std::string& name, double value, const char* unit);      // (0, inf)
void require_non_negative(const std::string& name, double value, const char* unit);  // [0, inf)
// [lo, hi) when hi_open, else [lo, hi]
void require_range(const std::string& name, double value, double lo, double hi, bool hi_open, const char* unit);
void require_finite(const std::string& name, const Vec2& value, const char* unit);

// Formats a double the way messages print it: shortest round-trip form.
std::string format_number(double value);

}  // namespace demlab
