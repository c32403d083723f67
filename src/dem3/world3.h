// The 3-D discrete-element world: equal or unequal spheres that do not rotate, on a
// triangulated terrain (tin.h), with Mikhailov's DEBRIS law in its 3-D form (DEBRIS.md D1-D4,
// D12; the algebra shared with the 2-D law in dem/laws/debris_law.h):
//   bed   F = E pi a^2 delta / R,          a^2 = R^2 - d^2, along the feature's normal
//   pair  F = E pi a^2 delta / (Ri + Rj),  a the half common chord, away from the other sphere
//   friction per sphere against its velocity, mu (N + P) + eta |v|, "trial" or "previous"
//   step  min(dt_max, safety min sqrt(m / K)), K the tangent stiffnesses one step ahead,
//         growing by at most 5 % a step (the 2-D law's rule, capped_growing_step)
// Each sphere gathers its own contacts (a pair is computed from both sides), so the result is
// the same on any number of threads. Bonds (set_bonds; dem/bonds/elastic_bond.h with the
// spheres' face, k0 = E L0/(2 sqrt 2) per bond) act beside the contacts as in 2-D: a central
// spring that breaks for good past its strain, evaluated once per bond in bond order, so the
// sums are the same on any number of threads too. Their force is not a contact force: it does
// not enter the friction's N + P. A sphere whose centre leaves the terrain's box in map
// view by more than its radius, or falls below the terrain by its height, is lost: it stops
// moving and counts no more.
#pragma once
#include <cstdint>
#include <memory>
#include <vector>

#include "core/binary_io.h"
#include "core/thread_pool.h"
#include "core/vec3.h"
#include "dem/bonds/elastic_bond.h"
#include "dem/laws/debris_law.h"
#include "dem3/tin.h"

namespace demlab {

struct Dem3Def {
    double youngs_modulus = 4e10;  // Pa, E of the spheres and of the bed (Mikhailov, Attabad: 40 GPa)
    double mu = 0.3;               // -, dry friction coefficient
    double eta = 0.0;              // N s/m, viscous friction of a sphere
    DebrisNormal friction_normal = DebrisNormal::Resultant;
    DebrisDirection friction_direction = DebrisDirection::Trial;
    double dt_max = 0.01;          // s, the step's ceiling (Mikhailov's step)
    double dt_fixed = 0.0;         // s, a fixed step instead of the rule (0: the rule)
    double safety = 0.8;           // -, of the rule
    double gravity = 9.81;         // m/s2, along -z
    int threads = 1;
};

// J; the ledger: kinetic + potential + elastic + dissipated stays at its start (DEBRIS.md 4.3)
struct Energy3 {
    double kinetic = 0.0;      // sum m v(n-1/2) . v(n+1/2) / 2: the leapfrog's energy at t_n
    double potential = 0.0;    // sum m g z at x_n
    double elastic = 0.0;      // the contacts' at x_n
    double dissipated = 0.0;   // by friction, so far
    double lost = 0.0;         // carried away by lost spheres
    double bond_elastic = 0.0;  // the intact bonds' at x_n (C7)
    double bond_broken = 0.0;   // the bonds' energy when they broke (C12)
    double balance() const { return kinetic + potential + elastic + dissipated + lost + bond_elastic + bond_broken; }
};

class World3 {
public:
    World3(const Dem3Def& def, std::shared_ptr<const Tin> terrain);

    void add_sphere(const Vec3& position, const Vec3& velocity, double radius, double density);
    // Bonds between spheres k != l with their rest lengths at the spheres' present positions;
    // replaces any earlier bonds. Refused: a missing sphere, a pair given twice.
    void set_bonds(const BondDef& def, const std::vector<std::pair<int, int>>& pairs);
    void step();
    // The contacts, bonds and ledger at the present positions without a step: a run's t = 0
    // (its first row then holds the start's energies, kinetic as sum m v^2 / 2).
    void measure();

    double time() const { return time_; }
    double dt() const { return dt_; }          // s, the last step's
    long step_count() const { return steps_; }
    size_t size() const { return pos_.size(); }
    const std::vector<Vec3>& positions() const { return pos_; }
    const std::vector<Vec3>& velocities() const { return vel_; }  // m/s, at the last half step
    const std::vector<double>& radii() const { return radius_; }
    const std::vector<double>& masses() const { return mass_; }
    const std::vector<std::uint8_t>& lost() const { return lost_; }
    size_t lost_count() const;
    double kinetic_energy() const;             // J, sum m v^2 / 2 at the last half step
    Energy3 energy() const { return energy_; }
    long contacts() const { return contacts_; }  // bed and pair contacts at the last pass
    Vec3 bed_force(size_t i) const { return load_.empty() ? Vec3::Zero() : load_[i].bed; }  // N, at the last pass
    const Tin& terrain() const { return *tin_; }
    const Dem3Def& def() const { return def_; }
    const std::vector<Bond>& bonds() const { return bonds_; }
    size_t intact_bonds() const { return intact_; }
    const std::vector<BondBreakEvent>& bond_breaks() const { return breaks_; }  // in the order they broke

    void save_state(BinaryWriter& out) const;
    void load_state(BinaryReader& in);

private:
    struct Load {                   // one sphere's gathered contacts at x_n
        Vec3 bed = Vec3::Zero();    // N, sum of the bed reactions
        Vec3 pairs = Vec3::Zero();  // N, sum of the pair forces
        Vec3 bonds = Vec3::Zero();  // N, sum of the bond forces
        double moduli = 0.0;        // N, sum of all their moduli ("sum")
        double k = 0.0;             // N/m, tangent stiffnesses ahead
        double elastic = 0.0;       // J, the bed's and half the pairs' energy
        int touching = 0;
    };
    void build_cells();
    void gather(size_t i, double ahead_dt, Load& l, std::vector<TinContact>& bed) const;
    void gather_all(double ahead_dt);
    double tally();
    void add_bond_forces();
    void book_lost(double dt);
    void integrate(double dt);

    Dem3Def def_;
    std::shared_ptr<const Tin> tin_;
    std::unique_ptr<ThreadPool> pool_;
    std::vector<Vec3> pos_, vel_;
    std::vector<double> radius_, mass_;
    std::vector<std::uint8_t> lost_;
    std::vector<Load> load_;
    // the cell list, rebuilt every step: spheres sorted by cell
    double cell_ = 1.0, r_max_ = 0.0;
    std::vector<std::pair<std::uint64_t, std::uint32_t>> cells_;
    std::int64_t cell_origin_[3] = {0, 0, 0};  // the cells' indices are counted from here (build_cells)
    double time_ = 0.0, dt_ = 0.0;
    long steps_ = 0;
    long contacts_ = 0;
    Energy3 energy_;
    std::vector<std::uint32_t> just_lost_;  // lost in the last step, booked in the next (book_lost)
    BondDef bond_def_;
    std::vector<Bond> bonds_;
    size_t intact_ = 0;
    std::vector<BondBreakEvent> breaks_;
};

}  // namespace demlab
