#include "dem/rotation.h"

#include <cmath>

#include "core/error.h"
#include "core/validate.h"

namespace demlab {

void validate(const RotationDef& d, double r_min, const std::string& where) {
    if (d.model < 1 || d.model > 3)
        throw InputError(where + ".model = " + std::to_string(d.model) +
                         ": must be 1 (rotation locked), 2 (rolling resistance) or 3 (2 + rotational damping)");
    if (d.model >= 2) {
        require_non_negative(where + ".u_rr", d.u_rr, "m");
        if (r_min > 0 && !(d.u_rr < 0.6 * r_min))
            throw InputError(where + ".u_rr = " + format_number(d.u_rr) +
                             " m: must be < 0.6 r_min = " + format_number(0.6 * r_min) +
                             " m (eq. 2.71 needs r_rr = r - u_rr > 2/5 r for the smallest disc)");
    }
    if (d.model == 3) require_range(where + ".mu_br", d.mu_br, 0.0, 1.0, false, "(factor)");
    if (d.model == 3 && d.mu_br == 0.0) throw InputError(where + ".mu_br = 0: must be in (0, 1]");
}

// Eq. 2.71: d_omega = -g c_rr / (r (r_rr - 2/5 r)) dt, eq. 2.72: r_rr = sqrt(r^2 - c_rr^2).
// The calibrated input is the penetration u_rr = r - r_rr, so c_rr = sqrt(r^2 - (r - u_rr)^2).
double preh_poisel_factor(double r, double u_rr) {
    const double r_rr = r - u_rr;
    const double c_rr = std::sqrt(std::max(0.0, r * r - r_rr * r_rr));
    return c_rr / (r * (r_rr - 0.4 * r));
}

}  // namespace demlab
