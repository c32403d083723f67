// The thesis' three models of particle rotation (section 5, Table 15).
//   Model 1: rotation locked, omega = 0 always.
//   Model 2: rotation free; rolling resistance at disc-wall contacts (Preh & Poisel 2007).
//   Model 3: Model 2 plus rotational damping mu_Br at disc-disc contacts (eq. 2.75).
#pragma once
#include <string>

namespace demlab {

// How g in eq. 2.71 is read. Literal: gravity's magnitude, as printed (the derivation puts
// the wall's normal force N = m g). NormalForce: N / m with the disc's actual wall normal force.
enum class RollingForm { Literal, NormalForce };

// Whether mu_Br multiplies omega once per step for a disc touching any disc (eq. 2.75 as
// read) or once per disc-disc contact (mu_Br^k for k contacts).
enum class RotDampingPer { Disc, Contact };

struct RotationDef {
    int model = 3;                                 // 1, 2 or 3
    double u_rr = 0.00015;                         // m, penetration depth of the rolling-resistance model (Table 15)
    RollingForm rolling_form = RollingForm::Literal;
    double mu_br = 0.5;                            // -, rotational damping factor in (0, 1] (Table 15); 1 = none
    RotDampingPer damping_per = RotDampingPer::Disc;
};

// Checks the model number, u_rr in [0, 0.6 r_min) (so r_rr > 2/5 r) and mu_br in (0, 1].
void validate(const RotationDef& d, double r_min, const std::string& where);

// Geometry factor of eq. 2.71-2.72: c_rr / (r (r_rr - 2/5 r)) with r_rr = r - u_rr and
// c_rr = sqrt(r^2 - r_rr^2), in 1/m. The angular deceleration is g times this.
double preh_poisel_factor(double r, double u_rr);

// Reduces |omega| by delta (>= 0) without changing its sign (eq. 2.73: "never past zero").
inline double reduce_towards_zero(double omega, double delta) {
    if (omega > delta) return omega - delta;
    if (omega < -delta) return omega + delta;
    return 0.0;
}

}  // namespace demlab
