// PFC's simplified Hertz-Mindlin law (hertz_law.h) against Hertz's closed forms: a normal
// impact's largest overlap, peak force and contact time (disc on a wall, disc on disc), the
// restitution with its dashpots against the same equation integrated finely, sliding to rest,
// an undamped gas's energy, the keys, and a flume at scale 20 run to rest.
//
// Undamped impact at v of effective mass m on F = K U^(3/2) (K = a sqrt(R~)): energy gives
//   U_max = (5 m v^2 / (4 K))^(2/5),  F_max = K U_max^(3/2),
//   t_c = 2 (U_max / v) int_0^1 dx / sqrt(1 - x^(5/2)) = 2.94320 U_max / v.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>

#include "core/error.h"
#include "dem/world.h"
#include "files.h"
#include "helpers.h"
#include "run/run.h"
#include "scenario/scenario.h"

using namespace demlab;
using demlab::test::expect_refused;

namespace {

constexpr double kG = 2.9e10, kNu = 0.15, kRho = 2672.0, kR = 0.005;
const double kMass = kRho * kPi * kR * kR;
// 2 int_0^1 dx / sqrt(1 - x^(5/2)) (Hertz's contact time; Johnson, Contact Mechanics, 11.2)
constexpr double kHertzTime = 2.94320;

double hertz_a() { return 2.0 * kG * std::sqrt(2.0) / (3.0 * (1.0 - kNu)); }

WorldDef hertz_world(double beta_n = 0.0, double beta_s = 0.0, Vec2 g = Vec2::Zero()) {
    WorldDef def;
    def.law = law_kind<HertzLaw>();
    def.gravity = g;
    def.damping.beta_n = beta_n;
    def.damping.beta_s = beta_s;
    def.law_def<HertzLaw>().shear_modulus = kG;
    def.law_def<HertzLaw>().poisson_ratio = kNu;
    def.domain_lo = Vec2(-10, -10);
    def.domain_hi = Vec2(10, 10);
    return def;
}

int sand(World& w, double friction = 0.3) {
    MaterialDef m;
    m.density = kRho;
    m.friction = friction;
    return w.add_material(m);
}

void floor_wall(World& w, double friction = 0.3) {
    WallDef f;
    f.p0 = Vec2(-5.0, 0.0);
    f.p1 = Vec2(5.0, 0.0);
    f.material = test::wall_material(w, friction);
    w.add_wall(f);
}

struct Impact {
    double max_overlap = 0.0, peak_force = 0.0, contact_time = 0.0, rebound = 0.0;
};

// A disc at v0 onto the floor (wall), or two discs closing at v0 (pair),
// at a fixed step of 1/steps of the contact time, until the contact has ended.
Impact impact(bool pair, double v0, double beta_n, int steps_per_contact) {
    const double m_eff = pair ? 0.5 * kMass : kMass;
    const double k = hertz_a() * std::sqrt(kR);  // R~ = 2 R R / (R + R) = R for the pair, R for the wall
    const double u_max = std::pow(5.0 * m_eff * v0 * v0 / (4.0 * k), 0.4);
    WorldDef def = hertz_world(beta_n);
    def.timestep.automatic = false;
    def.timestep.fixed = kHertzTime * u_max / v0 / steps_per_contact;
    def.rotation.model = 1;
    World w(def);
    const int m = sand(w);
    const double gap = 0.5 * v0 * def.timestep.fixed;  // touches within the first step
    if (pair) {
        w.add_disc({Vec2(0.0, 0.0), kR, Vec2(0.5 * v0, 0.0), 0, 0, m});
        w.add_disc({Vec2(2.0 * kR + gap, 0.0), kR, Vec2(-0.5 * v0, 0.0), 0, 0, m});
    } else {
        w.add_disc({Vec2(0.0, kR + gap), kR, Vec2(0.0, -v0), 0, 0, m});
        floor_wall(w);
    }
    w.finalize();
    Impact out;
    bool touched = false;
    double t_first = 0.0, t_last = 0.0;
    for (long s = 0; s < 40L * steps_per_contact; ++s) {
        w.step();
        const double overlap =
            pair ? 2.0 * kR - (w.positions()[1] - w.positions()[0]).norm() : kR - w.positions()[0].y();
        const double f = pair ? std::abs(w.force(1).x()) : std::abs(w.force(0).y());
        if (overlap > 0.0) {
            if (!touched) t_first = w.time() - w.dt();
            touched = true;
            t_last = w.time();
            out.max_overlap = std::max(out.max_overlap, overlap);
        }
        out.peak_force = std::max(out.peak_force, f);
        if (touched && overlap < 0.0) break;
    }
    out.contact_time = t_last - t_first;
    // the relative speed after, over the one before
    out.rebound = pair ? (w.velocities()[1].x() - w.velocities()[0].x()) / v0 : w.velocities()[0].y() / v0;
    return out;
}

// The same impact with its dashpot (mode 0: the force may pull at the end), integrated by
// RK4 at 200,000 steps per contact: x'' = -(K x^(3/2) + 2 beta sqrt(m 3/2 K sqrt x) x') / m.
double reference_restitution(bool pair, double v0, double beta_n) {
    const double m = pair ? 0.5 * kMass : kMass;
    const double k = hertz_a() * std::sqrt(kR);
    const double u_max = std::pow(5.0 * m * v0 * v0 / (4.0 * k), 0.4);
    const double h = kHertzTime * u_max / v0 / 200000.0;
    auto acc = [&](double x, double v) {
        if (x <= 0.0) return 0.0;
        return -(k * x * std::sqrt(x) + 2.0 * beta_n * std::sqrt(m * 1.5 * k * std::sqrt(x)) * v) / m;
    };
    double x = 0.0, v = v0;  // x: the overlap, v its rate
    for (long s = 0; s < 2000000; ++s) {
        const double k1x = v, k1v = acc(x, v);
        const double k2x = v + 0.5 * h * k1v, k2v = acc(x + 0.5 * h * k1x, v + 0.5 * h * k1v);
        const double k3x = v + 0.5 * h * k2v, k3v = acc(x + 0.5 * h * k2x, v + 0.5 * h * k2v);
        const double k4x = v + h * k3v, k4v = acc(x + h * k3x, v + h * k3v);
        x += h / 6.0 * (k1x + 2 * k2x + 2 * k3x + k4x);
        v += h / 6.0 * (k1v + 2 * k2v + 2 * k3v + k4v);
        if (x < 0.0 && s > 10) break;
    }
    return -v / v0;
}

}  // namespace

