// The dashpots at the step's centre (timestep.dashpots = "centred", centred_dashpots.cpp):
// restitution against the closed form (eq. 2.56-2.62) at fine steps and at PFC's step,
// second-order convergence, and stability at PFC's rule as printed where the lagged
// dashpots blow up.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <random>
#include <utility>

#include "dem/centre_lanes.h"
#include "dem/laws/pair_kernel.h"

#include "dashpot_stability.h"
#include "helpers.h"

using namespace demlab;
using namespace demlab::test;

namespace {

constexpr double kRho = 2672.0, kK = 1e8;

WorldDef impact_def(double beta, DashpotScheme scheme) {
    WorldDef def;
    def.gravity = Vec2::Zero();
    def.damping.beta_n = beta;
    def.damping.beta_s = beta;
    def.rotation.model = 2;
    def.rotation.u_rr = 0.0;
    def.timestep.dashpots = scheme;
    def.timestep.damping_correction = false;
    return def;
}

// A disc hits a wall head-on at 1 m/s; the rebound speed over the impact speed. steps_per_contact
// > 0: a fixed step of that fraction of the contact's duration pi sqrt(m / k); 0: PFC's rule.
double wall_restitution(double beta, DashpotScheme scheme, double steps_per_contact) {
    World w(impact_def(beta, scheme));
    const int m = w.add_material(material(0.3, kK, kRho));
    const double r = 0.0015;
    w.add_disc({Vec2(0.0, r + 1e-6), r, Vec2(0.0, -1.0), 0.0, 0.0, m});
    w.add_wall(segment(w, Vec2(-0.1, 0.0), Vec2(0.1, 0.0)));
    const double mass = kRho * kPi * r * r;
    const double k = 0.5 * kK;  // disc and wall in series
    if (steps_per_contact > 0) w.set_dt(kPi * std::sqrt(mass / k) / steps_per_contact);
    w.finalize();
    bool touched = false;
    for (int s = 0; s < 200000; ++s) {
        w.step();
        if (w.touching_wall_pairs() > 0) touched = true;
        if (touched && w.touching_wall_pairs() == 0) break;
    }
    EXPECT_TRUE(touched);
    return w.velocities()[0].y();
}

// Two discs of radii 1 and 2 mm meet at 1 m/s each; the relative rebound ratio.
double disc_restitution(double beta, DashpotScheme scheme, double steps_per_contact) {
    World w(impact_def(beta, scheme));
    const int m = w.add_material(material(0.3, kK, kRho));
    const double r1 = 0.001, r2 = 0.002;
    w.add_disc({Vec2(-r1 - 1e-6, 0.0), r1, Vec2(1.0, 0.0), 0.0, 0.0, m});
    w.add_disc({Vec2(r2 + 1e-6, 0.0), r2, Vec2(-1.0, 0.0), 0.0, 0.0, m});
    const double m1 = kRho * kPi * r1 * r1, m2 = kRho * kPi * r2 * r2;
    if (steps_per_contact > 0) w.set_dt(kPi * std::sqrt(effective_mass(m1, m2) / (0.5 * kK)) / steps_per_contact);
    w.finalize();
    bool touched = false;
    for (int s = 0; s < 200000; ++s) {
        w.step();
        if (w.touching_disc_pairs() > 0) touched = true;
        if (touched && w.touching_disc_pairs() == 0) break;
    }
    EXPECT_TRUE(touched);
    return (w.velocities()[1].x() - w.velocities()[0].x()) / 2.0;
}

}  // namespace

class CentredRestitution : public ::testing::TestWithParam<double> {};

// The limit is the closed form: at 4,000 steps per contact both impacts give it within 1e-4
// of the impact speed, and within a fifth of their error at 62.5 steps per contact. (The
// error falls in steps, not as a power of dt: a contact starts and ends between steps, and
// that first-order error of the contact's duration outweighs the scheme's second-order one.)
TEST_P(CentredRestitution, TendsToTheClosedForm) {
    const double beta = GetParam();
    const double e = restitution(beta);
    for (auto* impact : {&wall_restitution, &disc_restitution}) {
        const double coarse = std::abs(impact(beta, DashpotScheme::Centred, 62.5) - e);
        const double fine = std::abs(impact(beta, DashpotScheme::Centred, 4000) - e);
        EXPECT_LT(fine, 1e-4) << "beta " << beta;
        EXPECT_LT(fine, 0.2 * coarse) << "beta " << beta;
    }
}

