// The SIMD pair kernels (pair_kernel_avx2.cpp, and pair_kernel_avx512.cpp where the CPU has
// AVX-512) against the scalar one (pair_kernel.h): the same bits for every field, every dashpot
// mode, open and touching pairs, sliding and sticking, tension cut or not, the pairs with nothing
// to do left out; and a blown-up pair left to the scalar kernel.
#include <gtest/gtest.h>

#include <bit>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <sys/wait.h>

#include "setups/db9k.h"
#include "core/jitter.h"
#include "dem/laws/pair_kernel.h"
#include "dem/world.h"

using namespace demlab;

namespace {

uint64_t bits(double x) { return std::bit_cast<uint64_t>(x); }
uint32_t bits(float x) { return std::bit_cast<uint32_t>(x); }

// Discs on a jittered grid, so that a neighbour pair is open, touching or deep in contact, with
// random velocities and spins; the pairs' histories random (some zero, some beyond the
// Coulomb cap, so that both slide and stick), two materials.
struct KernelCase {
    std::vector<Vec2> pos, vel;
    std::vector<double> radius, omega;
    std::vector<int32_t> material;
    std::vector<PairMaterial> materials;
    std::vector<DiscContact> contacts;

    explicit KernelCase(unsigned seed, size_t n_discs = 900) {  // and 40 more at rest
        std::mt19937_64 rng(seed);
        std::uniform_real_distribution<double> u(0.0, 1.0);
        const size_t side = 30;
        for (size_t d = 0; d < n_discs; ++d) {
            const double r = 0.001 + 0.0005 * u(rng);
            // (y drawn first: the draws once left to the order of a call's arguments, GCC's)
            const double y = 0.0024 * double(d / side) + 0.0006 * u(rng);
            pos.emplace_back(0.0024 * double(d % side) + 0.0006 * u(rng), y);
            radius.push_back(r);
            const double vy = 6.0 * u(rng) - 3.0;
            vel.emplace_back(6.0 * u(rng) - 3.0, vy);
            omega.push_back(400.0 * u(rng) - 200.0);
            material.push_back(int32_t(d % 3 == 0));
        }
        // A row of discs at rest, touching, frictionless between them (material 1 with 1):
        // their pairs' trial shear force is exactly +0 or -0 and the Coulomb cap 0, where
        // max(-0, +0) and max(+0, -0) differ (std::max's operand order is then what makes the
        // bits; a kernel with the operands swapped fails here).
        const size_t rest_first = n_discs;
        for (size_t d = 0; d < 40; ++d) {
            pos.emplace_back(0.0024 * double(d), -0.01);
            radius.push_back(0.00121);
            vel.emplace_back(0.0, 0.0);
            omega.push_back(0.0);
            material.push_back(1);
        }
        n_discs += 40;
        auto pm = [](double kn, double ks, double mu) { return PairMaterial{kn, ks, mu, std::max(kn, ks), 1.0 / ks}; };
        materials = {pm(1e8, 1e8, 0.3), pm(2e8, 0.7e8, 0.5), pm(2e8, 0.7e8, 0.5), pm(3e8, 2e8, 0.0)};
        for (size_t a = 0; a < n_discs; ++a)
            for (size_t b = a + 1; b < n_discs; ++b) {
                const double dist = (pos[b] - pos[a]).norm(), rsum = radius[a] + radius[b];
                // neighbours only, none blown up (the next test covers that)
                if (dist > 1.4 * rsum || rsum - dist > 0.45 * std::min(radius[a], radius[b])) continue;
                DiscContact c{int32_t(a), int32_t(b), 0.0, 0.0, 0.0, 0.0f, 0.0f};
                if (u(rng) < 0.7) {
                    c.fs = (u(rng) - 0.5) * 2.0e4;
                    c.damp_n = float((u(rng) - 0.5) * 2000.0);
                    c.damp_s = u(rng) < 0.5 ? 0.0f : float((u(rng) - 0.5) * 2000.0);
                } else if (u(rng) < 0.2) {
                    c.fs = -0.0;  // a history of signed zeros: not nothing (the kernel must write +0)
                    if (u(rng) < 0.5) c.damp_s = -0.0f;
                }
                // dashpots of the size DB-9k's have (beta 2 sqrt(m k) ~ 1000 N s/m)
                c.cn = 2000.0 * u(rng);
                c.cs = u(rng) < 0.3 ? 0.0 : 1000.0 * u(rng);
                if (a >= rest_first) {  // the row at rest: a history of signed zeros
                    c.fs = (a % 2 == 0) ? 0.0 : -0.0;
                    c.damp_n = c.damp_s = 0.0f;
                }
                contacts.push_back(c);
            }
    }
    DiscArrays arrays() const { return {pos.data(), vel.data(), radius.data(), omega.data(), material.data()}; }
    PairPassParams params(DashpotMode mode) const { return {materials.data(), 2, mode, 3.1e-6, 2.9e-6, 0.5}; }
};

// Result slot of each contact of a batch (-1: left out), checking the results are in list order.
std::vector<int> batch_slots(const PairBatch& batch, size_t done) {
    std::vector<int> slot(done, -1);
    EXPECT_LE(batch.count, done);
    for (size_t b = 0; b < batch.count && b < done; ++b) {
        EXPECT_LT(batch.index[b], done);
        if (b > 0) {
            EXPECT_GT(batch.index[b], batch.index[b - 1]);
        }
        if (batch.index[b] < done) slot[batch.index[b]] = int(b);
    }
    return slot;
}

// The SIMD kernels this CPU runs: the AVX2 one, and the AVX-512 one where it has AVX-512.
struct SimdKernel {
    const char* name;
    size_t group;  // pairs per group of the law
    size_t (*run)(const DiscArrays&, const PairPassParams&, DiscContact*, size_t, PairBatch&, const PairSkip*);
};
std::vector<SimdKernel> simd_kernels() {
    std::vector<SimdKernel> k;
    if (cpu_has_avx2()) k.push_back({"AVX2", 4, disc_pairs_avx2});
    if (cpu_has_avx512()) k.push_back({"AVX-512", 8, disc_pairs_avx512});
    return k;
}

// The SIMD pass' history of a pair against the scalar kernel's, bit for bit.
::testing::AssertionResult same_history(const DiscContact& simd, const DiscContact& scalar) {
    if (bits(simd.fs) != bits(scalar.fs) || bits(simd.damp_n) != bits(scalar.damp_n) ||
        bits(simd.damp_s) != bits(scalar.damp_s))
        return ::testing::AssertionFailure() << "history (" << simd.fs << ", " << simd.damp_n << ", " << simd.damp_s
                                             << ") against the scalar kernel's (" << scalar.fs << ", " << scalar.damp_n
                                             << ", " << scalar.damp_s << ")";
    return ::testing::AssertionSuccess();
}

}  // namespace

