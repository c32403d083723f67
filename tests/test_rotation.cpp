// Rotation models: Preh-Poisel rolling resistance (eq. 2.71-2.73) and Model 3's damping (eq. 2.75).
#include <gtest/gtest.h>

#include "helpers.h"

using namespace demlab;
using namespace demlab::test;

TEST(PrehPoisel, WorkedExampleOfPhysicsMd) {
    // r = 1.5 mm, u_rr = 0.15 mm: c_rr = 0.654 mm, deceleration about 5,700 rad/s2
    const double r = 0.0015, u = 0.00015;
    const double r_rr = r - u, c_rr = std::sqrt(r * r - r_rr * r_rr);
    EXPECT_NEAR(c_rr, 0.654e-3, 0.001e-3);
    EXPECT_NEAR(9.81 * preh_poisel_factor(r, u), 5701.0, 5.0);
}

namespace {
// A disc spinning at omega0 on a frictionless horizontal floor under gravity.
World spinning_disc(int model, RollingForm form, double omega0, double r, double u_rr) {
    WorldDef def;
    def.rotation.model = model;
    def.rotation.u_rr = u_rr;
    def.rotation.rolling_form = form;
    def.damping.beta_s = 0.0;  // no shear dashpot: the frictionless floor exerts no torque
    def.timestep.automatic = false;
    World w(def);
    const int m = w.add_material(material(0.0));
    const double mass = 2672.0 * kPi * r * r;
    const double overlap = mass * 9.81 / 5e7;
    w.add_disc({Vec2(0.0, r - overlap), r, Vec2::Zero(), omega0, 0.0, m});
    w.add_wall(segment(w, Vec2(-1, 0), Vec2(1, 0), 0.0, SegmentSolid::Right));
    w.set_dt(1e-6);
    w.finalize();
    return w;
}
}  // namespace

TEST(PrehPoisel, SpinningDiscDeceleratesAtEq271AndStopsWithoutReversing) {
    const double r = 0.0015, u = 0.00015, omega0 = 20.0;
    World w = spinning_disc(2, RollingForm::Literal, omega0, r, u);
    const double decel = 9.81 * preh_poisel_factor(r, u);
    w.run(1000);  // 1 ms
    EXPECT_NEAR(w.omegas()[0], omega0 - decel * w.time(), 1e-9 * omega0);
    // it stops after omega0 / decel = 3.5 ms and stays stopped
    w.run(6000);
    EXPECT_EQ(w.omegas()[0], 0.0);
    const double angle = w.angles()[0];
    w.run(1000);
    EXPECT_EQ(w.omegas()[0], 0.0);
    EXPECT_EQ(w.angles()[0], angle);
    // the angle turned equals omega0^2 / (2 decel) within a step's worth
    EXPECT_NEAR(angle, omega0 * omega0 / (2.0 * decel), omega0 * 2e-6);
}

TEST(PrehPoisel, NormalForceFormUsesTheActualWallForce) {
    const double r = 0.0015, u = 0.00015, omega0 = -20.0;
    World w = spinning_disc(2, RollingForm::NormalForce, omega0, r, u);
    w.run(1000);
    // at rest on the floor N = m g, so the rate equals the literal one (to the spring's jitter)
    const double decel = 9.81 * preh_poisel_factor(r, u);
    EXPECT_NEAR(w.omegas()[0], omega0 + decel * w.time(), 0.002 * std::abs(omega0));
}

TEST(PrehPoisel, RefusesPenetrationBeyondSixTenthsOfTheSmallestRadius) {
    WorldDef def;
    def.rotation.model = 2;
    def.rotation.u_rr = 0.0007;
    World w(def);
    const int m = w.add_material(material(0.3));
    w.add_disc({Vec2(0, 0), 0.001, Vec2::Zero(), 0, 0, m});
    EXPECT_THROW(w.finalize(), InputError);
}

namespace {
// Three discs in a row, just touching, no gravity, no friction: the middle one has two contacts.
World row_of_three(RotDampingPer per) {
    WorldDef def;
    def.gravity = Vec2::Zero();
    def.rotation.model = 3;
    def.rotation.mu_br = 0.5;
    def.rotation.damping_per = per;
    def.damping.beta_s = 0.0;
    def.timestep.automatic = false;
    World w(def);
    const int m = w.add_material(material(0.0));
    const double r = 0.001, gap = -1e-7;  // slight overlap
    for (int k = 0; k < 3; ++k) w.add_disc({Vec2(k * (2 * r + gap), 0), r, Vec2::Zero(), 10.0, 0.0, m});
    w.set_dt(1e-7);
    w.finalize();
    return w;
}
}  // namespace

TEST(RotationalDamping, Model3MultipliesOmegaByMuBrOncePerDisc) {
    World w = row_of_three(RotDampingPer::Disc);
    w.step();
    for (int k = 0; k < 3; ++k) EXPECT_DOUBLE_EQ(w.omegas()[size_t(k)], 5.0);
    w.step();
    for (int k = 0; k < 3; ++k) EXPECT_DOUBLE_EQ(w.omegas()[size_t(k)], 2.5);
}

TEST(RotationalDamping, PerContactOptionAppliesItOncePerContact) {
    World w = row_of_three(RotDampingPer::Contact);
    w.step();
    EXPECT_DOUBLE_EQ(w.omegas()[0], 5.0);
    EXPECT_DOUBLE_EQ(w.omegas()[1], 2.5);  // two contacts: 0.5^2
    EXPECT_DOUBLE_EQ(w.omegas()[2], 5.0);
}

TEST(RotationModels, Model1KeepsOmegaZero) {
    WorldDef def;
    def.rotation.model = 1;
    World w(def);
    const int m = w.add_material(material(0.5));
    w.add_disc({Vec2(0, 0.001), 0.001, Vec2(1.0, 0.0), 50.0, 0.0, m});
    w.add_wall(segment(w, Vec2(-1, 0), Vec2(1, 0), 0.5));
    w.finalize();
    w.run(2000);
    EXPECT_EQ(w.omegas()[0], 0.0);
    EXPECT_EQ(w.angles()[0], 0.0);
}
