// Bonds, the world's persistent interactions (dem/bonds/elastic_bond.h), against the closed
// forms of docs/spec/COHESION.md section 5 (E = 5e4 Pa, t = 1 m: k0 = 28,867.51 N/m).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/binary_io.h"
#include "dem/world.h"
#include "helpers.h"

using namespace demlab;
using demlab::test::expect_refused;

namespace {
// discs of radius 0.05, density 7500 (m = 58.905 kg), no gravity, no damping, rotation locked
WorldDef bond_world_def(int threads = 1) {
    WorldDef d;
    d.gravity = Vec2::Zero();
    d.damping.beta_n = d.damping.beta_s = 0.0;
    d.rotation.model = 1;
    d.threads = threads;
    return d;
}
MaterialDef steel_like() {
    MaterialDef m;
    m.density = 7500.0;
    return m;
}
int disc(World& w, Vec2 p, Vec2 v = Vec2::Zero(), double r = 0.05) { return w.add_disc({p, r, v, 0.0, 0.0, 0}); }
}  // namespace

TEST(Bonds, LawHasItsClosedForms) {
    const BondDef d;
    const double k0 = ElasticBond::k0(d);
    EXPECT_NEAR(k0, 28867.513, 1e-3);
    // C6: |F| = k0 (L - L0) L / L0 ("current"); f d with |d| = L
    const auto e = ElasticBond::evaluate(d, k0, 1.0, 1.0, Vec2(1.09, 0.0));
    EXPECT_NEAR(e.strain, 0.09, 1e-12);
    EXPECT_NEAR(e.f * 1.09, 2831.903, 1e-3);
    // C7 is the integral of C6: dU/dL = F
    const double h = 1e-6;
    const double dU = (ElasticBond::energy(d, k0, 1.0, 0.09 + h) - ElasticBond::energy(d, k0, 1.0, 0.09 - h)) / (2 * h);
    EXPECT_NEAR(dU, e.f * 1.09, 1e-3);
    BondDef rest = d;
    rest.area = BondArea::Rest;
    EXPECT_NEAR(ElasticBond::evaluate(rest, k0, 1.0, 1.0, Vec2(1.09, 0.0)).f * 1.09, k0 * 0.09, 1e-6);
    EXPECT_TRUE(ElasticBond::evaluate(d, k0, 1.0, 1.0, Vec2(0.79, 0.0)).breaks);   // compression past 0.2
    BondDef tension = d;
    tension.break_mode = BondBreak::Tension;
    EXPECT_FALSE(ElasticBond::evaluate(tension, k0, 1.0, 1.0, Vec2(0.79, 0.0)).breaks);
    EXPECT_TRUE(ElasticBond::evaluate(d, k0, 1.0, 1.0, Vec2(5e-4, 0.0)).skipped);  // C4: min_distance
}

// AvaFrame's three-point test (A4), pinned to numbers: discs at (0,0), (1,0), (0,1), bonds
// 0-1, 0-2, 1-2; disc 1 moved to (1.09, 0), then to (1.21, 0) (bond 0-1 breaks).
TEST(Bonds, AvaFrameThreePointCase) {
    for (const double x1 : {1.09, 1.21}) {
        World w(bond_world_def());
        w.add_material(steel_like());
        disc(w, {0, 0});
        disc(w, {1, 0});
        disc(w, {0, 1});
        w.add_bond(0, 1);
        w.add_bond(0, 2);
        w.add_bond(2, 1);  // stored as (1, 2)
        w.finalize();
        w.set_position(1, {x1, 0.0});
        w.set_dt(1e-12);
        w.step();  // the forces of the step are those at the positions before it
        if (x1 == 1.09) {
            EXPECT_NEAR(w.force(1).x(), -4278.327, 2e-3);
            EXPECT_NEAR(w.force(1).y(), 1326.995, 2e-3);
            EXPECT_NEAR(w.force(0).x(), 2831.903, 2e-3);
            EXPECT_NEAR(w.force(0).y(), 0.0, 1e-9);
            EXPECT_NEAR(w.force(2).x(), 1446.424, 2e-3);
            EXPECT_NEAR(w.force(2).y(), -1326.995, 2e-3);
            EXPECT_TRUE(w.bond_breaks().empty());
        } else {
            EXPECT_NEAR(w.force(1).x(), -3841.479, 2e-3);
            EXPECT_NEAR(w.force(1).y(), 3174.776, 2e-3);
            EXPECT_NEAR(w.force(0).norm(), 0.0, 1e-9);
            ASSERT_EQ(w.bond_breaks().size(), 1u);
            EXPECT_EQ(w.bond_breaks()[0].k, 0);
            EXPECT_EQ(w.bond_breaks()[0].l, 1);
            EXPECT_NEAR(w.bond_breaks()[0].strain, 0.21, 1e-12);
            EXPECT_TRUE(w.bonds()[0].broken);
        }
        const Vec2 sum = w.force(0) + w.force(1) + w.force(2);
        EXPECT_LT(sum.norm(), 1e-9);
    }
}