TEST(PairKernel, SimdKernelsGiveTheScalarKernelsBits) {
    if (simd_kernels().empty()) GTEST_SKIP() << "this CPU has no AVX2";
    for (const SimdKernel& kern : simd_kernels())
    for (DashpotMode mode : {DashpotMode::Full, DashpotMode::NoTension, DashpotMode::NoShearWhileSliding,
                             DashpotMode::NoTensionNoShearWhileSliding}) {
        SCOPED_TRACE(kern.name);
        const KernelCase k(11 + unsigned(mode));
        const DiscArrays d = k.arrays();
        const PairPassParams p = k.params(mode);
        std::vector<DiscContact> scalar = k.contacts, simd = k.contacts;
        size_t touching = 0, open_with_dashpots = 0, sliding = 0, tension_cut = 0, checked = 0, left_out = 0,
               signed_zero_history = 0;
        PairBatch batch;
        for (size_t k0 = 0; k0 < simd.size(); k0 += PairBatch::kSize) {
            const size_t n = std::min(PairBatch::kSize, simd.size() - k0);
            const size_t done = kern.run(d, p, &simd[k0], n, batch, nullptr);
            ASSERT_EQ(done, n - n % 4);  // no blown-up pair in this case
            const std::vector<int> slot = batch_slots(batch, done);
            for (size_t a = 0; a < done; ++a) {
                DiscContact& c = scalar[k0 + a];
                const DiscContact before = c;
                PairOut o{};
                double overlap = 0.0;
                ASSERT_TRUE(disc_pair_force(d, p, c, o, overlap));
                ASSERT_TRUE(same_history(simd[k0 + a], c)) << "pair " << k0 + a;
                ++checked;
                if (bits(before.fs) == bits(-0.0) || bits(before.damp_s) == bits(-0.0f)) ++signed_zero_history;
                if (slot[a] < 0) {
                    // left out: open, with nothing to end, so the scalar kernel adds +0 and
                    // writes back the zeros it read
                    ASSERT_FALSE(o.touching) << "pair " << k0 + a;
                    ASSERT_EQ(bits(o.dissipated), bits(0.0)) << "pair " << k0 + a;
                    ASSERT_EQ(bits(before.fs), bits(0.0)) << "pair " << k0 + a;
                    ASSERT_EQ(bits(before.damp_n), bits(0.0f)) << "pair " << k0 + a;
                    ASSERT_EQ(bits(before.damp_s), bits(0.0f)) << "pair " << k0 + a;
                    ++left_out;
                    continue;
                }
                const size_t b = size_t(slot[a]);
                ASSERT_EQ(bits(batch.half_dissipated(b)), bits(0.5 * o.dissipated)) << "pair " << k0 + a;
                ASSERT_EQ(batch.touching[b], int32_t(o.touching)) << "pair " << k0 + a;
                if (o.touching) {
                    ++touching;
                    ASSERT_EQ(bits(batch.fx(b)), bits(o.f.x())) << "pair " << k0 + a;
                    ASSERT_EQ(bits(batch.fy(b)), bits(o.f.y())) << "pair " << k0 + a;
                    ASSERT_EQ(bits(batch.torque_i(b)), bits(o.torque_i));
                    ASSERT_EQ(bits(batch.torque_j(b)), bits(o.torque_j));
                    ASSERT_EQ(bits(batch.k_tran(b)), bits(o.k_tran));
                    ASSERT_EQ(bits(batch.k_rot(b)), bits(o.k_rot));
                }
                // disc i's record: the opposite force (added, it is the scalar pass' subtraction)
                // and the same stiffness
                ASSERT_EQ(bits(batch.to_i[b][0]), bits(-batch.fx(b))) << "pair " << k0 + a;
                ASSERT_EQ(bits(batch.to_i[b][1]), bits(-batch.fy(b))) << "pair " << k0 + a;
                ASSERT_EQ(bits(batch.to_i[b][3]), bits(batch.k_tran(b))) << "pair " << k0 + a;
                if (o.touching) {
                    const PairMaterial& pm = k.materials[size_t(k.material[size_t(c.i)]) * 2 + size_t(k.material[size_t(c.j)])];
                    if (std::abs(c.fs) == pm.mu * (pm.kn * overlap)) ++sliding;
                    if (c.damp_n != 0.0f && float(-pm.kn * overlap) == c.damp_n) ++tension_cut;
                } else {
                    // what the force pass adds for an open pair: +0 (PairBatch)
                    for (double x : {batch.fx(b), batch.fy(b), batch.torque_i(b), batch.torque_j(b), batch.k_tran(b),
                                     batch.k_rot(b)})
                        ASSERT_EQ(bits(x), bits(0.0));
                    if (before.damp_n != 0.0f || before.damp_s != 0.0f) ++open_with_dashpots;
                }
            }
        }
        // the case covers what it is meant to
        EXPECT_GT(checked, 2000u);
        EXPECT_GT(touching, checked / 5);
        EXPECT_GT(checked - touching, checked / 5);
        EXPECT_GT(open_with_dashpots, 100u);
        EXPECT_GT(left_out, 100u);
        EXPECT_GT(signed_zero_history, 50u);
        EXPECT_GT(sliding, 50u);
        if (mode == DashpotMode::NoTension || mode == DashpotMode::NoTensionNoShearWhileSliding) {
            EXPECT_GT(tension_cut, 3u);
        }
    }
}

