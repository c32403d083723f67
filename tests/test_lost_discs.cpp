// Discs that leave the domain (world.lost_discs): taken out with a record and their energy
// booked, the others untouched to the bit, a checkpoint after a loss resuming to the same
// bytes; or the run stopped with the right cause.
#include <gtest/gtest.h>

#include <csignal>
#include <filesystem>
#include <sstream>

#include "core/binary_io.h"
#include "core/error.h"
#include "core/interrupt.h"
#include "dem/world.h"
#include "files.h"
#include "helpers.h"
#include "resume.h"
#include "run/run.h"
#include "scenario/scenario.h"

using namespace demlab;
using demlab::test::read_file;
using demlab::test::temp_dir;
namespace fs = std::filesystem;

namespace {

MaterialDef sand() {
    MaterialDef m;
    m.density = 2650;
    m.kn = m.ks = 1e6;
    m.friction = 0.3;
    return m;
}

// the ledge: a floor from x = 0 to 1 m with a free end
void add_ledge(World& w) {
    WallDef floor;
    floor.p0 = Vec2(0, 0);
    floor.p1 = Vec2(1, 0);
    MaterialDef sheet;
    sheet.kn = sheet.ks = 1e6;
    sheet.friction = 0.3;
    floor.material = w.add_material(sheet);
    w.add_wall(floor);
}

// A disc resting on a ledge from x = 0 to 1 m, and (with the stray) one sliding off its free
// end at 2 m/s, falling out of the domain [-0.5, 1.5] x [-0.5, 0.6].
World ledge(bool with_stray, LostDiscs policy, int threads = 1) {
    WorldDef def;
    def.domain_lo = Vec2(-0.5, -0.5);
    def.domain_hi = Vec2(1.5, 0.6);
    def.lost_discs = policy;
    def.threads = threads;
    World w(def);
    const int m = w.add_material(sand());
    w.add_disc({Vec2(0.2, 0.01), 0.01, Vec2::Zero(), 0, 0, m});
    w.add_disc({Vec2(0.3, 0.0101), 0.01, Vec2(0.0, 0.0), 0, 0, m});
    if (with_stray) w.add_disc({Vec2(0.9, 0.02), 0.01, Vec2(2.0, 0.0), 0, 0, m});
    w.add_disc({Vec2(0.5, 0.03), 0.012, Vec2(0.1, 0.0), 0, 0, m});
    add_ledge(w);
    w.finalize();
    return w;
}

}  // namespace

// The stray leaves, is recorded with the id it was added with, and the three others move as
// in a world that never had it (they never touch it: every sum of theirs is the same).
TEST(LostDiscs, StrayIsTakenOutAndTheOthersKeepTheirBits) {
    World with = ledge(true, LostDiscs::Remove), without = ledge(false, LostDiscs::Remove);
    with.set_dt(2e-5);
    without.set_dt(2e-5);
    const double e0 = with.energy().balance();
    // the balance across the step that takes the stray out moves by a step's rounding alone
    double before = e0, across = 0.0;
    for (int k = 0; k < 30000; ++k) {
        if (with.lost_discs().empty()) before = with.energy().balance();
        const bool had = !with.lost_discs().empty();
        with.step();
        if (!had && !with.lost_discs().empty()) across = with.energy().balance() - before;
    }
    without.run(30000);
    EXPECT_LT(std::abs(across), 1e-9 * std::abs(e0));
    ASSERT_EQ(with.lost_discs().size(), 1u);
    const LostDiscEvent& e = with.lost_discs()[0];
    EXPECT_EQ(e.id, 2);
    EXPECT_TRUE(e.pos.x() > 1.5 || e.pos.y() < -0.5) << e.pos.transpose();
    // it left the ledge at x = 1 with 2 m/s less the friction of its slide: a free fall after
    EXPECT_GT(e.vel.x(), 1.0);
    EXPECT_LT(e.vel.y(), -2.0);
    EXPECT_NEAR(e.energy, 0.5 * e.mass * e.vel.squaredNorm() + 0.5 * 0.5 * e.mass * 1e-4 * e.omega * e.omega, 1e-12);
    ASSERT_EQ(with.disc_count(), 3u);
    EXPECT_EQ(with.disc_ids(), (std::vector<int32_t>{0, 1, 3}));
    EXPECT_EQ(with.disc_index(2), -1);
    EXPECT_EQ(with.disc_index(3), 2);
    for (size_t i = 0; i < 3; ++i) {
        EXPECT_EQ(with.positions()[i], without.positions()[i]) << i;
        EXPECT_EQ(with.velocities()[i], without.velocities()[i]) << i;
    }
    // the balance stays closed: what the stray took is booked (the drift is the contacts')
    const EnergyReport r = with.energy();
    EXPECT_GT(r.lost_with_discs, 0.0);
    EXPECT_NEAR(r.balance(), e0, 1e-3 * std::abs(e0));
}

