// A set-up: the part of a scenario that says where the mass runs. It gives the run its walls,
// its release (a box the mass is generated in, or none: explicit discs), and what the
// measurements need: the bed path (front, deposit, run-up), which walls' loads go to
// forces.csv, and whether the deposit's envelope is measured. The run loop, the renderer and
// the plots ask the set-up; none of them tests a scenario's tables.
//
// Set-ups (make_setup picks one from the scenario's tables):
//   flume      the thesis' flume (Table 2): slope W1, arc W2, barrier W3, gate, lid
//   dam_break  the calibration's column on a floor (section 4.3.3)
//   terrain    walls from a CSV polyline (x, y in m), a release polygon or explicit discs
//   explicit   [[walls]] and [[discs]] only
// Adding one is a new class here and a line in make_setup (plus its key table in the
// scenario's registry).
#pragma once
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "geometry/bed_path.h"
#include "scenario/scenario.h"
#include "setups/flume.h"

namespace demlab {

class World;

// A named group of walls (indices of the run's world) whose summed load forms forces.csv's
// columns fx_<name>, fy_<name> (N/m) and ix_<name>, iy_<name> (N s/m).
struct ForceGroup {
    std::string name;
    std::vector<int> walls;
};

// Which walls' loads fill forces.csv. The slope, arc and barrier are roles the landmarks read
// (the peak x-force on the barrier, the peak y-force on the arc); a set-up without one leaves
// it empty and forces.csv has no such columns. `others` are a set-up's own groups (the dam
// break's floor and back wall). The gate's columns come last, where the set-up has a gate.
struct ForceWalls {
    std::vector<int> slope, arc, barrier;
    std::vector<ForceGroup> others;
    int gate = -1;
    // the groups forces.csv holds, in its column order: slope, arc and barrier where present, then the others
    std::vector<ForceGroup> written() const {
        std::vector<ForceGroup> g;
        if (!slope.empty()) g.push_back({"slope", slope});
        if (!arc.empty()) g.push_back({"arc", arc});
        if (!barrier.empty()) g.push_back({"barrier", barrier});
        g.insert(g.end(), others.begin(), others.end());
        return g;
    }
};

// Where the run-up is measured along a bed path: beyond s_barrier, above the barrier's foot.
struct BarrierMarks {
    double s_barrier = INFINITY;  // m; infinite: no barrier (no run-up, no arrival time)
    Vec2 foot{0.0, 0.0};          // m
};

class Setup {
public:
    virtual ~Setup() = default;
    virtual std::string kind() const = 0;
    // The set-up's walls for the run, in the order the world numbers them ([[walls]] follow),
    // of the scenario's wall material (kWallMaterial: a world adds scenario_materials).
    virtual std::vector<WallDef> walls() const = 0;
    // Whether the discs are generated in a release box (and its box).
    virtual bool has_release() const { return false; }
    virtual ReleaseBox release_box() const;
    // The bed path over the world's joined walls (null: the set-up has none).
    virtual std::unique_ptr<BedPath> bed_path(const World& /*w*/) const { return nullptr; }
    virtual BarrierMarks barrier(const BedPath& /*path*/) const { return {}; }
    virtual ForceWalls force_walls() const { return {}; }
    // The deposit's upper envelope over [0, envelope_length()] and its slope angles (dam break).
    virtual bool measures_envelope() const { return false; }
    virtual double envelope_length() const { return 0.0; }
    // Points the run's domain must hold besides the walls' ends and the discs.
    virtual std::vector<Vec2> extent() const { return {}; }
};

std::unique_ptr<Setup> make_setup(const Scenario& s);

}  // namespace demlab