TEST(Hertz, NormalImpactMatchesHertzsClosedForms) {
    for (const bool pair : {false, true})
        for (const double v0 : {0.5, 3.0}) {
            const double m_eff = pair ? 0.5 * kMass : kMass;
            const double k = hertz_a() * std::sqrt(kR);
            const double u_max = std::pow(5.0 * m_eff * v0 * v0 / (4.0 * k), 0.4);
            const Impact im = impact(pair, v0, 0.0, 4000);
            SCOPED_TRACE(std::string(pair ? "disc on disc" : "disc on wall") + ", v0 = " + std::to_string(v0));
            EXPECT_NEAR(im.max_overlap / u_max, 1.0, 0.01);
            EXPECT_NEAR(im.peak_force / (k * std::pow(u_max, 1.5)), 1.0, 0.01);
            EXPECT_NEAR(im.contact_time / (kHertzTime * u_max / v0), 1.0, 0.01);
            EXPECT_NEAR(im.rebound, 1.0, 1e-3);  // no dashpot: elastic
        }
    // Hertz's contact time falls as v^(-1/5): six times the speed, 0.699 times the time
    const double t_slow = impact(false, 0.5, 0.0, 2000).contact_time, t_fast = impact(false, 3.0, 0.0, 2000).contact_time;
    EXPECT_NEAR(t_fast / t_slow, std::pow(6.0, -0.2), 0.005);
}

TEST(Hertz, RestitutionWithDashpotsMatchesTheEquationIntegratedFinely) {
    for (const bool pair : {false, true})
        for (const double beta : {0.2, 0.5}) {
            const Impact im = impact(pair, 1.0, beta, 4000);
            const double e = reference_restitution(pair, 1.0, beta);
            SCOPED_TRACE(std::string(pair ? "disc on disc" : "disc on wall") + ", beta " + std::to_string(beta));
            EXPECT_GT(e, 0.0);
            EXPECT_LT(e, 1.0);
            EXPECT_NEAR(im.rebound, e, 0.003 * e + 1e-4);
        }
}