// A pair stretched by 1e-5 oscillates at omega = sqrt(2 k0 / m) = 31.3072 rad/s (period
// 0.200695 s); the ledger (kinetic + bond energy) stays put.
TEST(Bonds, PairOscillatesAndTheLedgerCloses) {
    World w(bond_world_def());
    w.add_material(steel_like());
    disc(w, {0, 0});
    disc(w, {1.0, 0});
    w.add_bond(0, 1);
    w.finalize();
    w.set_position(1, {1.0 + 1e-5, 0.0});
    w.set_dt(1e-5);
    const double e0 = w.energy().balance();
    EXPECT_GT(w.energy().bond_elastic, 0.0);
    // upward zero crossings of the stretch, interpolated
    std::vector<double> crossings;
    double last = 1e-5, max_drift = 0.0;
    for (int s = 0; s < 50000; ++s) {
        w.step();
        const double stretch = w.positions()[1].x() - w.positions()[0].x() - 1.0;
        if (last < 0.0 && stretch >= 0.0) crossings.push_back(w.time() - w.dt() * stretch / (stretch - last));
        last = stretch;
        if (s % 100 == 0) max_drift = std::max(max_drift, std::abs(w.energy().balance() - e0));
    }
    ASSERT_GE(crossings.size(), 2u);
    const double period = (crossings.back() - crossings.front()) / double(crossings.size() - 1);
    EXPECT_NEAR(period, 0.200695, 0.001 * 0.200695);
    EXPECT_LT(max_drift, 1e-3 * e0);  // the centred ledger's O((omega dt)^2) wobble
}

// Two bonded discs flying apart at v: the bond breaks iff v > sqrt(2 U_c / m_eff) = 6.66581 m/s
// (U_c = 654.330 J at eps = 0.2, m_eff = 29.452 kg): at 6.60 m/s the stretch peaks at 0.19813;
// at 8 m/s they part at 4.4235 m/s, and the
// energy the bond held moves to the break loss.
TEST(Bonds, BreaksPastMaxStrain) {
    for (const double v : {6.60, 8.0}) {
        World w(bond_world_def());
        w.add_material(steel_like());
        disc(w, {0, 0}, {-0.5 * v, 0.0});
        disc(w, {1.0, 0}, {0.5 * v, 0.0});
        w.add_bond(0, 1);
        w.finalize();
        w.set_dt(1e-5);
        const double e0 = w.energy().balance();
        // to the largest stretch (the discs stop separating), or 0.3 s after a break; a bond
        // that held would break in compression on the way back (v > 5.82908 m/s, "both")
        double max_strain = 0.0;
        for (int s = 0; s < 30000; ++s) {
            w.step();
            max_strain = std::max(max_strain, w.positions()[1].x() - w.positions()[0].x() - 1.0);
            if (w.bond_breaks().empty() && w.velocities()[1].x() <= w.velocities()[0].x()) break;
        }
        if (v < 6.66) {
            EXPECT_TRUE(w.bond_breaks().empty());
            EXPECT_NEAR(max_strain, 0.19813, 2e-4);
        } else {
            ASSERT_EQ(w.bond_breaks().size(), 1u);
            const double separation = w.velocities()[1].x() - w.velocities()[0].x();
            EXPECT_NEAR(separation, 4.4235, 0.005 * 4.4235);
            const EnergyReport e = w.energy();
            EXPECT_NEAR(e.bond_break_loss, 654.330, 2.0);  // U at the breaking step (eps just past 0.2)
            EXPECT_EQ(e.bond_elastic, 0.0);
            EXPECT_LT(std::abs(e.balance() - e0), 1e-3 * e0);
        }
    }
}