INSTANTIATE_TEST_SUITE_P(Betas, CentredRestitution, ::testing::Values(0.2, 0.5, 0.85));

// The restitution at PFC's step (a lone disc's rule: 0.8 sqrt(m / k_own), about 6 steps per
// contact) beside the closed form and the lagged scheme's, as docs/engine.md states them.
TEST(CentredRestitution, AtPfcStepStaysNearTheClosedForm) {
    std::printf("beta  closed   centred(wall disc)  lagged(wall disc)\n");
    for (double beta : {0.2, 0.5, 0.85}) {
        const double e = restitution(beta);
        const double cw = wall_restitution(beta, DashpotScheme::Centred, 0);
        const double cd = disc_restitution(beta, DashpotScheme::Centred, 0);
        const double lw = wall_restitution(beta, DashpotScheme::Lagged, 0);
        const double ld = disc_restitution(beta, DashpotScheme::Lagged, 0);
        std::printf("%.2f  %.4f   %.4f %.4f       %.4f %.4f\n", beta, e, cw, cd, lw, ld);
        // a rebound, never more than the impact, within 0.06 of the closed form
        for (double c : {cw, cd}) {
            EXPECT_GE(c, 0.0);
            EXPECT_LT(c, 1.0);
            EXPECT_NEAR(c, e, 0.06) << "beta " << beta;
        }
    }
}

// The pressed pair with free rotation, 1e6 steps at PFC's rule as printed: the centred
// dashpots never let its energy grow nor its dissipation go back (the spin ends as a
// rolling of the pair along the walls, which nothing resists); the lagged ones blow up.
TEST(CentredDashpots, PressedPairWithFreeRotationIsStableAtPfcRule) {
    const DashpotWatch centred = pressed_pair(DashpotScheme::Centred, 1000000);
    EXPECT_FALSE(centred.threw);
    EXPECT_LE(centred.energy_rise, 1e-12 * centred.energy_start);
    EXPECT_LE(centred.dissipation_drop, 1e-12 * centred.energy_start);
    const DashpotWatch lagged = pressed_pair(DashpotScheme::Lagged, 1000000);
    EXPECT_TRUE(lagged.threw || lagged.energy_rise > 1e-6 * lagged.energy_start);
}

// The pack of 2,000-odd discs settling for 50,000 steps (0.9 s) at PFC's rule as printed; the slow validation run
// (tests/slow_dashpots.cpp) takes it to 1e6 steps.
TEST(CentredDashpots, SettlingPackIsStableAtPfcRule) {
    DEMLAB_RELEASE_PASS_ONLY("every flume run (centred dashpots, the default)");
    const DashpotWatch pack = settling_pack(DashpotScheme::Centred, 50000);
    ASSERT_GE(pack.discs, 2000);
    EXPECT_FALSE(pack.threw);
    EXPECT_LE(pack.energy_rise, 1e-9 * std::abs(pack.energy_start));
    EXPECT_LE(pack.dissipation_drop, 1e-9 * std::abs(pack.energy_start));
    // the lagged dashpots at the same rule blow up within the first 5,000 steps
    const DashpotWatch lagged = settling_pack(DashpotScheme::Lagged, 50000);
    EXPECT_TRUE(lagged.threw || lagged.energy_rise > 1e-9 * std::abs(lagged.energy_start));
}

