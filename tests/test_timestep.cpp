// The automatic time step equals its formula (timestep.h).
#include <gtest/gtest.h>

#include "helpers.h"
#include "dem/timestep.h"

using namespace demlab;
using namespace demlab::test;

TEST(TimeStep, LoneDiscUsesItsOwnStiffness) {
    // centred dashpots (the default): PFC's rule as printed; lagged ones: with the correction
    for (const DashpotScheme scheme : {DashpotScheme::Centred, DashpotScheme::Lagged})
        for (int model : {1, 2}) {
            WorldDef def;
            def.rotation.model = model;
            def.rotation.u_rr = 0.0;
            def.timestep.dashpots = scheme;
            World w(def);
            const int m = w.add_material(material(0.3, 1e8));
            const double r = 0.002;
            w.add_disc({Vec2(0, 0), r, Vec2::Zero(), 0, 0, m});
            w.finalize();
            const bool lagged = scheme == DashpotScheme::Lagged;
            const double mass = 2672.0 * kPi * r * r, inertia = 0.5 * mass * r * r;
            const double phi_t = lagged ? translational_damping_factor(0.5) : 1.0;
            double t2 = phi_t * phi_t * mass / 1e8;
            if (model != 1) {
                const double phi = lagged ? rotational_damping_factor(0.5) : 1.0;
                t2 = std::min(t2, phi * phi * inertia / (1e8 * r * r));
            }
            EXPECT_DOUBLE_EQ(w.dt(), 0.8 * std::sqrt(t2)) << "model " << model << " lagged " << lagged;
        }
}

TEST(TimeStep, SumsTheStiffnessOfCurrentContacts) {
    // a disc resting on a floor and touching a neighbour: two contacts of 5e7 N/m each
    WorldDef def;
    def.rotation.model = 2;
    def.rotation.u_rr = 0.0;
    def.damping.beta_s = 0.0;  // phi = 1: PFC's rule as printed
    def.damping.beta_n = 0.0;  // phi_t = 1
    def.timestep.safety = 0.7;
    World w(def);
    const int m = w.add_material(material(0.3, 1e8));
    const double r = 0.002, big = 0.004;
    w.add_disc({Vec2(0, r - 1e-7), r, Vec2::Zero(), 0, 0, m});
    // the big disc rests on the floor beside the small one, overlapping it by 0.1 um
    const double dy = (big - 1e-7) - (r - 1e-7), reach = r + big - 1e-7;
    w.add_disc({Vec2(std::sqrt(reach * reach - dy * dy), big - 1e-7), big, Vec2::Zero(), 0, 0, m});
    w.add_wall(segment(w, Vec2(-1, 0), Vec2(1, 0), 0.3));
    w.finalize();
    const double m_small = 2672.0 * kPi * r * r;
    const double m_big = 2672.0 * kPi * big * big;
    // small disc: floor + big disc; big disc: floor + small disc: both K = 1e8
    const double t_small = std::min(m_small / 1e8, 0.5 * m_small * r * r / (1e8 * r * r));
    const double t_big = std::min(m_big / 1e8, 0.5 * m_big / 1e8);
    EXPECT_DOUBLE_EQ(w.dt(), 0.7 * std::sqrt(std::min(t_small, t_big)));
    EXPECT_DOUBLE_EQ(w.automatic_dt(), w.dt());
}

TEST(TimeStep, DampingCorrectionFactor) {
    EXPECT_DOUBLE_EQ(rotational_damping_factor(0.0), 1.0);
    EXPECT_DOUBLE_EQ(translational_damping_factor(0.0), 1.0);
    EXPECT_NEAR(translational_damping_factor(0.5), 0.8740, 1e-4);
    // z = sqrt(3) / 2: (2 / sqrt 3)(sqrt(1.75) - 0.866) = 0.5275
    EXPECT_NEAR(rotational_damping_factor(0.5), 0.5275, 1e-4);
}

TEST(TimeStep, ThesisDampingIsStableWithFreeRotation) {
    // a dense random pile with beta_n = beta_s = 0.5 and free rotation: with PFC's rule
    // alone this blows up; with the correction it settles
    WorldDef def;
    def.rotation.model = 2;
    def.rotation.u_rr = 0.0;
    World w(def);
    const int m = w.add_material(material(0.3));
    const double pitch = 0.0061;
    int row = 0;
    for (double y = pitch / 2; y < 0.1; y += pitch * 0.866, ++row)
        for (double x = pitch / 2 + (row % 2) * pitch / 2; x + pitch / 2 < 0.06; x += pitch)
            w.add_disc({Vec2(x, y), 0.0025 + 0.0005 * std::sin(x * 1000 + y * 777), Vec2::Zero(), 0, 0, m});
    w.add_wall(segment(w, Vec2(-0.01, 0), Vec2(0.3, 0), 0.4, SegmentSolid::Right));
    w.add_wall(segment(w, Vec2(0, 0.2), Vec2(0, -0.01), 0.4, SegmentSolid::Right));
    w.finalize();
    EXPECT_NO_THROW(while (w.time() < 0.15) w.step());
    const EnergyReport e = w.energy();
    EXPECT_LT(e.kinetic_translation + e.kinetic_rotation, 1.0);
}