// The law alone over a list of contacts (pair_law_avx2, pair_law_avx512: World's cross-range
// pairs), every pair whatever its state, in the list's order: the scalar kernel's bits, with an
// open pair's terms +0 and half its dissipation.
TEST(PairKernel, IndexedLawGivesTheScalarKernelsBits) {
    struct Law {
        const char* name;
        bool available;
        size_t (*run)(const DiscArrays&, const PairPassParams&, DiscContact*, PairBatch&);
    };
    const Law laws[] = {{"AVX2", cpu_has_avx2(), pair_law_avx2}, {"AVX-512", cpu_has_avx512(), pair_law_avx512}};
    if (!cpu_has_avx2()) GTEST_SKIP() << "this CPU has no AVX2";
    for (const Law& law : laws) {
        if (!law.available) continue;
        SCOPED_TRACE(law.name);
        const KernelCase k(31);
        const DiscArrays d = k.arrays();
        const PairPassParams p = k.params(DashpotMode::NoTensionNoShearWhileSliding);
        std::vector<DiscContact> scalar = k.contacts, simd = k.contacts;
        // every third contact, from the end backwards: a list in no particular order
        std::vector<uint32_t> list;
        for (size_t c = simd.size(); c-- > 0;)
            if (c % 3 == 0) list.push_back(uint32_t(c));
        size_t touching = 0, open = 0;
        PairBatch batch;
        for (size_t e = 0; e < list.size(); e += PairBatch::kSize) {
            const size_t n = std::min(PairBatch::kSize, list.size() - e);
            for (size_t b = 0; b < n; ++b) batch.index[b] = list[e + b];
            batch.count = n;
            ASSERT_EQ(law.run(d, p, simd.data(), batch), n);
            for (size_t b = 0; b < n; ++b) {
                DiscContact& c = scalar[list[e + b]];
                PairOut o{};
                double overlap = 0.0;
                ASSERT_TRUE(disc_pair_force(d, p, c, o, overlap));
                ASSERT_TRUE(same_history(simd[list[e + b]], c)) << "contact " << list[e + b];
                ASSERT_EQ(batch.touching[b], int32_t(o.touching));
                ASSERT_EQ(bits(batch.half_dissipated(b)), bits(0.5 * o.dissipated));
                if (o.touching) {
                    ++touching;
                    ASSERT_EQ(bits(batch.fx(b)), bits(o.f.x()));
                    ASSERT_EQ(bits(batch.fy(b)), bits(o.f.y()));
                    ASSERT_EQ(bits(batch.torque_i(b)), bits(o.torque_i));
                    ASSERT_EQ(bits(batch.torque_j(b)), bits(o.torque_j));
                    ASSERT_EQ(bits(batch.k_tran(b)), bits(o.k_tran));
                    ASSERT_EQ(bits(batch.k_rot(b)), bits(o.k_rot));
                } else {
                    ++open;
                    for (double x : {batch.fx(b), batch.fy(b), batch.torque_j(b), batch.k_tran(b), batch.k_rot(b)})
                        ASSERT_EQ(bits(x), bits(0.0));
                }
            }
        }
        EXPECT_GT(touching, 200u);
        EXPECT_GT(open, 200u);
    }
}