// Two bonded discs approaching at v (no contact: they touch only at L = 0.1 m): with "both" the
// bond breaks in compression iff v > sqrt(2 U(-0.2) / m_eff) = 5.82908 m/s (U = 500.370 J at
// eps = -0.2, C7); with "tension" it never breaks and the pair rebounds with e = 1 (the bond
// is conservative).
TEST(Bonds, BreaksInCompression) {
    // U(-0.2) = k0 L0^2 (0.02 - 0.008/3), the closed form the threshold comes from
    EXPECT_NEAR(ElasticBond::energy(BondDef{}, ElasticBond::k0(BondDef{}), 1.0, -0.2), 500.370, 1e-3);
    for (const BondBreak mode : {BondBreak::Both, BondBreak::Tension})
        for (const double v : {5.75, 6.0}) {
            WorldDef d = bond_world_def();
            d.bond.break_mode = mode;
            World w(d);
            w.add_material(steel_like());
            disc(w, {0, 0}, {0.5 * v, 0.0});
            disc(w, {1.0, 0}, {-0.5 * v, 0.0});
            w.add_bond(0, 1);
            w.finalize();
            w.set_dt(1e-5);
            const double e0 = w.energy().balance();
            double min_strain = 0.0;
            bool rebounded = false;
            for (int s = 0; s < 40000 && !rebounded; ++s) {
                w.step();
                const double strain = w.positions()[1].x() - w.positions()[0].x() - 1.0;
                min_strain = std::min(min_strain, strain);
                if (!w.bond_breaks().empty()) break;
                rebounded = min_strain < -0.1 && strain >= 0.0;  // back at the rest length
            }
            const bool breaks = mode == BondBreak::Both && v > 5.82908;
            ASSERT_EQ(w.bond_breaks().size(), breaks ? 1u : 0u) << v;
            if (breaks) {
                EXPECT_NEAR(w.bond_breaks()[0].strain, -0.2, 2e-3);
                EXPECT_NEAR(w.energy().bond_break_loss, 500.370, 5.0);
                EXPECT_LT(std::abs(w.energy().balance() - e0), 1e-3 * e0);
                continue;
            }
            ASSERT_TRUE(rebounded) << v;
            if (v < 5.82908) EXPECT_GT(min_strain, -0.2);  // short of the break
            else EXPECT_LT(min_strain, -0.2);              // "tension": past -0.2 and intact
            const double separation = w.velocities()[1].x() - w.velocities()[0].x();
            EXPECT_NEAR(separation / v, 1.0, 1e-4);  // e = 1
        }
}

// C5: with lengths from positions predicted one step the bond is a spring and a dashpot
// c = k_b dt, damping ratio zeta = omega dt / 2 = 0.015654 at dt = 1e-3 s (C11): the amplitude
// falls by exp(-2 pi zeta / sqrt(1 - zeta^2)) = 0.90632 a period (within 5 % of the decrement);
// the dashpot's work is booked, so the ledger still closes; a checkpoint resumes to the bits.
TEST(Bonds, PredictDamps) {
    auto build = [] {
        WorldDef d = bond_world_def();
        d.bond.predict = true;
        d.timestep.automatic = false;
        d.timestep.fixed = 1e-3;
        auto w = std::make_unique<World>(d);
        w->add_material(steel_like());
        disc(*w, {0, 0});
        disc(*w, {1.0, 0});
        w->add_bond(0, 1);
        w->finalize();
        w->set_position(1, {1.0 + 1e-5, 0.0});
        return w;
    };
    auto w = build();
    const double e0 = w->energy().balance();
    // the stretch's peaks, one a period
    std::vector<double> peaks;
    double before = 0.0, last = 1e-5;
    for (int s = 0; s < 2000; ++s) {
        w->step();
        const double stretch = w->positions()[1].x() - w->positions()[0].x() - 1.0;
        if (s > 1 && last > before && last >= stretch) peaks.push_back(last);
        before = last;
        last = stretch;
    }
    ASSERT_GE(peaks.size(), 8u);
    const double ratio = std::pow(peaks[7] / peaks[0], 1.0 / 7.0);
    EXPECT_NEAR(std::log(ratio), std::log(0.90632), 0.05 * std::abs(std::log(0.90632)));
    const EnergyReport e = w->energy();
    EXPECT_GT(e.dissipated_contacts, 0.5 * e0);  // most of the energy went into the dashpot
    EXPECT_LT(std::abs(e.balance() - e0), 0.01 * e.dissipated_contacts);
    // a checkpoint mid-way resumes to the same bits (the dashpot's last force is history)
    auto a = build(), b = build();
    a->run(600);
    b->run(300);
    BinaryWriter out;
    b->save_state(out);
    auto c = build();
    BinaryReader in(out.bytes(), "predict checkpoint");
    c->load_state(in);
    c->run(300);
    EXPECT_EQ(a->positions(), c->positions());
    EXPECT_EQ(a->velocities(), c->velocities());
    EXPECT_EQ(a->energy().dissipated_contacts, c->energy().dissipated_contacts);
}