// The centred pass' lanes (centre_lanes.h) give the same bits in every width this CPU runs, on
// a block whose count is not a multiple of any width, with sliding and tension-capped pairs, and
// lane 0 is the header's formula.
TEST(CentreLanes, EveryWidthGivesTheBaselineBits) {
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    CentreBlock in;
    in.count = 61;
    for (size_t l = 0; l < in.count; ++l) {
        in.ri[l] = 1e-3 * (1.5 + u(rng));
        in.rj[l] = 1e-3 * (1.5 + u(rng));
        const double dist = (in.ri[l] + in.rj[l]) * (1.0 - 0.01 * (1.0 + u(rng)));
        const double a = 3.14159 * u(rng);
        in.dx[l] = dist * std::cos(a);
        in.dy[l] = dist * std::sin(a);
        in.dist2[l] = in.dx[l] * in.dx[l] + in.dy[l] * in.dy[l];
        in.vrx[l] = u(rng);
        in.vry[l] = u(rng);
        in.wi[l] = 100.0 * u(rng);
        in.wj[l] = 100.0 * u(rng);
        in.prx[l] = u(rng);
        in.pry[l] = u(rng);
        in.pwi[l] = 100.0 * u(rng);
        in.pwj[l] = 100.0 * u(rng);
        in.inv_mn[l] = 2.0 / (1e-2 * (1.5 + u(rng)));
        in.inv_ii[l] = 1.0 / (1e-8 * (1.5 + u(rng)));
        in.inv_ij[l] = 1.0 / (1e-8 * (1.5 + u(rng)));
        in.cn[l] = 600.0 * (1.5 + u(rng));  // g = c dt / m of 0.1-1, as at PFC's step
        in.cs[l] = 600.0 * (1.5 + u(rng));
        in.kn[l] = 1e8;
        in.mu[l] = 0.28;
        // a third of the pairs slide: |F_s| = mu F_n
        const double fn = in.kn[l] * (in.ri[l] + in.rj[l] - dist);
        in.fs[l] = l % 3 == 0 ? in.mu[l] * fn : 0.5 * in.mu[l] * fn * u(rng);
    }
    struct Width {
        const char* name;
        bool avx2, avx512;
    };
    std::vector<Width> widths{{"baseline", false, false}};
    if (cpu_has_avx2()) widths.push_back({"AVX2", true, false});
    if (cpu_has_avx512()) widths.push_back({"AVX-512", true, true});
    for (const bool rotation_free : {false, true})
        for (const int mode : {0, 1, 2, 3}) {
            const CentreConsts k{2e-6, 1e-6, rotation_free, mode == 1 || mode == 3, mode == 2 || mode == 3};
            CentreBlock ref = in;
            centre_block(ref, k, false, false);
            for (const Width& w : widths) {
                SCOPED_TRACE(std::string(w.name) + " mode " + std::to_string(mode) + (rotation_free ? " free" : " locked"));
                CentreBlock b = in;
                centre_block(b, k, w.avx2, w.avx512);
                for (size_t l = 0; l < in.count; ++l) {
                    ASSERT_EQ(std::memcmp(&b.fx[l], &ref.fx[l], 8), 0) << l;
                    ASSERT_EQ(std::memcmp(&b.fy[l], &ref.fy[l], 8), 0) << l;
                    ASSERT_EQ(std::memcmp(&b.torque_i[l], &ref.torque_i[l], 8), 0) << l;
                    ASSERT_EQ(std::memcmp(&b.torque_j[l], &ref.torque_j[l], 8), 0) << l;
                    ASSERT_EQ(std::memcmp(&b.dissipated[l], &ref.dissipated[l], 8), 0) << l;
                    ASSERT_EQ(std::memcmp(&b.damp_n[l], &ref.damp_n[l], 8), 0) << l;
                    ASSERT_EQ(std::memcmp(&b.damp_s[l], &ref.damp_s[l], 8), 0) << l;
                }
            }
            // lane 0 against the formula: u(t) = (u* + (g/2) u-) / (1 + g/2) along the normal
            const double dist = std::sqrt(in.dist2[0]);
            const double nx = in.dx[0] / dist, ny = in.dy[0] / dist;
            const double vn = in.vrx[0] * nx + in.vry[0] * ny, pn = in.prx[0] * nx + in.pry[0] * ny;
            const double gn = in.cn[0] * k.dt * in.inv_mn[0];
            double d_new = -in.cn[0] * (pn + 0.5 * gn * vn) / (1.0 + 0.5 * gn);
            double d_old = -in.cn[0] * vn;
            if (k.no_tension) {
                const double fn = in.kn[0] * (in.ri[0] + in.rj[0] - dist);
                d_new = std::max(d_new, -fn);
                d_old = std::max(d_old, -fn);
            }
            EXPECT_NEAR(ref.damp_n[0], d_new, 1e-12 * std::abs(d_new));
            // the shift's normal component is d_new - d_old (lane 0 slides: no shear shift in modes 2, 3)
            if (k.no_shear_sliding) {
                EXPECT_NEAR(ref.fx[0] * nx + ref.fy[0] * ny, d_new - d_old, 1e-9 * std::abs(d_new - d_old) + 1e-15);
            }
        }
}

