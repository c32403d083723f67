// The linear contact law: closed forms of a normal impact, the Coulomb cap and PFC's dashpot modes.
#include <gtest/gtest.h>

#include "dem/laws/contact_law.h"
#include "helpers.h"

using namespace demlab;
using namespace demlab::test;

namespace {

WorldDef impact_def(double beta) {
    WorldDef def;
    def.gravity = Vec2::Zero();
    def.damping.beta_n = beta;
    def.damping.beta_s = beta;
    def.rotation.model = 1;
    def.timestep.automatic = false;
    return def;
}

// A disc hits a wall head-on at 1 m/s; returns the rebound speed over the impact speed.
double wall_restitution(double beta) {
    World w(impact_def(beta));
    const int m = w.add_material(material(0.3));
    const double r = 0.0015;
    w.add_disc({Vec2(0.0, r + 1e-6), r, Vec2(0.0, -1.0), 0.0, 0.0, m});
    w.add_wall(segment(w, Vec2(-0.1, 0.0), Vec2(0.1, 0.0)));
    // contact duration pi sqrt(m / k); resolve it with ~2000 steps
    const double mass = 2672.0 * kPi * r * r;
    const double duration = kPi * std::sqrt(mass / 5e7);
    w.set_dt(duration / 2000.0);
    w.finalize();
    bool touched = false;
    for (int s = 0; s < 20000; ++s) {
        w.step();
        if (w.touching_wall_pairs() > 0) touched = true;
        if (touched && w.touching_wall_pairs() == 0) break;
    }
    EXPECT_TRUE(touched);
    return w.velocities()[0].y() / 1.0;
}

// Two discs of different size meet at 1 m/s each; returns the relative rebound ratio.
double disc_restitution(double beta) {
    World w(impact_def(beta));
    const int m = w.add_material(material(0.3));
    const double r1 = 0.001, r2 = 0.002;
    w.add_disc({Vec2(-r1 - 1e-6, 0.0), r1, Vec2(1.0, 0.0), 0.0, 0.0, m});
    w.add_disc({Vec2(r2 + 1e-6, 0.0), r2, Vec2(-1.0, 0.0), 0.0, 0.0, m});
    const double m1 = 2672.0 * kPi * r1 * r1, m2 = 2672.0 * kPi * r2 * r2;
    const double duration = kPi * std::sqrt(effective_mass(m1, m2) / 5e7);
    w.set_dt(duration / 2000.0);
    w.finalize();
    bool touched = false;
    for (int s = 0; s < 20000; ++s) {
        w.step();
        if (w.touching_disc_pairs() > 0) touched = true;
        if (touched && w.touching_disc_pairs() == 0) break;
    }
    EXPECT_TRUE(touched);
    return (w.velocities()[1].x() - w.velocities()[0].x()) / 2.0;
}

}  // namespace

class Restitution : public ::testing::TestWithParam<double> {};

TEST_P(Restitution, DiscOnWallMatchesClosedForm) {
    const double beta = GetParam();
    EXPECT_NEAR(wall_restitution(beta), restitution(beta), 0.01 * restitution(beta));
}

TEST_P(Restitution, DiscOnDiscMatchesClosedForm) {
    const double beta = GetParam();
    EXPECT_NEAR(disc_restitution(beta), restitution(beta), 0.01 * restitution(beta));
}

INSTANTIATE_TEST_SUITE_P(Betas, Restitution, ::testing::Values(0.0, 0.1, 0.3, 0.5, 0.7));

TEST(LinearContact, ThesisDampingGivesRestitution0163) { EXPECT_NEAR(restitution(0.5), 0.163, 0.0005); }

TEST(LinearContact, ShearSpringIsCappedAtMuTimesElasticNormalForce) {
    LinearContactParams p{1e8, 1e8, 0.5, 100.0, 100.0, DashpotMode::Full};
    // overlap 1e-5 -> Fn = 1000 N; a large shear increment must be capped at 500 N
    const LinearContactForce f = linear_contact(p, 1e-5, 0.0, 1.0, 1e-4, 0.0);
    EXPECT_TRUE(f.sliding);
    EXPECT_DOUBLE_EQ(f.fs_spring, -500.0);
    EXPECT_DOUBLE_EQ(f.ft, -500.0 - 100.0);  // the dashpot is added on top in mode 0
    EXPECT_GT(f.slip_work, 0.0);
}

TEST(LinearContact, ShearSpringIsIncrementalBelowTheCap) {
    LinearContactParams p{1e8, 2e7, 0.5, 0.0, 0.0, DashpotMode::Full};
    const LinearContactForce f = linear_contact(p, 1e-5, 0.0, 0.01, 1e-4, 3.0);
    EXPECT_FALSE(f.sliding);
    EXPECT_DOUBLE_EQ(f.fs_spring, 3.0 - 2e7 * 0.01 * 1e-4);
}

TEST(LinearContact, DashpotModesFollowPFC) {
    // separating fast: the normal dashpot pulls (tension) unless the mode forbids it
    const double overlap = 1e-6, vn = 10.0, vs = 1.0, dt = 1e-4;
    LinearContactParams p{1e8, 1e8, 0.1, 50.0, 50.0, DashpotMode::Full};
    EXPECT_LT(linear_contact(p, overlap, vn, vs, dt, 0.0).fn, 0.0);
    p.mode = DashpotMode::NoTension;
    EXPECT_DOUBLE_EQ(linear_contact(p, overlap, vn, vs, dt, 0.0).fn, 0.0);
    // sliding: the shear dashpot is switched off in modes 2 and 3
    p.mode = DashpotMode::NoShearWhileSliding;
    LinearContactForce f = linear_contact(p, overlap, vn, vs, dt, 0.0);
    EXPECT_TRUE(f.sliding);
    EXPECT_DOUBLE_EQ(f.ft, f.fs_spring);
    EXPECT_LT(f.fn, 0.0);
    p.mode = DashpotMode::NoTensionNoShearWhileSliding;
    f = linear_contact(p, overlap, vn, vs, dt, 0.0);
    EXPECT_DOUBLE_EQ(f.ft, f.fs_spring);
    EXPECT_DOUBLE_EQ(f.fn, 0.0);
}

TEST(LinearContact, SeriesStiffnessAndFrictionRules) {
    EXPECT_DOUBLE_EQ(series_stiffness(1e8, 1e8), 5e7);
    EXPECT_DOUBLE_EQ(combine_friction(FrictionRule::Min, 0.2, 0.4), 0.2);
    EXPECT_DOUBLE_EQ(combine_friction(FrictionRule::Max, 0.2, 0.4), 0.4);
    EXPECT_NEAR(dashpot_coefficient(0.5, 2.0, 8.0), 0.5 * 2.0 * 4.0, 1e-12);
}