// The clearance test (PairSkip): what it records is a bound of each open pair's gap above
// the approach, the pairs it then skips are those, and the others get the scalar kernel's bits.
TEST(PairKernel, ClearanceTestSkipsOnlyPairsThatCannotTouch) {
    if (simd_kernels().empty()) GTEST_SKIP() << "this CPU has no AVX2";
    for (const SimdKernel& kern : simd_kernels()) {
    SCOPED_TRACE(kern.name);
    const KernelCase k(23);
    const DiscArrays d = k.arrays();
    const PairPassParams p = k.params(DashpotMode::Full);
    std::vector<DiscContact> scalar = k.contacts, simd = k.contacts;
    std::vector<float> clearance(simd.size(), 0.0f);
    const double approach = 1.0e-4;  // m, as if the discs had moved since the clearances began
    const PairSkip skip{clearance.data(), float(approach), std::nextafter(float(approach), 1.0f)};
    // two passes over the same state: the first finds the clear pairs, the second skips them
    size_t cleared = 0, marked_touching = 0, looked_again = 0, skipped = 0, done_total = 0;
    for (int pass = 0; pass < 2; ++pass) {
        PairBatch batch;
        for (size_t k0 = 0; k0 < simd.size(); k0 += PairBatch::kSize) {
            const size_t n = std::min(PairBatch::kSize, simd.size() - k0);
            PairSkip s = skip;
            s.clearance = clearance.data() + k0;
            std::vector<float> before(clearance.begin() + long(k0), clearance.begin() + long(k0 + n));
            const size_t done = kern.run(d, p, &simd[k0], n, batch, &s);
            ASSERT_EQ(done, n - n % 4);
            const std::vector<int> slot = batch_slots(batch, done);
            for (size_t a = 0; a < done; ++a) {
                DiscContact& c = scalar[k0 + a];
                PairOut o{};
                double overlap = 0.0;
                ASSERT_TRUE(disc_pair_force(d, p, c, o, overlap));
                ASSERT_TRUE(same_history(simd[k0 + a], c)) << "pair " << k0 + a;
                const float cl = clearance[k0 + a];
                const double gap = (k.pos[size_t(c.j)] - k.pos[size_t(c.i)]).norm() - (k.radius[size_t(c.i)] + k.radius[size_t(c.j)]);
                if (pass == 1 && before[a] > skip.approach_hi) {
                    ++skipped;  // left alone: not in the batch, its clearance kept
                    ASSERT_LT(slot[a], 0) << "pair " << k0 + a;
                    ASSERT_EQ(bits(cl), bits(before[a]));
                }
                if (slot[a] >= 0) {
                    const size_t b = size_t(slot[a]);
                    ASSERT_EQ(batch.touching[b], int32_t(o.touching)) << "pair " << k0 + a;
                    ASSERT_EQ(bits(batch.half_dissipated(b)), bits(0.5 * o.dissipated)) << "pair " << k0 + a;
                    if (o.touching) {
                        ASSERT_EQ(bits(batch.fx(b)), bits(o.f.x()));
                        ASSERT_EQ(bits(batch.torque_j(b)), bits(o.torque_j));
                    }
                } else {
                    ASSERT_FALSE(o.touching) << "pair " << k0 + a;
                    ASSERT_EQ(bits(o.dissipated), bits(0.0)) << "pair " << k0 + a;
                }
                if (o.touching) {
                    ASSERT_EQ(cl, -1.0f) << "pair " << k0 + a;  // to do next time, no look
                    if (pass == 0) ++marked_touching;
                } else if (cl > 0.0f) {
                    // a bound: open now with a zero history, and at least its gap away
                    ASSERT_LE(double(cl), approach + gap) << "pair " << k0 + a;
                    ASSERT_GT(double(cl), approach + gap - 2e-8) << "pair " << k0 + a;  // and a tight one (2^-20 of some mm)
                    ASSERT_EQ(bits(c.fs), bits(0.0));
                    ASSERT_EQ(bits(c.damp_n), bits(0.0f));
                    ASSERT_EQ(bits(c.damp_s), bits(0.0f));
                    if (pass == 0) ++cleared;
                }
                // a pair whose history the first pass ended has clearance 0: looked at again
                if (pass == 1 && bits(before[a]) == bits(0.0f) && !o.touching) ++looked_again;
            }
            done_total += done;
        }
    }
    EXPECT_GT(done_total, 4000u);
    EXPECT_GT(cleared, 200u);
    EXPECT_GT(marked_touching, 500u);
    EXPECT_GT(looked_again, 50u);
    EXPECT_GT(skipped, 200u);
    }
}

