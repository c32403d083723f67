// What the run loop needs of a solver (run.cpp): step it, read its clock, watch its energy,
// and save and load its state for checkpoints. The DEM world is the first solver; a
// continuum solver (DAN, docs/spec/DAN.md) is meant to be the second, with measurements of its
// own beside the loop. A virtual call per step, never per disc or contact.
#pragma once
#include "core/binary_io.h"
#include "dem/world.h"

namespace demlab {

class Solver {
public:
    virtual ~Solver() = default;
    virtual void step() = 0;
    virtual double time() const = 0;            // s, simulated
    virtual double dt() const = 0;              // s, the next step
    virtual long step_count() const = 0;
    virtual double kinetic_energy() const = 0;  // J/m after the last step (the rest watch)
    virtual EnergyReport energy() const = 0;    // the ledger (energy.csv, the energy watch)
    virtual void save_state(BinaryWriter& out) const = 0;
    virtual void load_state(BinaryReader& in) = 0;
};

// The DEM world as a solver.
class DemSolver final : public Solver {
public:
    explicit DemSolver(World& w) : w_(w) {}
    void step() override { w_.step(); }
    double time() const override { return w_.time(); }
    double dt() const override { return w_.dt(); }
    long step_count() const override { return w_.step_count(); }
    double kinetic_energy() const override { return w_.kinetic_energy(); }
    EnergyReport energy() const override { return w_.energy(); }
    void save_state(BinaryWriter& out) const override { w_.save_state(out); }
    void load_state(BinaryReader& in) override { w_.load_state(in); }

private:
    World& w_;
};

}  // namespace demlab
