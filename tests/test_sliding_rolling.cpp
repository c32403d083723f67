// Closed forms on an incline: sliding with rotation locked, sticking, rolling without slip.
#include <gtest/gtest.h>

#include "helpers.h"

using namespace demlab;
using namespace demlab::test;

namespace {

struct InclineResult {
    double accel;     // along the slope, downhill positive, m/s2
    double slip_rate; // |v - omega r| / |v| at the end
    double travel;    // distance moved along the slope, m
};

// A disc of radius 5 mm starts at rest on a segment inclined at theta (degrees) with friction
// mu (disc and wall alike). Measures the acceleration between t1 and t2.
InclineResult incline(double theta_deg, double mu, int model, DashpotMode mode = DashpotMode::NoShearWhileSliding,
                      double t1 = 0.05, double t2 = 0.25) {
    WorldDef def;
    def.rotation.model = model;
    def.rotation.u_rr = 0.0;
    def.damping.beta_n = 0.5;
    def.damping.beta_s = 0.5;
    def.damping.dp_mode = mode;
    def.timestep.automatic = false;
    World w(def);
    const int m = w.add_material(material(mu));
    const double th = deg_to_rad(theta_deg);
    const Vec2 down(std::cos(th), -std::sin(th));   // downhill along the slope
    const Vec2 normal(std::sin(th), std::cos(th));  // out of the slope
    const double r = 0.005;
    const double mass = 2672.0 * kPi * r * r;
    // start at the static overlap, so the normal spring starts in equilibrium
    const double overlap = mass * 9.81 * std::cos(th) / 5e7;
    w.add_disc({normal * (r - overlap), r, Vec2::Zero(), 0.0, 0.0, m});
    WallDef slope = segment(w, -2.0 * down, 3.0 * down, mu, SegmentSolid::Right);
    w.add_wall(slope);
    w.set_dt(2e-6);
    w.finalize();
    const auto along = [&] { return w.velocities()[0].dot(down); };
    while (w.time() < t1) w.step();
    const double v1 = along(), time1 = w.time();
    while (w.time() < t2) w.step();
    const double v2 = along(), time2 = w.time();
    InclineResult res;
    // velocities live at half steps: v(t - dt/2)
    res.accel = (v2 - v1) / (time2 - time1);
    const double v = along();
    res.slip_rate = std::abs(v) > 0 ? std::abs(v + w.omegas()[0] * r) / std::abs(v) : 0.0;
    res.travel = w.positions()[0].dot(down);
    return res;
}

}  // namespace

TEST(Incline, SlidingWithRotationLockedAcceleratesAtGTimesSinMinusMuCos) {
    for (double theta : {30.0, 45.0}) {
        const double mu = 0.3;
        const double expected = 9.81 * (std::sin(deg_to_rad(theta)) - mu * std::cos(deg_to_rad(theta)));
        const InclineResult r = incline(theta, mu, 1);
        EXPECT_NEAR(r.accel, expected, 0.005 * expected) << "theta " << theta;
    }
}

TEST(Incline, PfcMode0ShearDashpotMakesSlidingViscous) {
    // PFC's default keeps the shear dashpot while sliding: the disc reaches the terminal
    // speed (m g sin - mu m g cos) / c_s at once, c_s = 2 beta_s sqrt(m k_s)
    const double theta = 30.0, mu = 0.3, r = 0.005, mass = 2672.0 * kPi * r * r;
    const double cs = 2.0 * 0.5 * std::sqrt(mass * 5e7);
    const double v_terminal =
        mass * 9.81 * (std::sin(deg_to_rad(theta)) - mu * std::cos(deg_to_rad(theta))) / cs;
    const InclineResult res = incline(theta, mu, 1, DashpotMode::Full);
    EXPECT_NEAR(res.accel, 0.0, 1e-6);
    EXPECT_NEAR(res.travel / 0.25, v_terminal, 0.01 * v_terminal);
}

TEST(Incline, StaysPutWhenTanThetaBelowMu) {
    const InclineResult r = incline(10.0, 0.3, 1);
    EXPECT_NEAR(r.accel, 0.0, 1e-3);
    EXPECT_LT(std::abs(r.travel), 1e-6);  // only the elastic creep of the shear spring
}

TEST(Incline, FreeDiscRollsWithoutSlipAtTwoThirdsGSinTheta) {
    const double theta = 20.0;
    const double expected = 2.0 / 3.0 * 9.81 * std::sin(deg_to_rad(theta));
    // rolling needs tan(theta) <= 3 mu (disc: I = m r^2 / 2); mu = 0.5 is ample
    const InclineResult r = incline(theta, 0.5, 2, DashpotMode::Full);
    EXPECT_NEAR(r.accel, expected, 0.005 * expected);
    EXPECT_LT(r.slip_rate, 1e-3);
}

TEST(Incline, FreeDiscSlipsWhenFrictionIsShort) {
    // tan(40) = 0.84 > 3 mu = 0.3: rolls and slides, a = g (sin - mu cos)
    const double theta = 40.0, mu = 0.1;
    const double expected = 9.81 * (std::sin(deg_to_rad(theta)) - mu * std::cos(deg_to_rad(theta)));
    const InclineResult r = incline(theta, mu, 2);
    EXPECT_NEAR(r.accel, expected, 0.005 * expected);
    EXPECT_GT(r.slip_rate, 0.1);
}
