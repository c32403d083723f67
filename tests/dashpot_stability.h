// The dashpot stability cases shared by the tests and the slow validation run: a pressed pair
// with free rotation and a pack of 2,000 discs settling and lying still, at PFC's step rule as
// printed (safety 0.8, no damping correction), watched for energy that grows and dissipation
// that goes back.
#pragma once
#include <cmath>
#include <functional>

#include "dem/world.h"
#include "helpers.h"

namespace demlab::test {

// What a watched run showed.
struct DashpotWatch {
    bool threw = false;           // the run blew up
    double energy_rise = 0.0;     // J/m, the largest rise of kinetic + potential + elastic over its lowest so far
    double dissipation_drop = 0.0;  // J/m, the largest fall of the contacts' dissipation below its highest so far
    double energy_start = 0.0, energy_end = 0.0;
    double kinetic_end = 0.0;     // J/m
    long steps = 0;
    int discs = 0;
};

inline WorldDef pfc_rule_def(DashpotScheme scheme) {
    WorldDef def;
    def.damping.beta_n = def.damping.beta_s = 0.5;  // the thesis' (Table 15)
    def.rotation.model = 2;                         // free rotation
    def.rotation.u_rr = 0.0;                        // and no rolling resistance
    def.timestep.safety = 0.8;
    def.timestep.dashpots = scheme;
    def.timestep.damping_correction = false;        // PFC's rule as printed
    return def;
}

// Steps w, sampling every `every` steps.
inline DashpotWatch watch(World& w, long steps, long every) {
    DashpotWatch out;
    out.discs = int(w.disc_count());
    auto mechanical = [&] {
        const EnergyReport e = w.energy();
        return e.kinetic_translation + e.kinetic_rotation + e.potential + e.elastic;
    };
    double lowest = mechanical(), highest_diss = w.energy().dissipated_contacts;
    out.energy_start = lowest;
    try {
        for (long s = 0; s < steps; ++s) {
            w.step();
            if ((s + 1) % every != 0) continue;
            const double e = mechanical();
            const double d = w.energy().dissipated_contacts;
            if (!std::isfinite(e)) {
                out.threw = true;
                break;
            }
            out.energy_rise = std::max(out.energy_rise, e - lowest);
            out.dissipation_drop = std::max(out.dissipation_drop, highest_diss - d);
            lowest = std::min(lowest, e);
            highest_diss = std::max(highest_diss, d);
            out.energy_end = e;
            const EnergyReport r = w.energy();
            out.kinetic_end = r.kinetic_translation + r.kinetic_rotation;
        }
    } catch (const std::exception&) {
        out.threw = true;
    }
    out.steps = w.step_count();
    return out;
}

// Two discs pressed together between two soft walls (no gravity), one of them spun: the
// pair's shear mode with free rotation, the case the lagged dashpot makes unstable at PFC's
// rule. The walls are 50 times softer than the pair's contact, so the pair's own stiffness
// sets the step (as for a free pair) while the walls press it with 99 N/m.
inline DashpotWatch pressed_pair(DashpotScheme scheme, long steps) {
    WorldDef def = pfc_rule_def(scheme);
    def.gravity = Vec2::Zero();
    World w(def);
    const int m = w.add_material(material(0.5));
    const double r = 0.0025, wall_press = 1e-4, pair_press = 2e-6;  // m: the contacts' overlaps
    const double xa = 0.0, xb = 2 * r - pair_press;
    w.add_disc({Vec2(xa, 0.0), r, Vec2::Zero(), 5.0, 0.0, m});
    w.add_disc({Vec2(xb, 0.0), r, Vec2::Zero(), 0.0, 0.0, m});
    for (double x : {xa - r + wall_press, xb + r - wall_press}) {
        WallDef wall = segment(Vec2(x, -0.1), Vec2(x, 0.1));  // the pair rolls along them
        wall.material = wall_material(w, 0.5, 1e6);
        w.add_wall(wall);
    }
    w.finalize();
    return watch(w, steps, 100);
}

// About 2,000 discs of radii 2-3 mm dropped from a lattice into a box 0.3 m wide: they
// settle, then lie still.
inline DashpotWatch settling_pack(DashpotScheme scheme, long steps) {
    World w(pfc_rule_def(scheme));
    const int m = w.add_material(material(0.5));
    const double pitch = 0.0061, width = 0.3;
    int row = 0;
    for (double y = pitch / 2; row < 42; y += pitch * 0.866, ++row)
        for (double x = pitch / 2 + (row % 2) * pitch / 2; x + pitch / 2 < width; x += pitch)
            w.add_disc({Vec2(x, y), 0.0025 + 0.0005 * std::sin(x * 1000 + y * 777), Vec2::Zero(), 0, 0, m});
    w.add_wall(segment(w, Vec2(-0.01, 0), Vec2(width + 0.01, 0), 0.5, SegmentSolid::Right));
    w.add_wall(segment(w, Vec2(0, 0.4), Vec2(0, -0.01), 0.5, SegmentSolid::Right));
    w.add_wall(segment(w, Vec2(width, -0.01), Vec2(width, 0.4), 0.5, SegmentSolid::Right));
    w.finalize();
    return watch(w, steps, 1000);
}

}  // namespace demlab::test