TEST(PairKernel, SimdKernelsLeaveABlownUpGroupToTheScalarKernel) {
    if (simd_kernels().empty()) GTEST_SKIP() << "this CPU has no AVX2";
    for (const SimdKernel& kern : simd_kernels()) {
    SCOPED_TRACE(kern.name);
    KernelCase k(5);
    // pair 6 (group 4-7) overlaps by more than half the smaller radius
    DiscContact& bad = k.contacts[6];
    k.pos[size_t(bad.j)] = k.pos[size_t(bad.i)] + Vec2(0.1 * k.radius[size_t(bad.i)], 0.0);
    std::vector<DiscContact> simd = k.contacts;
    PairBatch batch;
    const size_t done = kern.run(k.arrays(), k.params(DashpotMode::Full), simd.data(), 16, batch, nullptr);
    // it stops at the first pair of the law's group (of the pairs with something to do) that
    // holds pair 6, and leaves everything from there on alone; with groups of four that is
    // past pair 0 in this case
    if (kern.group == 4) {
        EXPECT_GT(done, 0u);
    }
    EXPECT_LE(done, 6u);
    for (size_t m = done; m < 16; ++m) EXPECT_EQ(std::memcmp(&simd[m], &k.contacts[m], sizeof(DiscContact)), 0) << m;
    for (size_t b = 0; b < batch.count; ++b) EXPECT_LT(batch.index[b], done);
    PairOut o{};
    double overlap = 0.0;
    EXPECT_FALSE(disc_pair_force(k.arrays(), k.params(DashpotMode::Full), simd[6], o, overlap));
    }
}

TEST(PairKernel, SimdAndScalarWorldsGiveTheSameBits) {
    if (!cpu_has_avx2()) GTEST_SKIP() << "this CPU has no AVX2";
    // the whole pass (batches cut at cross contacts and range ends, the gather in list order):
    // part of DB-9k on 2 threads, with a shear dashpot, in the default mode and in the one that cuts tension and the sliding
    // shear dashpot
    auto discs = read_xyr(default_db9k_path());
    discs.resize(2000);
    for (DashpotMode mode : {DashpotMode::Full, DashpotMode::NoTensionNoShearWhileSliding}) {
        // worlds 0: the widest law the CPU has (AVX-512 or AVX2), 1: scalar, 2: AVX2
        uint64_t h[3];
        EnergyReport e[3];
        for (int k = 0; k < 3; ++k) {
            WorldDef def = db9k_world_def();
            def.threads = 2;
            def.simd = k != 1;
            def.avx512 = k == 0;
            def.damping.dp_mode = mode;
            def.damping.beta_s = 0.05;
            World w(def);
            EXPECT_EQ(w.simd_kernel(), k != 1);
            EXPECT_EQ(w.avx512_kernel(), k == 0 && cpu_has_avx512());
            build_db9k(w, discs);
            w.finalize();
            w.run(1500);
            h[k] = state_hash(w);
            e[k] = w.energy();
            // the SIMD passes skipped clear pairs (the clearance test), the scalar one none
            if (k != 1) {
                EXPECT_GT(w.pairs_skipped(), w.candidate_passes() / 10);
            } else {
                EXPECT_EQ(w.pairs_skipped(), 0);
            }
        }
        EXPECT_GT(e[0].dissipated_contacts, 0.0);
        for (int k = 1; k < 3; ++k) {
            EXPECT_EQ(h[0], h[k]) << "world " << k;
            EXPECT_EQ(bits(e[0].dissipated_contacts), bits(e[k].dissipated_contacts));
            EXPECT_EQ(bits(e[0].elastic), bits(e[k].elastic));
        }
    }
}

