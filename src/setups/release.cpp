#include "setups/release.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <random>
#include <sstream>
#include <unordered_map>

#include "core/csv.h"
#include "core/error.h"
#include "core/fileio.h"
#include "setups/setup.h"
#include "core/interrupt.h"
#include "core/progress.h"
#include "core/validate.h"
#include "dem/space_order.h"
#include "dem/world.h"
#include "setups/settle_loop.h"

namespace demlab {

long release_count(double area, double porosity, double r_min, double r_max) {
    const double r_mean = 0.5 * (r_min + r_max);
    return std::lround(area * (1.0 - porosity) / (kPi * r_mean * r_mean));
}

namespace {

// Uniform in [0, 1) from the top 53 bits: the same numbers on every platform.
double uniform01(std::mt19937_64& rng) { return double(rng() >> 11) * 0x1.0p-53; }

// A convex polygon (the release box), counter-clockwise or not.
struct Polygon {
    std::vector<Vec2> v;
    double area() const {
        double a = 0;
        for (size_t i = 0; i < v.size(); ++i) a += cross(v[i], v[(i + 1) % v.size()]);
        return 0.5 * std::abs(a);
    }
    // distance from p to the nearest edge, positive inside
    double inset(const Vec2& p) const {
        Vec2 g = Vec2::Zero();
        for (const Vec2& q : v) g += q;
        g /= double(v.size());
        double d = INFINITY;
        for (size_t i = 0; i < v.size(); ++i) {
            const Vec2 a = v[i], b = v[(i + 1) % v.size()];
            const Vec2 n = perp((b - a).normalized());
            const double side = (g - a).dot(n) > 0 ? 1.0 : -1.0;
            d = std::min(d, side * (p - a).dot(n));
        }
        return d;
    }
    Vec2 sample(std::mt19937_64& rng) const {
        Vec2 lo = v[0], hi = v[0];
        for (const Vec2& q : v) {
            lo = lo.cwiseMin(q);
            hi = hi.cwiseMax(q);
        }
        while (true) {
            // y is drawn first: the order the releases (and the references) were made with, once
            // left to the compiler's order of a call's arguments (GCC's: the last first)
            const double uy = uniform01(rng), ux = uniform01(rng);
            const Vec2 p(lo.x() + (hi.x() - lo.x()) * ux, lo.y() + (hi.y() - lo.y()) * uy);
            if (inset(p) >= 0) return p;
        }
    }
};

// Random sequential addition of discs of the given radii (scaled by s) without overlap.
std::vector<Vec2> place_without_overlap(const Polygon& tri, const std::vector<double>& radius, double s,
                                        std::mt19937_64& rng) {
    const double cell = 2.0 * s * *std::max_element(radius.begin(), radius.end());
    std::unordered_map<long long, std::vector<int>> grid;
    auto key = [&](long long ix, long long iy) { return ix * 1000003LL + iy; };
    std::vector<Vec2> pos(radius.size());
    for (size_t i = 0; i < radius.size(); ++i) {
        const double ri = s * radius[i];
        bool placed = false;
        for (int attempt = 0; attempt < 20000 && !placed; ++attempt) {
            const Vec2 p = tri.sample(rng);
            if (tri.inset(p) < ri) continue;
            const long long ix = (long long)std::floor(p.x() / cell), iy = (long long)std::floor(p.y() / cell);
            bool free = true;
            for (long long dx = -1; dx <= 1 && free; ++dx)
                for (long long dy = -1; dy <= 1 && free; ++dy) {
                    auto it = grid.find(key(ix + dx, iy + dy));
                    if (it == grid.end()) continue;
                    for (int j : it->second)
                        if ((pos[size_t(j)] - p).norm() < ri + s * radius[size_t(j)]) {
                            free = false;
                            break;
                        }
                }
            if (!free) continue;
            pos[i] = p;
            grid[key(ix, iy)].push_back(int(i));
            placed = true;
        }
        if (!placed)
            throw RunError("release generation: could not place disc " + std::to_string(i) + " of " +
                           std::to_string(radius.size()) + " without overlap (the box is too small for the discs)");
    }
    return pos;
}

}  // namespace

namespace {

// The generation is not checkpointed (minutes at scale 4): a signal ends it
// here, and `demlab resume` starts the run again (the seed gives the same mass).
// Settling steps at most: the real sand size (145,615 discs) settles in about 3e6.
constexpr double kMaxSettleSteps = 1e8;

// How many discs lie with their centre more than their radius beyond an edge of the box (the
// side facing away from `centroid`), and the first of them; beyond the lid only by more than
// lid_heave as well (a negative lid_heave: the lid's side is open).
size_t count_outside_box(const ReleaseBox& box, const Vec2& centroid, const std::vector<Vec2>& pos,
                         const std::vector<double>& radius, size_t& first, double lid_heave = -1.0) {
    size_t out = 0;
    for (size_t i = 0; i < pos.size(); ++i) {
        bool beyond = false;
        for (size_t k = 0; k < box.walls.size() && !beyond; ++k) {
            const bool lid = int(k) == box.lid;
            if (lid && lid_heave < 0.0) continue;
            const Vec2 a = box.walls[k].p0, n = perp((box.walls[k].p1 - a).normalized());
            const double inward = (centroid - a).dot(n) > 0.0 ? 1.0 : -1.0;
            beyond = !(inward * (pos[i] - a).dot(n) >= -radius[i] - (lid ? lid_heave : 0.0));
        }
        if (beyond && out++ == 0) first = i;
    }
    return out;
}

Vec2 centroid_of(const std::vector<Vec2>& v) {
    Vec2 c = Vec2::Zero();
    for (const Vec2& q : v) c += q;
    return v.empty() ? c : Vec2(c / double(v.size()));
}

// A settled mass lies in its box. The second settling phase goes without the lid (the box's
// top), so the mass in a polygon whose top slopes towards a low side pours out over that side
// before t = 0, and the run would start from discs anywhere, under the ground too. A disc whose
// centre lies more than its radius beyond an edge that stays (the lid's side is open: the mass
// may heave above it once it is gone) is refused, naming the lid.
void refuse_mass_outside_box(const Scenario& s, const ReleaseBox& box, const Polygon& poly, const std::vector<Vec2>& pos,
                             const std::vector<double>& radius) {
    size_t first = 0;
    const size_t out = count_outside_box(box, centroid_of(poly.v), pos, radius, first);
    if (out == 0) return;
    const std::string what = s.terrain.enabled ? "terrain.release's polygon" : "the release box";
    std::string lid;
    if (box.lid >= 0) {
        const Vec2 a = box.walls[size_t(box.lid)].p0, b = box.walls[size_t(box.lid)].p1;
        lid = "; the mass settles last without its top, the edge from [" + format_number(a.x()) + ", " + format_number(a.y()) +
              "] to [" + format_number(b.x()) + ", " + format_number(b.y()) +
              "], and must not pour out over the sides below it: give the polygon a level top, or sides that rise above "
              "the top's lower end";
    }
    throw InputError(s.source + ": " + std::to_string(out) + " of the " + std::to_string(pos.size()) +
                     " discs of the release mass left " + what + " while it settled (disc " + std::to_string(first) +
                     " at [" + format_number(pos[first].x()) + ", " + format_number(pos[first].y()) + "])" + lid);
}

// While the mass restiffens without friction and without its lid it is a fluid: it heaves as
// the soft overlaps relax, its surface levels, and discs that rise above the lid's line pour
// over the box's top corners and fall out of it (geometry A at scale 20: 21 of 364 discs, for
// a third of the seeds, were refused as outside the box). A cap two of the largest radii above
// the lid's line, closed at both ends, lets the mass heave and keeps it in; the frictional
// stage then goes without it.
void add_lid_cap(World& w, const WallDef& lid, const Vec2& inside, const std::vector<double>& radius) {
    const double h = 2.0 * *std::max_element(radius.begin(), radius.end());
    Vec2 n = perp((lid.p1 - lid.p0).normalized());
    if (n.dot(inside - lid.p0) > 0.0) n = -n;  // away from the mass
    const Vec2 a = lid.p0 + h * n, b = lid.p1 + h * n;
    const std::pair<Vec2, Vec2> pieces[3] = {{lid.p0, a}, {a, b}, {b, lid.p1}};
    for (const auto& [p, q] : pieces) {
        WallDef cap = lid;
        cap.name = lid.name + " (cap)";
        cap.p0 = p;
        cap.p1 = q;
        w.add_wall(cap);
    }
}

// an interrupt during the generation ends it (not checkpointed)
const char* const kGenerationInterrupted = "stopped during the release generation, which is not checkpointed";
}  // namespace

// The radius expansion: the placed discs grown from s0 of their radii to their full size in
// stages, frictionless, without gravity, heavily damped, rotation locked; their positions then.
std::vector<Vec2> expand_to_size(const Scenario& s, const ReleaseBox& box, const std::vector<double>& radius,
                                 const std::vector<Vec2>& start, double s0, Progress& progress) {
    // --- radius expansion: frictionless, no gravity, heavily damped, rotation locked
    WorldDef gen;
    gen.threads = s.world.threads;  // the same bits for any count
    gen.space_order = SpaceOrder::Off;  // the placed discs' numbers are the mass' (order_in_space)
    gen.gravity = Vec2::Zero();
    gen.rotation.model = 1;
    gen.damping.beta_n = 0.5;
    gen.damping.beta_s = 0.0;
    gen.damping.local_alpha = 0.7;
    gen.max_overlap_ratio = 2.0;
    gen.timestep.safety = 0.8;
    World expand(gen);
    for (MaterialDef slick : scenario_materials(s)) {  // the discs' and the walls', frictionless
        slick.friction = 0.0;
        expand.add_material(slick);
    }
    const int mat = kDiscMaterial;
    for (size_t i = 0; i < radius.size(); ++i) expand.add_disc({start[i], s0 * radius[i], Vec2::Zero(), 0, 0, mat});
    for (const WallDef& w : box.walls) expand.add_wall(w);
    expand.finalize();
    // through the run loop: each stage's radii set before its steps, then 3000 steps to relax
    // at full size
    const int stages = 60, steps_per_stage = 150, relax_steps = 3000;
    int stage = 1;
    auto grow = [&] {
        const double sk = s0 + (1.0 - s0) * double(stage) / stages;
        for (size_t i = 0; i < radius.size(); ++i) expand.set_radius(int(i), sk * radius[i]);
        expand.refresh_dashpots();
    };
    grow();
    step_through_loop(expand, s, kGenerationInterrupted, [&]() -> std::string {
        const long n = expand.step_count();
        if (n == long(stages) * steps_per_stage + relax_steps) return "expanded";
        if (stage > stages || n != long(stage) * steps_per_stage) return "";
        progress.update(0.5 * double(stage) / stages, n);
        if (++stage <= stages) grow();
        return "";
    });
    return expand.positions();
}

namespace {
// The settling's stages, in order (settle_release).
enum class Stage { Compaction, Restiffen, Friction };
struct SettleStage {
    Stage stage;
    double stiffness_factor;  // of the materials' kn and ks
    double ratio_factor;      // of release.settle_ratio, where the stage stops
    double ramp_to = 0.0;     // > 0: the stiffness factor raised from stiffness_factor to this
    long ramp_steps = 0;      // over these steps
};

// With release.settle_ramp = "on" the compaction runs at a quarter of the factor (steps twice as
// large) and the stiffness comes back by fours, one frictionless stage each. Every stage
// starts from rest and its jump of stiffness sets off waves that must die out, some
// 6,000-10,000 steps at scale 4 whatever the jump, so one stage at the real stiffness after
// a compaction at 1/16 had to relax overlaps four times larger for 38,000 steps; by fours,
// with the intermediate stages stopped at 50 times the settle ratio (they only hand on a
// closer packing), geometry A at scale 4 settles in 32,600 steps instead of 43,200, at
// scale 2 in 74,400 instead of 113,600 (the compaction 81,800 -> 30,000), porosity inside
// the mass 0.1583 -> 0.1578 and 0.1578 -> 0.1574. Stopping the same stages at 10 times
// the ratio, or ramping by twos, gave 44,600-45,400 at scale 4; the compaction at 1/64,
// 76,000 at scale 2 (porosity 0.1566).
//
// With release.settle_ramp = "smooth" (and "auto" above kSettleRampDiscs) the compaction runs
// at a quarter of the factor as with "on", and one frictionless stage without the lid then
// raises the stiffness continuously to the real one. Each of "on"'s stages starts at four
// times the last one's stiffness from the same positions: the contact forces jump fourfold
// (the unbalanced-force ratio 0.67 at the stage's start) and the mass rings through several
// periods of its slowest mode. Raised over two of those periods, the stiffness keeps the mass
// near its equilibrium while its overlaps shrink: geometry A's restiffening (after the same
// compaction as "on"'s) at scale 8 6,600 -> 4,800 steps, at scale 4 15,200 -> 12,200, at scale
// 2 33,200 -> 24,600. Over one period 5,800 and 13,400, over three 5,600 and 10,800 (scales 8
// and 4): the counts move by a thousand or two with any change. In this stage more local
// damping (0.5, 0.7, 0.9) took 12,000, 19,400 and 65,600 steps at scale 4, less (0, 0.1, 0.2)
// 10,600-11,600; every velocity scaled by 0.3-0.9 at each check (a viscous damping) kept the
// ratio above 10 times the settle ratio for 150,000 steps: a frictionless mass settles by
// creeping into its gaps, and damping slows the creep. That stage being frictionless too,
// the compaction hands on at 20 times the settle ratio: its tail's creep goes on under the
// ramp (at 10 times, the compaction's last 30,000 of 81,800 steps at scale 1 took the ratio
// from 0.009 to 0.005). Settling steps against "on", geometry A: scale 8 15,400 -> 10,800,
// scale 4 32,600 -> 25,400, scale 2 74,400 -> 55,800 (seeds 2 and 3: 76,800 -> 58,600 and
// 78,400 -> 60,200; at 10 times 65,800, 69,000 and 73,000), porosity inside the mass
// 0.0003-0.0005 higher; scale 1 in docs/flume.md.
//
// The slowest mode (the mass' height ringing on its floor) shows in the ratio's oscillation: a
// period of about 2,000 steps at scale 4 (9,101 discs) and 4,000 at scale 2 (36,404). In steps
// it grows with the mass' height in discs, sqrt(N) (the period goes as that height times
// sqrt(m / k), the step as sqrt(m / k)): about 21 sqrt(N) steps.
constexpr double kSlowestModeStepsPerSqrtDisc = 21.0;
constexpr double kSmoothRampPeriods = 2.0;

std::vector<SettleStage> settle_stages(const ReleaseDef& rd, size_t discs) {
    const bool large = long(discs) > kSettleRampDiscs;
    const bool smooth = rd.settle_stiffness_factor < 1.0 && (rd.settle_ramp == "smooth" || (rd.settle_ramp == "auto" && large));
    const bool ramp = rd.settle_stiffness_factor < 1.0 && rd.settle_ramp == "on";
    std::vector<SettleStage> stages;
    if (smooth) {
        const double f = 0.25 * rd.settle_stiffness_factor;
        const long ramp_steps = std::lround(kSmoothRampPeriods * kSlowestModeStepsPerSqrtDisc * std::sqrt(double(discs)));
        stages.push_back({Stage::Compaction, f, 20.0});
        stages.push_back({Stage::Restiffen, f, 10.0, 1.0, ramp_steps});
        stages.push_back({Stage::Friction, 1.0, 1.0});
        return stages;
    }
    if (ramp) {
        stages.push_back({Stage::Compaction, 0.25 * rd.settle_stiffness_factor, 10.0});
        for (double f = rd.settle_stiffness_factor; f < 1.0; f *= 4.0) stages.push_back({Stage::Restiffen, f, 50.0});
    } else {
        stages.push_back({Stage::Compaction, rd.settle_stiffness_factor, 10.0});
    }
    if (rd.settle_stiffness_factor != 1.0) stages.push_back({Stage::Restiffen, 1.0, 10.0});
    stages.push_back({Stage::Friction, 1.0, 1.0});
    return stages;
}
}  // namespace

// The reduced discs settled under gravity (release.h): their positions, and in m the ratio
// reached, the lid's load, whether they settled, the time and steps it took.
void settle_release(const Scenario& s, const ReleaseBox& box, std::vector<Vec2>& positions, const std::vector<double>& radius,
                    ReleaseMass& m, Progress& progress) {
    const ReleaseDef& rd = s.release;
    // --- radius reduction, then settling under gravity: first frictionless, so the mass
    // compacts below the lid as far as it can (frictional discs jam looser than the
    // generated density and would stay pressed against the lid), then with the real
    // friction until it is at rest
    WorldDef settle = s.world;
    settle.space_order = SpaceOrder::Off;  // the mass keeps the numbers it settles with (layers, grid)
    settle.rotation.model = 1;  // settling is quasi-static; rotation does not change the state reached
    // the dashpots lagged (release.settle_dashpots): a centred step is a second pass over the
    // contacts and costs about twice a lagged one, which with the damping correction takes
    // steps 0.87 times as long; the mass settles into the same packing (geometry A at scale 4:
    // 8.8 -> 5.9 s, porosity inside the mass 0.1585 and 0.1583; at scale 2: 98 -> 55 s)
    if (rd.settle_dashpots == "lagged") {
        settle.timestep.dashpots = DashpotScheme::Lagged;
        settle.timestep.damping_correction = true;
    }
    settle.damping.local_alpha = rd.settle_alpha;
    // no tensile contact forces while settling: with local damping, PFC mode 0 chatters
    settle.damping.dp_mode = DashpotMode::NoTension;
    double settled_time = 0.0;
    long settled_steps = 0;
    // The stages: the compaction (frictionless, with the lid, at release.settle_stiffness_factor
    // of the stiffnesses); then, when it ran soft, frictionless at the real stiffness without
    // the lid, so that the soft compaction's larger overlaps relax while the discs still slide
    // along the walls (with friction at once the walls' friction locks them in: the dam-break
    // column of 1,722 N/m stood on its floor with 2,590 N/m at t = 0; relaxed under the lid,
    // with 1,810 N/m, the lid's release locking in the rest); then with the real friction,
    // without the lid, until at rest. The frictionless stages share the first half of
    // release.settle_max_time, the frictional one has the second.
    const std::vector<SettleStage> stages = settle_stages(rd, radius.size());
    const double t_half = 0.5 * rd.settle_max_time;
    double t_frictionless = 0.0;  // the frictionless stages' time so far
    for (const SettleStage& def : stages) {
        const Stage stage = def.stage;
        const bool frictionless = stage != Stage::Friction;
        const double t_stage = frictionless ? t_half - t_frictionless : t_half;
        if (!(t_stage > 0.0)) continue;  // the compaction took the first half
        const int phase = frictionless ? 0 : 1;  // the progress bar's quarter
        // Local damping in both phases (release.settle_alpha, settle_friction_alpha). The
        // compaction is a slow flow of frictionless discs: more damping slows it (geometry A at
        // scale 4: 117,600 steps at 0.7, 22,800 at 0.3, with f = 0.25). With friction, a light
        // local damping removes the slow modes the dashpots hardly touch: 25,600 steps on the
        // dashpots alone, 9,600 at 0.2; at 0.7 the mass chatters (the ratio stays at 0.4 at
        // scale 8).
        settle.damping.local_alpha = frictionless ? rd.settle_alpha : rd.settle_friction_alpha;
        World w(settle);
        for (MaterialDef mat_phase : scenario_materials(s)) {  // the discs' and the walls'
            if (frictionless) mat_phase.friction = 0.0;
            // the frictionless compaction is quasi-static: softer contacts (overlaps 1/f times
            // larger: at f = 0.25 about a thousandth of a radius at the bottom of geometry A's
            // mass) let it take steps 1/sqrt(f) times larger
            if (def.stiffness_factor != 1.0) {
                mat_phase.kn *= def.stiffness_factor;
                mat_phase.ks *= def.stiffness_factor;
            }
            w.add_material(mat_phase);
        }
        const int mat2 = kDiscMaterial;
        for (size_t i = 0; i < radius.size(); ++i) w.add_disc({positions[i], radius[i], Vec2::Zero(), 0, 0, mat2});
        const std::vector<WallDef>& walls = box.walls;
        // the lid only holds the mass while it compacts; the later stages go without it, so
        // prestress locked in by the lid (a small mass of large discs jams looser than the
        // generated density) is released gently here rather than at the release
        int lid_index = -1;
        for (int k = 0; k < int(walls.size()); ++k) {
            if (k == box.lid) {
                if (stage == Stage::Restiffen) add_lid_cap(w, walls[size_t(k)], centroid_of(positions), radius);
                if (stage != Stage::Compaction) continue;
                lid_index = int(w.wall_count());
            }
            w.add_wall(walls[size_t(k)]);
        }
        w.finalize();
        SettleRule rule;
        rule.t_end = t_stage;
        // the frictionless stages only compact: they may stop at ten times the final ratio
        rule.ratio = def.ratio_factor * rd.settle_ratio;
        rule.interrupted = kGenerationInterrupted;
        // a smooth ramp (settle_stages) raises the stiffness at every check, geometrically from
        // the stage's factor to ramp_to over ramp_steps (jumps of 16^(200 / ramp_steps): 1.15 at
        // scale 4, 1.04 at scale 1); the stage may stop from the check after the last jump
        rule.min_steps = def.ramp_steps > 0 ? def.ramp_steps + 1 : 0;
        double stiffness_now = def.stiffness_factor;
        rule.on_check = [&](double t, long steps, double) {
            if (def.ramp_to > 0.0 && stiffness_now != def.ramp_to) {
                const double x = std::min(1.0, double(steps) / double(def.ramp_steps));
                const double next = x >= 1.0 ? def.ramp_to : def.stiffness_factor * std::pow(def.ramp_to / def.stiffness_factor, x);
                w.scale_stiffness(next / stiffness_now);
                stiffness_now = next;
            }
            // a step so small that settling would not end in any time (an absurd stiffness or
            // density) is refused at once instead of running for ever
            if (steps <= 200 && (t_stage - t) / w.dt() > kMaxSettleSteps)
                throw RunError(s.source + ": settling the release would take " + format_number((t_stage - t) / w.dt()) +
                               " steps of " + format_number(w.dt()) + " s (more than " + format_number(kMaxSettleSteps) +
                               "): material.kn / ks and material.density give an absurdly small time step");
            const double t_done = frictionless ? t_frictionless + t : t;
            progress.update(0.5 + 0.25 * phase + 0.25 * std::min(1.0, t_done / t_half), steps);
        };
        const SettleResult settled = settle_through_loop(w, s, rule);
        m.settle_ratio = settled.ratio;
        if (stage == Stage::Compaction) {  // the lid's load at the compaction's end
            double weight = 0;
            for (double mi : w.masses()) weight += mi * s.world.gravity.norm();
            // (a mass without weight, world.gravity = [0, 0], puts no load on the lid: 0, not
            // 0 / 0, which release.csv's reader would refuse)
            m.lid_load_fraction = lid_index >= 0 && weight > 0.0 ? w.wall_force(lid_index).norm() / weight : 0.0;
        }
        if (frictionless) t_frictionless += w.time();
        positions = w.positions();
        settled_time += w.time();
        settled_steps += w.step_count();
        if (!frictionless) m.settled = settled.settled;
    }
    m.settle_time = settled_time;
    m.settle_steps = settled_steps;
}

// The settled mass's porosity over its box, and each disc's layer and grid cell (the renderer's
// colours).
void mark_layers(ReleaseMass& m, const ReleaseDef& rd) {
    double solid_settled = 0.0;
    double y_min = INFINITY;
    Vec2 lo(INFINITY, INFINITY);
    for (size_t i = 0; i < m.pos.size(); ++i) {
        solid_settled += kPi * m.radius[i] * m.radius[i];
        y_min = std::min(y_min, m.pos[i].y());
        lo = lo.cwiseMin(m.pos[i]);
    }
    m.porosity_settled = 1.0 - solid_settled / m.box_area;
    m.layer.resize(m.pos.size());
    m.grid.resize(m.pos.size());
    for (size_t i = 0; i < m.pos.size(); ++i) {
        m.layer[i] = int(std::floor((m.pos[i].y() - y_min) / rd.layer_height));
        const int gx = int(std::floor((m.pos[i].x() - lo.x()) / rd.grid_cell));
        const int gy = int(std::floor((m.pos[i].y() - lo.y()) / rd.grid_cell));
        m.grid[i] = gy * 1000 + gx;  // the renderer decodes the cell as (grid % 1000, grid / 1000)
    }
}

ReleaseMass generate_release(const Scenario& s) {
    const auto t0 = std::chrono::steady_clock::now();
    const ReleaseDef& rd = s.release;
    const ReleaseBox box = make_setup(s)->release_box();
    const Polygon tri{box.polygon};
    ReleaseMass m;
    m.box_area = tri.area();
    m.porosity_target = rd.porosity;
    // the count before anything is allocated: 10 um radii over a terrain's release polygon
    // asked for 1e11 discs and ended in std::bad_alloc
    const double r_mean = 0.5 * (rd.r_min + rd.r_max);
    const double count = m.box_area * (1.0 - rd.porosity) / (kPi * r_mean * r_mean);
    if (!(count <= kMaxReleaseDiscs))
        throw InputError(s.source + ": release: the release area (" + format_number(m.box_area) + " m2) would hold " +
                         format_number(count) + " discs of radii release.r_min = " + format_number(rd.r_min) +
                         " m to release.r_max = " + format_number(rd.r_max) + " m (release.porosity = " +
                         format_number(rd.porosity) + "), more than " + format_number(kMaxReleaseDiscs) +
                         ": use larger radii (release.scale, release.r_min, release.r_max) or a smaller area");
    const long n = release_count(m.box_area, rd.porosity, rd.r_min, rd.r_max);
    if (n < 1) throw InputError(s.source + ": release: the box holds no disc of these radii");

    std::mt19937_64 rng(s.seed);
    std::vector<double> radius(static_cast<size_t>(n), 0.0);
    for (double& r : radius) r = rd.r_min + (rd.r_max - rd.r_min) * uniform01(rng);
    double solid = 0.0;
    for (double r : radius) solid += kPi * r * r;
    // place at an area fraction of 0.35, where random addition is quick, then expand
    const double s0 = std::min(1.0, std::sqrt(0.35 * m.box_area / solid));
    std::vector<Vec2> start = place_without_overlap(tri, radius, s0, rng);
    // Space order before settling (release.space_order). Discs placed at random get numbers
    // at random, and the force pass then runs as one range: one thread, and at large N a
    // pair's two discs far apart in memory. The numbering decides the order in which each
    // disc sums its terms, so it changes the settled mass' bits: auto leaves the masses of
    // up to kSpaceOrderDiscs discs (scale 20, the regression references) as they were; from
    // scale 4 up the settling runs on every thread (geometry A at scale 4 on 2 threads:
    // 56.6 s numbered as placed, 26.2 s in space order, porosity inside the mass 0.15854
    // and 0.15856).
    if (rd.space_order == "on" || (rd.space_order == "auto" && n > kSpaceOrderDiscs)) {
        ReleaseMass placed;
        placed.pos = std::move(start);
        placed.radius = std::move(radius);
        order_in_space(placed, 4.0 * rd.r_max);
        start = std::move(placed.pos);
        radius = std::move(placed.radius);
    }

    Progress progress(1.0, "of generation");
    std::vector<Vec2> positions = expand_to_size(s, box, radius, start, s0, progress);
    m.porosity_generated = 1.0 - solid / m.box_area;

    const double shrink = 1.0 - rd.radius_reduction;
    for (double& r : radius) r *= shrink;
    settle_release(s, box, positions, radius, m, progress);
    progress.finish();
    refuse_mass_outside_box(s, box, tri, positions, radius);
    m.pos = positions;
    m.radius = radius;
    mark_layers(m, rd);
    m.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return m;
}

void order_in_space(ReleaseMass& m, double strip) {
    const size_t n = m.pos.size();
    const std::vector<size_t> order = space_order(m.pos, strip);
    if (order.empty()) return;
    auto permute = [&](auto& v) {
        if (v.size() != n) return;
        auto old = v;
        for (size_t k = 0; k < n; ++k) v[k] = old[order[k]];
    };
    permute(m.pos);
    permute(m.radius);
    permute(m.layer);
    permute(m.grid);
}

void save_release(const ReleaseMass& m, const std::string& path) {
    std::ostringstream o;
    o.precision(17);
    o << "# demlab release mass: a settled mass to start runs from (--release-from)\n";
    o << "# n " << m.pos.size() << "\n# box_area_m2 " << m.box_area << "\n# porosity_target " << m.porosity_target
      << "\n# porosity_generated " << m.porosity_generated << "\n# porosity_settled " << m.porosity_settled
      << "\n# settle_time_s " << m.settle_time << "\n# settle_steps " << m.settle_steps << "\n# settle_ratio "
      << m.settle_ratio << "\n# settled " << (m.settled ? 1 : 0) << "\n# lid_load_fraction " << m.lid_load_fraction
      << "\n";
    for (const auto& w : m.box_walls)
        o << "# wall " << w[0].x() << ' ' << w[0].y() << ' ' << w[1].x() << ' ' << w[1].y() << '\n';
    o << "id,x_m,y_m,r_m,layer,grid\n";
    for (size_t i = 0; i < m.pos.size(); ++i)
        o << i << ',' << m.pos[i].x() << ',' << m.pos[i].y() << ',' << m.radius[i] << ',' << m.layer[i] << ','
          << m.grid[i] << '\n';
    write_file_atomic(path, o.str());
}

void refuse_overlapping_discs(const ReleaseMass& m, double ratio, const std::string& path) {
    const size_t n = m.pos.size();
    std::vector<size_t> order(n);
    for (size_t i = 0; i < n; ++i) order[i] = i;
    // a sweep along x: only discs whose x ranges meet are compared
    std::sort(order.begin(), order.end(), [&](size_t a, size_t b) {
        const double la = m.pos[a].x() - m.radius[a], lb = m.pos[b].x() - m.radius[b];
        return la < lb || (la == lb && a < b);
    });
    for (size_t a = 0; a < n; ++a) {
        const size_t i = order[a];
        for (size_t b = a + 1; b < n; ++b) {
            const size_t j = order[b];
            if (m.pos[j].x() - m.radius[j] > m.pos[i].x() + m.radius[i]) break;
            const double overlap = m.radius[i] + m.radius[j] - (m.pos[j] - m.pos[i]).norm();
            if (overlap > ratio * std::min(m.radius[i], m.radius[j]))
                throw InputError(path + ": discs " + std::to_string(std::min(i, j)) + " and " + std::to_string(std::max(i, j)) +
                                 " (rows of the file, from 0) overlap by " + format_number(overlap) +
                                 " m, more than world.max_overlap_ratio = " + format_number(ratio) +
                                 " of the smaller radius: not a settled release mass");
        }
    }
}

void refuse_loaded_mass_outside_box(const ReleaseBox& box, const ReleaseMass& m, const std::string& path) {
    // a settled mass may heave a little above its lid once the lid is gone (a few mm at scale
    // 20), never by more than two of its largest discs
    double r_max = 0.0;
    for (double r : m.radius) r_max = std::max(r_max, r);
    size_t first = 0;
    const size_t out = count_outside_box(box, centroid_of(box.polygon), m.pos, m.radius, first, 4.0 * r_max);
    if (out == 0) return;
    throw InputError(path + ": " + std::to_string(out) + " of its " + std::to_string(m.pos.size()) +
                     " discs lie outside this scenario's release box (the first: disc row " + std::to_string(first) + ", counted from 0, at [" +
                     format_number(m.pos[first].x()) + ", " + format_number(m.pos[first].y()) +
                     "], more than its radius beyond an edge); a saved mass must lie in the box it settled in");
}

ReleaseMass load_release(const std::string& path) {
    std::istringstream in(read_input_file(path, kMaxTableBytes, "release mass file"));
    ReleaseMass m;
    std::string line;
    long lineno = 0, rows_declared = -1;
    bool header = false;
    auto at = [&](long l) { return path + ":" + std::to_string(l) + ": "; };
    while (std::getline(in, line)) {
        ++lineno;
        if (!line.empty() && line.back() == '\r') line.pop_back();  // (a copy with Windows line ends)
        if (line.empty()) continue;
        if (line[0] == '#') {
            std::istringstream h(line.substr(1));
            std::string k;
            double v = 0;
            if (line.rfind("# wall ", 0) == 0) {
                // four numbers, each whole
                std::istringstream wl(line.substr(7));
                std::vector<double> c;
                bool numbers = true;
                for (std::string cell; wl >> cell;) {
                    double x = 0.0;
                    numbers = numbers && parse_finite(cell, x);
                    c.push_back(x);
                }
                if (c.size() != 4 || !numbers)
                    throw InputError(path + ":" + std::to_string(lineno) + ": expected '# wall x0 y0 x1 y1' (four numbers, m)");
                m.box_walls.push_back({Vec2(c[0], c[1]), Vec2(c[2], c[3])});
                continue;
            }
            if (h >> k) {
                static const char* const kKnown[] = {"n", "box_area_m2", "porosity_target", "porosity_generated", "porosity_settled",
                                                     "settle_time_s", "settle_steps", "settle_ratio", "settled", "lid_load_fraction"};
                const bool known = std::find(std::begin(kKnown), std::end(kKnown), k) != std::end(kKnown);
                std::string value;
                h >> value;
                if (!known) continue;  // (other comments are free)
                if (!parse_finite(value, v))
                    throw InputError(at(lineno) + "'# " + k + "' needs a finite number, not '" + value + "'");
                if (k == "n") {
                    if (!(v >= 1.0 && v <= kMaxReleaseDiscs && v == std::floor(v)))
                        throw InputError(at(lineno) + "'# n " + value + "' is not a disc count");
                    rows_declared = long(v);
                }
                if (k == "box_area_m2") m.box_area = v;
                else if (k == "porosity_target") m.porosity_target = v;
                else if (k == "porosity_generated") m.porosity_generated = v;
                else if (k == "porosity_settled") m.porosity_settled = v;
                else if (k == "settle_time_s") m.settle_time = v;
                else if (k == "settle_steps") m.settle_steps = long(v);
                else if (k == "settle_ratio") m.settle_ratio = v;
                else if (k == "settled") m.settled = v != 0;
                else if (k == "lid_load_fraction") m.lid_load_fraction = v;
            }
            continue;
        }
        if (!header) {
            if (line.rfind("id,x_m,y_m,r_m,layer,grid", 0) != 0)
                throw InputError(path + ":" + std::to_string(lineno) + ": expected the header 'id,x_m,y_m,r_m,layer,grid'");
            header = true;
            continue;
        }
        std::istringstream row(line);
        std::string cell;
        std::vector<double> v;
        // every cell a number, all of it ("0.0976x" is not 0.0976)
        while (std::getline(row, cell, ',')) v.push_back(parse_number_cell(cell, path + ":" + std::to_string(lineno)));
        if (v.size() != 6 || !(v[3] > 0) || !std::isfinite(v[1]) || !std::isfinite(v[2]))
            throw InputError(path + ":" + std::to_string(lineno) + ": expected id,x,y,r,layer,grid with r > 0");
        // the layer and grid tags colour the discs: whole numbers from 0 (a NaN or 1e30 would
        // not convert to an int at all)
        for (int c : {4, 5})
            if (!(v[size_t(c)] >= 0.0 && v[size_t(c)] <= 1e9 && v[size_t(c)] == std::floor(v[size_t(c)])))
                throw InputError(at(lineno) + "its " + (c == 4 ? "layer" : "grid") + " '" + format_number(v[size_t(c)]) +
                                 "' is not a whole number from 0 to 1e9");
        m.pos.emplace_back(v[1], v[2]);
        m.radius.push_back(v[3]);
        m.layer.push_back(int(v[4]));
        m.grid.push_back(int(v[5]));
    }
    if (m.pos.empty()) throw InputError(path + ": no discs in the release mass file");
    // a file cut at a line's end reads as a smaller mass: the count it was written with says so
    if (rows_declared >= 0 && long(m.pos.size()) != rows_declared)
        throw InputError(path + ": it has " + std::to_string(m.pos.size()) + " disc rows where its '# n' line says " +
                         std::to_string(rows_declared) + ": the file is cut short or edited");
    return m;
}

}  // namespace demlab