// "stop": the run ends, and the message names the cause (no time step is blamed).
TEST(LostDiscs, StopNamesAFreeEndNotTheTimeStep) {
    World w = ledge(true, LostDiscs::Stop);
    w.set_dt(2e-5);
    std::string what;
    try {
        w.run(30000);
    } catch (const RunError& e) {
        what = e.what();
    }
    EXPECT_NE(what.find("lost disc"), std::string::npos) << what;
    EXPECT_NE(what.find("disc 2"), std::string::npos) << what;
    EXPECT_NE(what.find("free end"), std::string::npos) << what;
    EXPECT_EQ(what.find("time step"), std::string::npos) << what;
    EXPECT_NE(what.find("world.lost_discs"), std::string::npos) << what;
}

// A checkpoint written after a loss restores into a world built from the set-up (the stray
// still in it) and continues to the same bits, on another thread count.
TEST(LostDiscs, CheckpointAfterALossResumesToTheSameBits) {
    World a = ledge(true, LostDiscs::Remove);
    a.set_dt(2e-5);
    a.run(20000);
    ASSERT_EQ(a.lost_discs().size(), 1u);
    BinaryWriter out;
    a.save_state(out);
    World b = ledge(true, LostDiscs::Remove, 2);
    b.set_dt(2e-5);
    BinaryReader in(out.bytes(), "state");
    b.load_state(in);
    ASSERT_EQ(b.disc_count(), 3u);
    EXPECT_EQ(b.disc_ids(), a.disc_ids());
    a.run(5000);
    b.run(5000);
    for (size_t i = 0; i < 3; ++i) EXPECT_EQ(a.positions()[i], b.positions()[i]) << i;
    EXPECT_EQ(a.energy().balance(), b.energy().balance());
    EXPECT_EQ(b.lost_discs()[0].t, a.lost_discs()[0].t);
}

namespace {
// A scenario with a pile on a ledge and two discs thrown off its free end, one of them tracked
// and one bonded to a third (the pair flies off together).
Scenario stray_scenario(const std::string& extra = "") {
    std::ostringstream t;
    t << "[scenario]\nname = \"strays\"\n[stop]\nt_max = 1.2\n[output]\nseries_interval = 0.01\nsnapshot_interval = 0.1\ntrack = [1, 6]\n"
      << extra << "[[walls]]\nstart = [0, 0]\nend = [1, 0]\n[[walls]]\nstart = [0, 0]\nend = [0, 0.2]\n";
    for (int i = 0; i < 5; ++i) t << "[[discs]]\nposition = [" << 0.05 + 0.021 * i << ", 0.01]\nradius = 0.01\n";
    t << "[[discs]]\nposition = [0.97, 0.01]\nradius = 0.01\nvelocity = [0.6, 0]\n";
    t << "[[discs]]\nposition = [0.3, 0.01]\nradius = 0.01\nvelocity = [3, 0]\n";
    Scenario s = parse_scenario(t.str(), "strays.toml");
    finish_scenario(s);
    return s;
}
}  // namespace

TEST(LostDiscs, RunRecordsThemAndResumesToTheSameBytes) {
    const Scenario s = stray_scenario();
    const fs::path ref = temp_dir("lost-ref"), cut = temp_dir("lost-cut");
    const RunSummary r = run_scenario(s, {ref.string(), false, {}});
    EXPECT_EQ(r.lost_discs, 2);
    EXPECT_EQ(r.n_discs, 7);
    EXPECT_LT(r.energy_balance_error, 1e-3);
    const std::string lost = read_file(ref / "lost.csv");
    EXPECT_EQ(lost.rfind("t_s,id,x_m,y_m,vx_m_per_s,vy_m_per_s,omega_rad_per_s,mass_kg_per_m,kinetic_J_per_m\n", 0), 0u) << lost;
    // the slow one (id 5), near the end, drops out of the bottom at 0.41 s; the fast one
    // (id 6, tracked) goes out of the side at 0.69 s
    std::istringstream rows(lost);
    std::string header, first, second;
    std::getline(rows, header);
    std::getline(rows, first);
    std::getline(rows, second);
    EXPECT_EQ(first.substr(first.find(',') + 1, 2), "5,") << first;
    EXPECT_EQ(second.substr(second.find(',') + 1, 2), "6,") << second;
    EXPECT_LT(std::stod(first), 0.5);
    EXPECT_GT(std::stod(second), 0.5);
    // its track ends there, the other tracer's goes on
    std::istringstream track(read_file(ref / "track.csv"));
    std::string row;
    double last6 = -1, last1 = -1;
    std::getline(track, row);
    while (std::getline(track, row)) {
        const double t = std::stod(row);
        const std::string id = row.substr(row.find(',') + 1, 2);
        (id == "6," ? last6 : last1) = t;
    }
    EXPECT_LT(last6, std::stod(second));
    EXPECT_GT(last6, std::stod(second) - 0.011);
    EXPECT_GT(last1, std::stod(second) + 0.1);
    EXPECT_NE(read_file(ref / "summary.json").find("\"lost_discs\": 2"), std::string::npos);

    // interrupted between the two losses, resumed on 2 threads: the same bytes
    RunOptions ro{cut.string(), false, [](const std::string&, const std::string&, int index) {
                      if (index == 5) request_interrupt(SIGTERM);
                  }};
    ro.handle_signals = true;
    EXPECT_THROW(run_scenario(s, ro), Interrupted);
    demlab::test::resume_run(cut, 2);
    for (const char* f : {"forces.csv", "energy.csv", "track.csv", "lost.csv", "snapshots/discs_00008.vtp"})
        EXPECT_EQ(read_file(ref / f), read_file(cut / f)) << f;
    fs::remove_all(ref);
    fs::remove_all(cut);

    // with "stop" the same scenario ends with a run error naming the disc
    const fs::path stop = temp_dir("lost-stop");
    EXPECT_THROW(run_scenario(stray_scenario("[world]\nlost_discs = \"stop\"\n"), {stop.string(), false, {}}), RunError);
    fs::remove_all(stop);
}