// A disc moved or grown by hand between steps may touch a pair the clearance test had found
// clear: World forgets the clearances then, so the AVX2 world still gives the scalar bits.
TEST(PairKernel, ClearancesAreForgottenWhenDiscsAreEditedByHand) {
    if (!cpu_has_avx2()) GTEST_SKIP() << "this CPU has no AVX2";
    auto discs = read_xyr(default_db9k_path());
    discs.resize(1500);
    for (int edit = 0; edit < 2; ++edit) {
        uint64_t h[2];
        for (int k = 0; k < 2; ++k) {
            WorldDef def = db9k_world_def();
            def.simd = k == 0;
            World w(def);
            build_db9k(w, discs);
            w.finalize();
            w.run(400);
            // the first candidate pair open by 2 to 10 % of a radius: bring its discs into
            // contact (move j towards i, or grow i), by 1 % of a radius beyond the gap
            for (const DiscContact& c : w.disc_contacts()) {
                const Vec2 pi = w.positions()[size_t(c.i)], pj = w.positions()[size_t(c.j)];
                const double ri = w.radii()[size_t(c.i)], rj = w.radii()[size_t(c.j)];
                const double gap = (pj - pi).norm() - (ri + rj);
                if (gap < 0.02 * rj || gap > 0.1 * rj) continue;
                if (edit == 0)
                    w.set_position(c.j, pj - (pj - pi).normalized() * (gap + 0.01 * rj));
                else
                    w.set_radius(c.i, ri + gap + 0.01 * rj);
                break;
            }
            if (edit == 1) w.refresh_dashpots();
            w.run(50);
            h[k] = state_hash(w);
        }
        EXPECT_EQ(h[0], h[1]) << (edit == 0 ? "set_position" : "set_radius");
    }
}

