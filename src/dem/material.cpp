#include "dem/material.h"

#include "core/validate.h"

namespace demlab {

void validate(const MaterialDef& m, const std::string& where) {
    require_positive(where + ".density", m.density, "kg/m3");
    require_positive(where + ".kn", m.kn, "N/m");
    require_positive(where + ".ks", m.ks, "N/m");
    require_non_negative(where + ".friction", m.friction, "(coefficient)");
}

}  // namespace demlab