// A lone bonded pair, automatic step: 0.8 sqrt(m / (1.4 k0)) = 0.0305420 s (C10, "current").
TEST(Bonds, TimeStepSeesBonds) {
    WorldDef d = bond_world_def();
    d.timestep.automatic = true;
    World w(d);
    w.add_material(steel_like());
    disc(w, {0, 0});
    disc(w, {1.0, 0});
    w.add_bond(0, 1);
    w.finalize();
    w.step();
    EXPECT_NEAR(w.dt(), 0.0305420, 1e-7);
}

// A bonded lattice with random velocities and no contacts: momentum is kept to round-off
// (central forces), and 1 and 2 threads give the same bits; a checkpoint resumes to them too.
TEST(Bonds, MomentumThreadsAndCheckpoint) {
    auto build = [](int threads) {
        auto w = std::make_unique<World>(bond_world_def(threads));
        w->add_material(steel_like());
        std::mt19937_64 rng(7);
        std::uniform_real_distribution<double> u(-0.01, 0.01);
        const int nx = 80, ny = 60;  // 4,800 discs, spaced 0.25 m (enough for the pool to share them)
        for (int j = 0; j < ny; ++j)
            for (int i = 0; i < nx; ++i) disc(*w, {0.25 * i, 0.25 * j}, {u(rng), u(rng)});
        for (int j = 0; j < ny; ++j)
            for (int i = 0; i < nx; ++i) {
                const int k = j * nx + i;
                if (i + 1 < nx) w->add_bond(k, k + 1);
                if (j + 1 < ny) w->add_bond(k, k + nx);
                if (i + 1 < nx && j + 1 < ny) w->add_bond(k, k + nx + 1);
            }
        w->finalize();
        w->set_dt(1e-3);
        return w;
    };
    auto w1 = build(1), w2 = build(2);
    Vec2 p0 = Vec2::Zero();
    for (size_t i = 0; i < w1->disc_count(); ++i) p0 += w1->masses()[i] * w1->velocities()[i];
    w1->run(300);
    w2->run(150);
    EXPECT_EQ(w2->force_pass_ranges(), 2);  // the bonds' terms really are added by two ranges
    BinaryWriter out;
    w2->save_state(out);
    auto w3 = build(2);
    BinaryReader in(out.bytes(), "bond checkpoint");
    w3->load_state(in);
    w3->run(150);
    Vec2 p1 = Vec2::Zero();
    for (size_t i = 0; i < w1->disc_count(); ++i) p1 += w1->masses()[i] * w1->velocities()[i];
    EXPECT_LT((p1 - p0).norm(), 1e-9);
    EXPECT_EQ(w1->positions(), w3->positions());
    EXPECT_EQ(w1->velocities(), w3->velocities());
    EXPECT_EQ(w1->energy().bond_elastic, w3->energy().bond_elastic);
}

TEST(Bonds, BadBondsAreRefused) {
    World w(bond_world_def());
    w.add_material(steel_like());
    disc(w, {0, 0});
    disc(w, {1, 0});
    expect_refused([&] { w.add_bond(0, 2); }, {"bond[0]", "no such disc"});
    expect_refused([&] { w.add_bond(1, 1); }, {"joins two discs"});
    w.add_bond(0, 1);
    w.add_bond(1, 0);
    expect_refused([&] { w.finalize(); }, {"given twice"});
}