// A disc's intact bonds go with it: counted, their energy booked, the ledger closed.
TEST(LostDiscs, BondsOfALostDiscGoWithIt) {
    WorldDef def;
    def.domain_lo = Vec2(-0.5, -0.5);
    def.domain_hi = Vec2(1.5, 0.6);
    def.lost_discs = LostDiscs::Remove;
    def.bond.modulus = 1e6;
    World w(def);
    const int m = w.add_material(sand());
    w.add_disc({Vec2(0.2, 0.01), 0.01, Vec2::Zero(), 0, 0, m});
    w.add_disc({Vec2(0.22, 0.01), 0.01, Vec2::Zero(), 0, 0, m});
    w.add_disc({Vec2(0.9, 0.02), 0.01, Vec2(2.0, 0.0), 0, 0, m});
    w.add_disc({Vec2(0.92, 0.02), 0.01, Vec2(2.0, 0.0), 0, 0, m});
    add_ledge(w);
    w.add_bond(0, 1);
    w.add_bond(2, 3);
    w.finalize();
    w.set_dt(2e-5);
    const double e0 = w.energy().balance();
    w.run(30000);
    ASSERT_EQ(w.lost_discs().size(), 2u);
    EXPECT_EQ(w.bonds_at_start(), 2u);
    EXPECT_EQ(w.bonds().size(), 1u);
    EXPECT_EQ(w.bonds_lost_with_discs(), 1u);
    EXPECT_EQ(w.bond_breaks().size(), 0u);
    EXPECT_NEAR(w.energy().balance(), e0, 1e-3 * std::abs(e0));
}

// Two bonded discs in a world without walls fly apart once the bond breaks (issue 48, row 4):
// with the default domain (their box padded by 0.5 m) both are taken out and the run ends
// saying so, not "rest"; world.domain gives the box, and one that does not hold a disc at
// t = 0, or has its corners the wrong way round, is refused naming the key.
TEST(LostDiscs, EveryDiscGoneEndsTheRunSayingSo) {
    auto scenario = [](const std::string& extra) {
        Scenario s = parse_scenario("[world]\ngravity = [0.0, 0.0]\n" + extra +
                                        "\n[cohesion]\nenabled = true\nmodulus = 1e6\nmax_strain = 0.01\nbonds = [[0, 1]]\n"
                                        "[stop]\nt_max = 1.0\n[output]\nsnapshot_interval = 0\n"
                                        "[[discs]]\nposition = [0.0, 0.0]\nradius = 0.01\nvelocity = [-2.0, 0.0]\n"
                                        "[[discs]]\nposition = [0.02, 0.0]\nradius = 0.01\nvelocity = [2.0, 0.0]\n",
                                    "pair.toml");
        finish_scenario(s);
        return s;
    };
    const fs::path dir = temp_dir("all-lost");
    const RunSummary gone = run_scenario(scenario(""), {dir.string(), false, {}});
    EXPECT_EQ(gone.stop_reason, "all discs left the domain");
    EXPECT_EQ(gone.lost_discs, 2);
    EXPECT_LT(gone.t_end, 0.3);  // 0.5 m at 2 m/s
    EXPECT_NE(read_file(dir / "summary.json").find("\"stop_reason\": \"all discs left the domain\""), std::string::npos);
    fs::remove_all(dir);
    // a box 5 m either side: still flying at t_max
    const RunSummary kept = run_scenario(scenario("domain = [[-5.0, -1.0], [5.0, 1.0]]"), {dir.string(), false, {}});
    EXPECT_EQ(kept.stop_reason, "t_max");
    EXPECT_EQ(kept.lost_discs, 0);
    EXPECT_NE(read_file(dir / "scenario.toml").find("domain = [[-5.0, -1.0], [5.0, 1.0]]"), std::string::npos);
    fs::remove_all(dir);
    demlab::test::expect_refused([&] { scenario("domain = [[0.01, -1.0], [5.0, 1.0]]"); }, {"world.domain", "discs[0]", "outside"});
    demlab::test::expect_refused([&] { scenario("domain = [[5.0, 1.0], [-5.0, -1.0]]"); }, {"world.domain", "lower left"});
    demlab::test::expect_refused([&] { scenario("domain = [[-5.0, -1.0]]"); }, {"world.domain", "1 point;"});
}
