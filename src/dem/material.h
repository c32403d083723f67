// A material (of discs or of walls) and the rules that combine two bodies' properties into
// one contact.
#pragma once
#include <string>

namespace demlab {

// A material. Discs and walls both refer to one by its index in the world (World::add_material;
// DiscDef::material, WallDef::material). Discs have unit thickness (1 m, as PFC2D):
// m = rho pi r^2, I = m r^2 / 2. A wall's material gives the wall's own stiffnesses, in series
// with the disc's, and its friction coefficient; its density is not used (a wall is of
// infinite mass), though it is validated as a disc's.
struct MaterialDef {
    double density = 2672.0;        // kg/m3, quartz sand (Table 15); not used for a wall
    double kn = 1.0e8;              // N/m, the body's own normal stiffness (two in series per contact)
    double ks = 1.0e8;              // N/m, the body's own shear stiffness
    double friction = 0.27732;      // -, Coulomb coefficient; tan(15.5 deg), the calibrated disc-disc angle
};

void validate(const MaterialDef& m, const std::string& where);

// Which of two friction coefficients a contact takes (PFC: the smaller; the thesis set the
// larger at disc-wall contacts, section 4.3.2).
enum class FrictionRule { Min, Max };

inline double combine_friction(FrictionRule rule, double mu1, double mu2) {
    return rule == FrictionRule::Min ? (mu1 < mu2 ? mu1 : mu2) : (mu1 > mu2 ? mu1 : mu2);
}

// Stiffnesses in series (eq. 2.59, 2.61): k = 1 / (1/k1 + 1/k2).
inline double series_stiffness(double k1, double k2) { return k1 * k2 / (k1 + k2); }

// Effective mass of a contact (eq. 2.60, 2.62); a wall is of infinite mass.
inline double effective_mass(double m1, double m2) { return m1 * m2 / (m1 + m2); }

}  // namespace demlab