// A disc sent along the floor with its rotation locked slides to rest in v^2 / (2 mu g)
// (no shear dashpot: on top of the slider, as PFC has it, it would hold the disc).
TEST(Hertz, SlidesToRestInTheCoulombDistance) {
    const double mu = 0.3, g = 9.81, v0 = 1.0;
    WorldDef def = hertz_world(0.5, 0.0, Vec2(0.0, -g));
    def.rotation.model = 1;
    World w(def);
    const int m = sand(w, mu);
    // at the overlap where the floor carries the weight, so that it does not bounce
    const double u = std::pow(kMass * g / (hertz_a() * std::sqrt(kR)), 2.0 / 3.0);
    w.add_disc({Vec2(0.0, kR - u), kR, Vec2(v0, 0.0), 0, 0, m});
    floor_wall(w, mu);
    w.finalize();
    while (w.time() < 0.8) w.step();
    const double x_stopped = w.positions()[0].x();
    while (w.time() < 1.0) w.step();
    // stuck: the shear spring rings (no shear dashpot) but the disc goes no further
    EXPECT_LT(std::abs(w.positions()[0].x() - x_stopped), 1e-6);
    EXPECT_NEAR(w.positions()[0].x() / (v0 * v0 / (2.0 * mu * g)), 1.0, 0.01);
}

// Undamped, frictionless discs in a box without gravity: the ledger's energy stays put over
// many impacts at the automatic step (which follows the contacts' stiffness, growing slowly).
TEST(Hertz, UndampedGasKeepsItsEnergy) {
    // (a step that grew back after each impact gained 14 % in 0.2 s at safety 0.8: the step
    // never grows, hertz_law.h)
    for (const auto& [safety, tolerance] : {std::pair{0.8, 0.02}, {0.2, 0.003}}) {
        WorldDef def = hertz_world();
        def.timestep.safety = safety;
        World w(def);
        const int m = sand(w, 0.0);
        for (int i = 0; i < 6; ++i)
            for (int j = 0; j < 6; ++j)
                w.add_disc({Vec2(0.015 * i + 0.002 * (j % 2), 0.015 * j), kR, Vec2(std::sin(3.0 * i + j), std::cos(5.0 * j + i)), 0, 0, m});
        for (const auto& [a, b] : {std::pair{Vec2(-0.01, -0.01), Vec2(0.09, -0.01)}, {Vec2(0.09, -0.01), Vec2(0.09, 0.09)},
                                   {Vec2(0.09, 0.09), Vec2(-0.01, 0.09)}, {Vec2(-0.01, 0.09), Vec2(-0.01, -0.01)}}) {
            WallDef wd;
            wd.p0 = a;
            wd.p1 = b;
            wd.material = test::wall_material(w, 0.0);
            w.add_wall(wd);
        }
        w.finalize();
        const double e0 = w.energy().balance();
        long touching_steps = 0;
        while (w.time() < 0.2) {
            w.step();
            touching_steps += w.touching_disc_pairs() + w.touching_wall_pairs() > 0 ? 1 : 0;
        }
        SCOPED_TRACE("safety " + std::to_string(safety));
        EXPECT_GT(touching_steps, 1000);
        EXPECT_NEAR(w.energy().balance() / e0, 1.0, tolerance);
        EXPECT_LT(w.dt(), def.law_def<HertzLaw>().dt_max);
    }
}

TEST(Hertz, KeysAreTheLawsAndRefusedWhereUnused) {
    Scenario s = load_scenario(std::string(DEMLAB_SOURCE_DIR) + "/scenarios/geometry-A.toml");
    apply_override(s, "contact.law=\"hertz\"");
    apply_override(s, "hertz.shear_modulus=1e9");
    EXPECT_EQ(s.world.law, law_kind<HertzLaw>());
    EXPECT_EQ(s.world.law_def<HertzLaw>().shear_modulus, 1e9);
    EXPECT_THROW(apply_override(s, "hertz.poisson_ratio=0.5"), InputError);
    apply_override(s, "material.kn=2e8");
    EXPECT_THROW(finish_scenario(s), InputError);
}

// geometry A at scale 20 with the Hertz law from its release to rest
TEST(Hertz, FlumeAtScale20RunsToRest) {
    Scenario s = load_scenario(std::string(DEMLAB_SOURCE_DIR) + "/scenarios/geometry-A.toml");
    apply_override(s, "release.scale=20");
    apply_override(s, "contact.law=\"hertz\"");
    apply_override(s, "hertz.shear_modulus=1e9");
    apply_override(s, "output.snapshot_interval=0");
    finish_scenario(s);
    const std::filesystem::path dir = demlab::test::temp_dir("hertz-flume");
    const RunSummary r = run_scenario(s, {dir.string(), false, {}});
    EXPECT_EQ(r.stop_reason, "rest");
    EXPECT_GT(r.runout_s, 1.5);
    EXPECT_LT(r.runout_s, 3.0);
    std::filesystem::remove_all(dir);
}