// The wide gather (centre_wide.h) against the scalar gather into a block and the baseline
// lanes: discs with random states, two materials, 61 listed pairs (not a multiple of any
// width), every dashpot mode with rotation free and locked; the same bits in every output,
// and a listed pair that does not touch refused (the caller then gathers one by one).
TEST(CentreLanes, WideGatherGivesTheScalarGathersBits) {
    const bool avx2 = cpu_has_avx2(), avx512 = cpu_has_avx512();
    if (!avx2) GTEST_SKIP() << "this CPU has no AVX2";
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const size_t n_discs = 40;
    std::vector<Vec2> pos(n_discs);
    std::vector<double> radius(n_discs);
    std::vector<int32_t> material(n_discs);
    struct alignas(64) Row {
        double v[8];
    };
    std::vector<Row> discs(n_discs);
    for (size_t d = 0; d < n_discs; ++d) {
        const double y = 0.01 * u(rng);  // (y drawn first: the draws once left to the order of a call's arguments, GCC's)
        pos[d] = Vec2(0.01 * u(rng), y);
        radius[d] = 1e-3 * (1.5 + 0.5 * u(rng));
        material[d] = int32_t(d % 2);
        discs[d] = Row{{u(rng), u(rng), 100.0 * u(rng), u(rng), u(rng), 100.0 * u(rng), 1.0 / (1e-2 * (1.5 + u(rng))),
                        1.0 / (1e-8 * (1.5 + u(rng)))}};
    }
    const std::vector<PairMaterial> materials{LinearLaw::params(1e8, 5e7, 0.28), LinearLaw::params(8e7, 4e7, 0.36),
                                              LinearLaw::params(8e7, 4e7, 0.36), LinearLaw::params(6e7, 3e7, 0.5)};
    // pairs placed touching: j moved to a random direction at 0.98-0.999 of the radii' sum
    std::vector<DiscContact> contacts;
    std::vector<uint32_t> list;
    for (size_t k = 0; k < 61; ++k) {
        const int32_t i = int32_t(k % (n_discs - 1)), j = int32_t(i + 1 + int32_t(k % 3 == 0 && i + 2 < int32_t(n_discs)));
        const double a = 3.14159 * u(rng), dist = (radius[size_t(i)] + radius[size_t(j)]) * (0.9895 + 0.0095 * u(rng));
        pos[size_t(j)] = pos[size_t(i)] + dist * Vec2(std::cos(a), std::sin(a));
        // dashpots of beta about 0.3 at these masses and stiffnesses: g = c dt / m of 0.1-1, as
        // in a flow at PFC's step (smaller g would hide its rounding under the 1 of 1 + g/2)
        DiscContact c{i, j, 0.0, 600.0 * (1.5 + u(rng)), 600.0 * (1.5 + u(rng)), 0.0f, 0.0f};
        contacts.push_back(c);
        list.push_back(uint32_t(k));
    }
    // the positions moved as the list grew: keep the pairs that still touch, and give a third
    // of them a sliding shear force (|F_s| = mu F_n)
    std::vector<uint32_t> touching;
    for (const uint32_t k : list) {
        DiscContact& c = contacts[k];
        const size_t i = size_t(c.i), j = size_t(c.j);
        const double dist = (pos[j] - pos[i]).norm(), rsum = radius[i] + radius[j];
        if (dist >= rsum) continue;
        const PairMaterial& pm = materials[size_t(material[i]) * 2 + size_t(material[j])];
        const double fn = pm.kn * (rsum - dist);
        c.fs = touching.size() % 3 == 0 ? -pm.mu * fn : 0.5 * pm.mu * fn * u(rng);
        touching.push_back(k);
    }
    ASSERT_GT(touching.size(), 20u);
    ASSERT_NE(touching.size() % 8, 0u);
    CentrePairArrays arrays{pos.data()->data(), radius.data(), material.data(), materials.data(), 2, contacts.data(),
                            discs.data()->v};
    for (const bool rotation_free : {false, true})
        for (const int mode : {0, 1, 2, 3}) {
            SCOPED_TRACE("mode " + std::to_string(mode) + (rotation_free ? " free" : " locked"));
            const CentreConsts k{2e-6, 1e-6, rotation_free, mode == 1 || mode == 3, mode == 2 || mode == 3};
            // the scalar gather (centred_dashpots.cpp's), then the baseline lanes
            auto ref = std::make_unique<CentreBlock>();
            for (const uint32_t e : touching) {
                const DiscContact& c = contacts[e];
                const size_t i = size_t(c.i), j = size_t(c.j), l = ref->count++;
                const Vec2 dx = pos[j] - pos[i];
                const double* ci = discs[i].v;
                const double* cj = discs[j].v;
                const PairMaterial& pm = materials[size_t(material[i]) * 2 + size_t(material[j])];
                ref->dx[l] = dx.x();
                ref->dy[l] = dx.y();
                ref->dist2[l] = dx.squaredNorm();
                ref->ri[l] = radius[i];
                ref->rj[l] = radius[j];
                ref->vrx[l] = cj[0] - ci[0];
                ref->vry[l] = cj[1] - ci[1];
                ref->wi[l] = ci[2];
                ref->wj[l] = cj[2];
                ref->prx[l] = cj[3] - ci[3];
                ref->pry[l] = cj[4] - ci[4];
                ref->pwi[l] = ci[5];
                ref->pwj[l] = cj[5];
                ref->inv_mn[l] = ci[6] + cj[6];
                ref->inv_ii[l] = ci[7];
                ref->inv_ij[l] = cj[7];
                ref->cn[l] = c.cn;
                ref->cs[l] = c.cs;
                ref->kn[l] = pm.kn;
                ref->mu[l] = pm.mu;
                ref->fs[l] = c.fs;
            }
            centre_block(*ref, k, false, false);
            for (const auto& [eight, prefetch] : {std::pair{false, false}, std::pair{false, true}, std::pair{true, false},
                                                 std::pair{true, true}}) {  // asking ahead changes nothing
                if (eight && !avx512) continue;
                SCOPED_TRACE(eight ? "AVX-512" : "AVX2");
                SCOPED_TRACE(prefetch ? "prefetch" : "no prefetch");
                arrays.prefetch = prefetch;
                auto b = std::make_unique<CentreBlock>();
                const bool done = eight ? centre_touching_avx512(arrays, touching.data(), touching.size(), *b, k)
                                        : centre_touching_avx2(arrays, touching.data(), touching.size(), *b, k);
                ASSERT_TRUE(done);
                ASSERT_EQ(b->count, touching.size());
                for (size_t l = 0; l < b->count; ++l) {
                    ASSERT_EQ(b->contact[l], touching[l]);
                    ASSERT_EQ(b->i[l], contacts[touching[l]].i);
                    ASSERT_EQ(b->j[l], contacts[touching[l]].j);
                    for (const auto field : {&CentreBlock::fx, &CentreBlock::fy, &CentreBlock::torque_i, &CentreBlock::torque_j,
                                             &CentreBlock::dissipated, &CentreBlock::damp_n, &CentreBlock::damp_s})
                        ASSERT_EQ(std::memcmp(&((*b).*field)[l], &((*ref).*field)[l], 8), 0) << l;
                }
                // a pair that does not touch, listed
                const uint32_t open = uint32_t(contacts.size());
                std::vector<DiscContact> more = contacts;
                more.push_back(DiscContact{0, 1, 0.0, 1.0, 1.0, 0.0f, 0.0f});
                std::vector<Vec2> apart = pos;
                apart[1] = apart[0] + Vec2(1.0, 0.0);
                CentrePairArrays far = arrays;
                far.contacts = more.data();
                far.pos = apart.data()->data();
                const uint32_t one[1] = {open};
                EXPECT_FALSE(eight ? centre_touching_avx512(far, one, 1, *b, k) : centre_touching_avx2(far, one, 1, *b, k));
                EXPECT_EQ(b->count, 0u);
            }
            // the sliding pairs lose their shear dashpot in modes 2 and 3 only: the mode was exercised
            size_t no_shear = 0;
            for (size_t l = 0; l < ref->count; ++l) no_shear += ref->damp_s[l] == 0.0;
            if (k.no_shear_sliding) EXPECT_GE(no_shear, ref->count / 3);
            else EXPECT_EQ(no_shear, 0u);
        }
}

// A world whose discs are all gone (lost, or none added) still steps with the centred dashpots
// on every width: the wide gather's arrays are formed from empty vectors without touching them.
TEST(CentredDashpots, AWorldWithoutDiscsSteps) {
    for (const bool simd : {false, true}) {
        WorldDef def;
        def.simd = simd;
        def.timestep.automatic = false;
        def.timestep.fixed = 1e-6;
        World w(def);
        w.add_material(material(0.5, 2e7));
        w.add_wall(segment(w, Vec2(0.0, 0.0), Vec2(1.0, 0.0), 0.4, SegmentSolid::Right));
        w.finalize();
        for (int k = 0; k < 10; ++k) w.step();
        EXPECT_NEAR(w.time(), 1e-5, 1e-18);
    }
}
