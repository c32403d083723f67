// The AVX2 integration (integrate_avx2.cpp) against the scalar loop (World::integrate_discs):
// the same bits for every rotation model and rolling-resistance form, with the automatic step,
// walls, disc-disc contacts and a range whose last group of four is not full.
#include <gtest/gtest.h>

#include <bit>
#include <random>

#include "setups/db9k.h"
#include "helpers.h"
#include "dem/laws/pair_kernel.h"

using namespace demlab;
using namespace demlab::test;

namespace {
uint64_t bits(double x) { return std::bit_cast<uint64_t>(x); }

// 301 discs (not a multiple of 4) with random velocities and spins, falling onto a 20-degree
// floor between two side walls: they touch the walls (rolling resistance) and each other
// (Model 3's damping), spinning both ways.
std::unique_ptr<World> pile(int model, RollingForm form, bool simd, bool avx512 = false, double local_alpha = 0.0) {
    WorldDef def;
    def.threads = 2;
    def.simd = simd;
    def.avx512 = avx512;
    def.rotation.model = model;
    def.rotation.u_rr = 0.0002;
    def.rotation.rolling_form = form;
    def.timestep.automatic = true;
    def.damping.beta_n = 0.3;
    def.damping.beta_s = 0.1;
    def.damping.local_alpha = local_alpha;
    auto w = std::make_unique<World>(def);
    const int m = w->add_material(material(0.5, 2e7));
    std::mt19937_64 rng(17);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (int d = 0; d < 301; ++d) {
        const double r = 0.002 + 0.001 * u(rng);
        const Vec2 p(0.01 + 0.0065 * (d % 20), 0.065 + 0.0065 * (d / 20));
        const double vy = u(rng) - 1.0;  // (y drawn first: the draws once left to the order of a call's arguments, GCC's)
        w->add_disc({p, r, Vec2(u(rng) - 0.5, vy), 0, 200.0 * (u(rng) - 0.5), m});
    }
    w->add_wall(segment(*w, Vec2(0.0, 0.05), Vec2(0.14, 0.0), 0.4, SegmentSolid::Right));
    w->add_wall(segment(*w, Vec2(0.0, 0.3), Vec2(0.0, 0.0), 0.4, SegmentSolid::Right));
    w->add_wall(segment(*w, Vec2(0.14, 0.0), Vec2(0.14, 0.3), 0.4, SegmentSolid::Right));
    w->finalize();
    return w;
}
}  // namespace

// The scalar loop, the AVX2 loop (four discs at a time) and, where the CPU has it, the
// AVX-512 loop (eight): the same bits for every rotation rule, without and with local damping
// (the release's settling; 301 discs: the ranges end in partial groups).
TEST(IntegrateKernel, Avx2AndScalarGiveTheSameBitsForEveryRotationRule) {
    if (!cpu_has_avx2()) GTEST_SKIP() << "this CPU has no AVX2";
    for (double alpha : {0.0, 0.7})
    for (int model : {1, 2, 3})
        for (RollingForm form : {RollingForm::Literal, RollingForm::NormalForce}) {
            if (model == 1 && form == RollingForm::NormalForce) continue;
            auto simd = pile(model, form, true, false, alpha), scalar = pile(model, form, false, false, alpha);
            std::unique_ptr<World> wide = cpu_has_avx512() ? pile(model, form, true, true, alpha) : nullptr;
            ASSERT_FALSE(simd->avx512_kernel());
            if (wide) {
                ASSERT_TRUE(wide->avx512_kernel());
            }
            for (int round = 0; round < 4; ++round) {
                for (World* w : {simd.get(), scalar.get(), wide.get()})
                    if (w) w->run(1500);
                for (World* w : {simd.get(), wide.get()}) {
                    if (!w) continue;
                    const char* which = w == wide.get() ? "AVX-512" : "AVX2";
                    ASSERT_EQ(state_hash(*w), state_hash(*scalar)) << which << " model " << model << " round " << round;
                    ASSERT_EQ(bits(w->dt()), bits(scalar->dt())) << which;
                    const EnergyReport a = w->energy(), b = scalar->energy();
                    ASSERT_EQ(bits(a.dissipated_rotation), bits(b.dissipated_rotation)) << which;
                    ASSERT_EQ(bits(a.dissipated_local), bits(b.dissipated_local)) << which << " alpha " << alpha;
                    ASSERT_EQ(bits(a.dissipated_contacts), bits(b.dissipated_contacts)) << which;
                    ASSERT_EQ(bits(w->kinetic_energy()), bits(scalar->kinetic_energy())) << which;
                    ASSERT_EQ(w->touching_disc_pairs(), scalar->touching_disc_pairs()) << which;
                }
            }
            // the case covers what it is meant to: contacts with walls and discs, spin taken out
            // (local damping takes 70 % of gravity's pull off a falling disc: fewer have landed)
            EXPECT_GT(simd->touching_disc_pairs(), alpha > 0.0 ? 5 : 100);
            if (model >= 2) {
                EXPECT_GT(simd->energy().dissipated_rotation, 0.0) << "model " << model;
            }
            if (alpha > 0.0) {
                EXPECT_GT(simd->energy().dissipated_local, 0.0) << "model " << model;
            }
        }
}

// World::kinetic_energy, summed by the integration per block of discs: the direct sum to
// rounding, with and without the rotation term, and the same bits on 1 and 3 threads (the
// ranges are cut at other discs then).
TEST(IntegrateKernel, KineticEnergyIsTheDirectSumForAnyThreadCount) {
    const auto discs = read_xyr(default_db9k_path());
    for (bool locked : {false, true}) {
        double ke[2] = {0, 0};
        for (int k = 0; k < 2; ++k) {
            WorldDef def = db9k_world_def();
            def.threads = k == 0 ? 1 : 3;
            if (locked) def.rotation.model = 1;
            World w(def);
            build_db9k(w, discs);
            w.finalize();
            EXPECT_EQ(w.kinetic_energy(), 0.0);
            w.run(1200);
            ke[k] = w.kinetic_energy();
            double direct = 0.0, rotation = 0.0;
            for (size_t i = 0; i < w.disc_count(); ++i) {
                direct += 0.5 * w.masses()[i] * w.velocities()[i].squaredNorm();
                rotation += 0.25 * w.masses()[i] * w.radii()[i] * w.radii()[i] * w.omegas()[i] * w.omegas()[i];
            }
            if (!locked) {
                EXPECT_GT(rotation, 1e-6 * direct);  // the discs spin: the term is there
                direct += rotation;
            }
            EXPECT_GT(direct, 0.0);
            EXPECT_NEAR(ke[k], direct, 1e-12 * direct) << (locked ? "locked" : "free") << ", threads " << def.threads;
        }
        EXPECT_EQ(bits(ke[0]), bits(ke[1]));
    }
}
