#include "core/validate.h"

#include <charconv>
#include <cmath>

#include "core/error.h"

namespace demlab {

std::string format_number(double value) {
    char buf[64];
    auto res = std::to_chars(buf, buf + sizeof buf, value);
    return std::string(buf, res.ptr);
}

static std::string with_unit(const char* unit) {
    return (unit && *unit) ? std::string(" ") + unit : std::string();
}

void require_finite(const std::string& name, double value, const char* unit) {
    if (!std::isfinite(value))
        throw InputError(name + " = " + format_number(value) + ": must be a finite number" + with_unit(unit));
}

void require_positive(const std::string& name, double value, const char* unit) {
    require_finite(name, value, unit);
    if (!(value > 0.0))
        throw InputError(name + " = " + format_number(value) + with_unit(unit) + ": must be > 0");
}

void require_non_negative(const std::string& name, double value, const char* unit) {
    require_finite(name, value, unit);
    if (!(value >= 0.0))
        throw InputError(name + " = " + format_number(value) + with_unit(unit) + ": must be >= 0");
}

void require_range(const std::string& name, double value, double lo, double hi, bool hi_open, const char* unit) {
    require_finite(name, value, unit);
    bool ok = value >= lo && (hi_open ? value < hi : value <= hi);
    if (!ok)
        throw InputError(name + " = " + format_number(value) + with_unit(unit) + ": must be in [" + format_number(lo) +
                         ", " + format_number(hi) + (hi_open ? ")" : "]"));
}

void require_finite(const std::string& name, const Vec2& value, const char* unit) {
    if (!std::isfinite(value.x()) || !std::isfinite(value.y()))
        throw InputError(name + " = (" + format_number(value.x()) + ", " + format_number(value.y()) +
                         "): must be finite" + with_unit(unit));
}

}  // namespace demlab