namespace {
// The output of `demlab ARGS` (stdout), as `bench` prints it.
std::string demlab_output(const std::string& args) {
    std::unique_ptr<FILE, int (*)(FILE*)> pipe(popen((std::string(DEMLAB_EXE) + " " + args + " 2>/dev/null").c_str(), "r"),
                                              pclose);
    std::string out;
    if (!pipe) return out;
    char buf[512];
    while (fgets(buf, sizeof buf, pipe.get())) out += buf;
    return out;
}

// The exit code of `demlab ARGS` (-1 if it did not exit normally).
int demlab_exit_code(const std::string& args) {
    const int status = std::system((std::string(DEMLAB_EXE) + " " + args + " >/dev/null 2>&1").c_str());
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::string line_with(const std::string& text, const std::string& key) {
    const size_t at = text.find(key);
    if (at == std::string::npos) return "";
    const size_t begin = text.rfind('\n', at) + 1;  // npos + 1 = 0 on the first line
    return text.substr(begin, text.find('\n', at) - begin);
}
}  // namespace

TEST(PairKernel, BenchKernelFlagsChooseTheKernelAndKeepTheChecksum) {
    const std::string simd = demlab_output("bench db9k --steps 200");
    const std::string avx2 = demlab_output("bench db9k --steps 200 --no-avx512");
    const std::string scalar = demlab_output("bench db9k --steps 200 --scalar");
    const char* widest = cpu_has_avx512() ? "AVX-512 pair kernel" : cpu_has_avx2() ? "AVX2 pair kernel" : "scalar pair kernel";
    EXPECT_NE(line_with(simd, widest), "") << simd;
    EXPECT_NE(line_with(avx2, cpu_has_avx2() ? "AVX2 pair kernel" : "scalar pair kernel"), "") << avx2;
    EXPECT_NE(line_with(scalar, "scalar pair kernel"), "") << scalar;
    const std::string checksum = line_with(simd, "final-state checksum");
    ASSERT_NE(checksum, "") << simd;
    EXPECT_EQ(checksum, line_with(avx2, "final-state checksum"));
    EXPECT_EQ(checksum, line_with(scalar, "final-state checksum"));
}

TEST(Bench, CeilingRunsCopiesSideBySideAndNeedsTwoThreads) {
    // two 1-thread copies beside one alone: their figures, and the 2-thread run's against them
    const std::string out = demlab_output("bench db9k --steps 200 --threads 2 --ceiling");
    EXPECT_NE(line_with(out, "ceiling: one 1-thread run alone"), "") << out;
    EXPECT_NE(line_with(out, "2 side by side:"), "") << out;
    EXPECT_NE(line_with(out, "the 2 cores give"), "") << out;
    EXPECT_EQ(line_with(out, "checksums differ"), "") << out;  // every copy ends in the same bits
    // with one thread there is nothing to compare: an input error (exit code 2) before any run
    EXPECT_EQ(demlab_exit_code("bench db9k --ceiling --steps 200"), 2);
}

// bench db9k --copies: the columns stand side by side, each with its own left wall, and do not
// reach one another (every candidate pair stays within one copy, whose discs are numbered
// together); the command prints the larger N, and LAMMPS' script runs only one column.
TEST(Bench, CopiesStandSideBySideWithoutTouching) {
    auto discs = read_xyr(default_db9k_path());
    discs.resize(1500);  // the column's lowest rows
    const size_t n = discs.size();
    WorldDef def = db9k_world_def(3);
    def.threads = 2;
    World w(def);
    build_db9k(w, discs, 3);
    w.finalize();
    w.run(400);
    ASSERT_EQ(w.disc_count(), 3 * n);
    EXPECT_EQ(w.wall_count(), 4u);  // one floor, three left walls
    EXPECT_GT(w.disc_contacts().size(), 0u);
    for (const DiscContact& c : w.disc_contacts()) ASSERT_EQ(size_t(c.i) / n, size_t(c.j) / n) << c.i << " " << c.j;
    for (size_t i = 0; i < w.disc_count(); ++i) {
        const double x0 = kCopySpacing * double(i / n);  // the copy's left wall
        EXPECT_GT(w.positions()[i].x(), x0);
        EXPECT_LT(w.positions()[i].x(), x0 + 0.5 * kCopySpacing);
    }
    const std::string out = demlab_output("bench db9k --copies 2 --steps 20");
    EXPECT_NE(line_with(out, "(2 columns side by side): N=18280 "), "") << out;
    // input errors (2) before any run; a count out of 1..64 is a usage error (1)
    for (const char* args : {"bench db9k --copies 2 --peer --steps 10", "bench db9k --copies 2 --targets --steps 10",
                             "bench jitter --copies 2 --seconds 0.05"})
        EXPECT_EQ(demlab_exit_code(args), 2) << args;
    for (const char* args : {"bench db9k --copies 0 --steps 10", "bench db9k --copies 65 --steps 10"})
        EXPECT_EQ(demlab_exit_code(args), 1) << args;
}

// Software prefetch (WorldDef::prefetch) asks for cache lines and nothing else: on, off and
// auto end in the same bits, on 1 and 2 threads; auto stays off while the step's arrays fit in
// half the last-level cache, and the bench says which it used.
TEST(Prefetch, OnAndOffGiveTheSameBits) {
    auto discs = read_xyr(default_db9k_path());
    discs.resize(3000);
    uint64_t first = 0;
    for (Prefetch mode : {Prefetch::Off, Prefetch::On, Prefetch::Auto})
        for (int threads : {1, 2}) {
            WorldDef def = db9k_world_def(2);
            def.threads = threads;
            def.prefetch = mode;
            World w(def);
            build_db9k(w, discs, 2);
            w.finalize();
            w.run(300);
            EXPECT_EQ(w.prefetching(), mode == Prefetch::On);  // 6,000 discs: well inside the cache
            EXPECT_LT(w.step_bytes(), prefetch_threshold_bytes());
            EXPECT_GT(w.step_bytes(), 6000u * 100u);
            const uint64_t h = state_hash(w);
            if (first == 0) first = h;
            EXPECT_EQ(h, first) << int(mode) << " " << threads;
        }
    EXPECT_NE(line_with(demlab_output("bench db9k --steps 20 --prefetch on"), "software prefetch: on"), "");
    EXPECT_NE(line_with(demlab_output("bench db9k --steps 20"), "software prefetch: off"), "");
    EXPECT_EQ(demlab_exit_code("bench db9k --steps 20 --prefetch sometimes"), 1);
}

// The figures in one invocation: rounds of 1 thread, 2 threads and the ceiling, a
// table with medians and ranges, and the targets; every run ends in the same state.
TEST(Bench, TargetsRunRoundsAndPrintTheTable) {
    const std::string out = demlab_output("bench db9k --targets --rounds 2 --steps 100");
    EXPECT_NE(line_with(out, "round 1: 1 thread"), "") << out;
    EXPECT_NE(line_with(out, "round 2: 1 thread"), "") << out;
    EXPECT_EQ(line_with(out, "round 3:"), "") << out;
    EXPECT_NE(line_with(out, "| median |"), "") << out;
    EXPECT_NE(line_with(out, "| range |"), "") << out;
    EXPECT_NE(line_with(out, "| 2 threads vs demlab's 1 thread | 1.8x |"), "") << out;
    // 2 rounds of 5 runs (1 thread, 2 threads, one alone, two side by side), all the same bits
    EXPECT_NE(line_with(out, "in all 10 runs | met |"), "") << out;
    // --rounds belongs to --targets, and --targets chooses the threads itself: input errors
    for (const char* args : {"bench db9k --rounds 2 --steps 10", "bench db9k --targets --threads 2 --steps 10",
                             "bench db9k --targets --ceiling --steps 10"})
        EXPECT_EQ(demlab_exit_code(args), 2) << args;
}

// The jitter probe's accounting: with a threshold of 0 every step of the clock is a gap, so the
// gaps add up to the whole time probed (integer clock ticks: exactly); with a threshold longer
// than the probe, there are none.
TEST(Bench, JitterProbeAccountsForEveryTick) {
    const std::vector<CoreGaps> all = measure_gaps(1, 0.02, 0.0);
    ASSERT_EQ(all.size(), 1u);
    EXPECT_GT(all[0].gaps, 0);
    EXPECT_GE(all[0].seconds, 0.02);
    EXPECT_EQ(all[0].lost, all[0].seconds);
    EXPECT_LE(all[0].longest, all[0].lost);
    const std::vector<CoreGaps> none = measure_gaps(2, 0.02, 10.0);
    ASSERT_EQ(none.size(), 2u);
    for (const CoreGaps& g : none) {
        EXPECT_EQ(g.gaps, 0);
        EXPECT_EQ(g.lost, 0.0);
        EXPECT_GE(g.seconds, 0.02);
    }
    // the command: a line per core and the cost to a run that joins its threads
    const std::string out = demlab_output("bench jitter --threads 2 --seconds 0.05");
    EXPECT_NE(line_with(out, "probe on each of 2 core(s)"), "") << out;
    EXPECT_NE(line_with(out, "a run whose 2 threads join every step"), "") << out;
    // --seconds belongs to jitter, and jitter takes none of DB-9k's options: input errors
    for (const char* args : {"bench db9k --seconds 1 --steps 10", "bench jitter --steps 10 --seconds 0.05",
                             "bench jitter --peer --seconds 0.05"})
        EXPECT_EQ(demlab_exit_code(args), 2) << args;
}

// When the clearances are reset (a disc moved by hand), every pair is looked at again, and a pair
// that has come apart with its history still set must have it ended. Eight pairs of discs
// collide head-on; at the step where they have come apart with their histories still set, a
// disc far away is moved by hand. The SIMD world must end those histories (and count their
// dashpots' last half-step of work) as the scalar world does.
TEST(PairKernel, ClearanceResetKeepsPairsWithAHistoryToDo) {
    if (!cpu_has_avx2()) GTEST_SKIP() << "this CPU has no AVX2";
    std::unique_ptr<World> w[2];
    for (int k = 0; k < 2; ++k) {
        WorldDef def;
        def.simd = k == 0;
        def.gravity = Vec2::Zero();
        def.timestep.automatic = false;
        def.timestep.fixed = 2e-6;
        def.damping.beta_n = def.damping.beta_s = 0.3;
        w[k] = std::make_unique<World>(def);
        MaterialDef m;
        m.kn = m.ks = 1e8;
        m.friction = 0.3;
        const int mat = w[k]->add_material(m);
        for (int p = 0; p < 8; ++p) {
            const double x = 0.05 * p;
            w[k]->add_disc({Vec2(x, 0.0), 0.001, Vec2(1.0, 0.3), 0.0, 0.0, mat});
            w[k]->add_disc({Vec2(x + 0.0021, 0.0), 0.001, Vec2(-1.0, -0.3), 0.0, 0.0, mat});
        }
        w[k]->add_disc({Vec2(1.0, 1.0), 0.001, Vec2::Zero(), 0.0, 0.0, mat});  // the one moved by hand
        w[k]->finalize();
    }
    ASSERT_TRUE(w[0]->simd_kernel());
    auto parted_with_history = [](const World& x) {
        for (const DiscContact& c : x.disc_contacts()) {
            const double gap = (x.positions()[size_t(c.j)] - x.positions()[size_t(c.i)]).norm() -
                               (x.radii()[size_t(c.i)] + x.radii()[size_t(c.j)]);
            if (gap > 0.0 && (c.fs != 0.0 || c.damp_n != 0.0f)) return true;
        }
        return false;
    };
    bool touched = false, reset = false;
    for (int s = 0; s < 4000 && !reset; ++s) {
        touched = touched || w[0]->touching_disc_pairs() == 8;
        if (touched && parted_with_history(*w[0])) {
            ASSERT_TRUE(parted_with_history(*w[1]));
            for (auto& x : w) x->set_position(16, Vec2(1.0, 1.0));  // forgets the clearances
            reset = true;
        }
        for (auto& x : w) x->step();
    }
    ASSERT_TRUE(reset) << "the pairs did not come apart";
    for (auto& x : w) x->run(20);
    EXPECT_EQ(state_hash(*w[0]), state_hash(*w[1]));
    const EnergyReport a = w[0]->energy(), b = w[1]->energy();
    EXPECT_GT(a.dissipated_contacts, 0.0);
    EXPECT_EQ(bits(a.dissipated_contacts), bits(b.dissipated_contacts));
    for (size_t c = 0; c < w[0]->disc_contacts().size(); ++c)
        EXPECT_TRUE(same_history(w[0]->disc_contacts()[c], w[1]->disc_contacts()[c])) << "contact " << c;
}
