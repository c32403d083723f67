#include "setups/lattice_release.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <random>

#include "core/error.h"
#include "core/interrupt.h"
#include "core/progress.h"
#include "core/validate.h"
#include "dem/world.h"
#include "setups/settle_loop.h"
#include "setups/release.h"

namespace demlab {

namespace {
// Inside the polygon (even-odd crossings), or within tol of one of its edges.
bool inside_or_on(const std::vector<Vec2>& poly, const Vec2& p, double tol) {
    bool in = false;
    const size_t n = poly.size();
    for (size_t a = 0, b = n - 1; a < n; b = a++) {
        const Vec2 &pa = poly[a], &pb = poly[b];
        const Vec2 e = pb - pa;
        const double t = std::clamp((p - pa).dot(e) / e.squaredNorm(), 0.0, 1.0);
        if ((pa + t * e - p).norm() <= tol) return true;
        if ((pa.y() > p.y()) != (pb.y() > p.y()) && p.x() < pa.x() + (p.y() - pa.y()) / (pb.y() - pa.y()) * e.x()) in = !in;
    }
    return in;
}
}  // namespace

ReleaseMass lattice_mass(const Scenario& s, const std::vector<WallDef>& walls) {
    const LatticeReleaseDef& l = s.lattice_release;
    const double sp = l.spacing, row = 0.5 * std::sqrt(3.0) * sp, tol = 1e-9 * sp;
    const double a = l.angle_deg * kPi / 180.0;
    const Vec2 u(std::cos(a), std::sin(a)), w(-u.y(), u.x());
    // the region's extent in lattice coordinates, one node more on every side
    double u0 = INFINITY, u1 = -INFINITY, w0 = INFINITY, w1 = -INFINITY;
    for (const Vec2& p : l.fill) {
        const Vec2 d = p - l.origin;
        u0 = std::min(u0, d.dot(u));
        u1 = std::max(u1, d.dot(u));
        w0 = std::min(w0, d.dot(w));
        w1 = std::max(w1, d.dot(w));
    }
    // the discs' count from the area before any is made (a node per sp x row of area)
    double area = 0.0;
    for (size_t k = 0, n = l.fill.size(); k < n; ++k) area += cross(l.fill[k], l.fill[(k + 1) % n]);
    area = 0.5 * std::abs(area);
    if (!(area / (sp * row) <= kMaxReleaseDiscs))
        throw InputError(s.source + ": lattice_release: the region (" + format_number(area) + " m2) would hold " +
                         format_number(area / (sp * row)) + " discs at lattice_release.spacing = " + format_number(sp) +
                         " m, more than " + format_number(kMaxReleaseDiscs) +
                         ": use larger discs (lattice_release.r_min, r_max, spacing) or a smaller region");
    const long j0 = long(std::floor(w0 / row)) - 1, j1 = long(std::ceil(w1 / row)) + 1;
    const long i0 = long(std::floor(u0 / sp)) - 2, i1 = long(std::ceil(u1 / sp)) + 2;
    if (double(j1 - j0) * double(i1 - i0) > 5e7)
        throw InputError(s.source + ": lattice_release: the region holds more than 50 million nodes at spacing " +
                         format_number(sp) + " m");
    std::vector<WallGeom> geoms;
    for (const WallDef& wd : walls) geoms.push_back(make_geom(wd));
    std::mt19937_64 rng(s.seed);
    ReleaseMass m;
    for (long j = j0; j <= j1; ++j)
        for (long i = i0; i <= i1; ++i) {
            const double odd = (j % 2 + 2) % 2 == 1 ? 0.5 * sp : 0.0;
            const Vec2 p = l.origin + (double(i) * sp + odd) * u + double(j) * row * w;
            if (!inside_or_on(l.fill, p, tol)) continue;
            const double r = l.r_min + (l.r_max - l.r_min) * (double(rng() >> 11) * 0x1.0p-53);
            bool clear = true;
            // (0.1 % of r of slack: coordinates given to 0.1 mm put a row meant to touch the
            // bed a few hundredths of a millimetre into it)
            for (const WallGeom& g : geoms) clear = clear && (p - closest_point(g, p)).norm() >= r * (1.0 - 1e-3);
            if (!clear) continue;
            m.pos.push_back(p);
            m.radius.push_back(r);
            m.layer.push_back(int(j - j0));
            m.grid.push_back(0);
        }
    if (m.pos.empty()) throw InputError(s.source + ": lattice_release: no node of the lattice lies inside the region and clear of the walls");
    m.settled = true;
    if (l.settle) settle_lattice(s, walls, m);
    return m;
}

// The lattice settled under gravity before t = 0 (COHESION.md section 3, variant C): the
// discs and every wall of the run, those removed at t = 0 (a gate) too, with local damping
// lattice_release.settle_alpha and no tensile dashpot force (mode 1, as the flume's settling),
// rotation locked; settled when the mean unbalanced force falls below
// release.settle_ratio of the mean contact force, refused when it does not within
// release.settle_max_time. Bonds are built afterwards, at t = 0, from the settled positions.
void settle_lattice(const Scenario& s, const std::vector<WallDef>& walls, ReleaseMass& m) {
    const auto t0 = std::chrono::steady_clock::now();
    const ReleaseDef& rd = s.release;
    WorldDef def = s.world;
    def.rotation.model = 1;
    def.space_order = SpaceOrder::Off;  // the lattice keeps its numbers (its layers, its bonds)
    def.damping.local_alpha = s.lattice_release.settle_alpha;
    def.damping.dp_mode = DashpotMode::NoTension;
    World w(def);
    for (const MaterialDef& mt : scenario_materials(s)) w.add_material(mt);
    const int mat = kDiscMaterial;
    for (size_t i = 0; i < m.pos.size(); ++i) w.add_disc({m.pos[i], m.radius[i], Vec2::Zero(), 0, 0, mat});
    for (WallDef wd : walls) {
        wd.remove_at = kNever;  // a gate holds the mass while it settles
        wd.velocity = Vec2::Zero();
        w.add_wall(wd);
    }
    w.finalize();
    Progress progress(rd.settle_max_time, "s of settling");
    SettleRule rule;
    rule.t_end = rd.settle_max_time;
    rule.ratio = rd.settle_ratio;
    rule.interrupted = "stopped while the lattice settled, which is not checkpointed";
    rule.on_check = [&](double t, long steps, double) { progress.update(t, steps); };
    const SettleResult settled = settle_through_loop(w, s, rule);
    m.settle_ratio = settled.ratio;
    const bool done = settled.settled;
    progress.finish();
    if (!done)
        throw RunError(s.source + ": lattice_release.settle: the lattice did not settle within release.settle_max_time = " +
                       format_number(rd.settle_max_time) + " s (unbalanced force ratio " + format_number(m.settle_ratio) +
                       ", asked < release.settle_ratio = " + format_number(rd.settle_ratio) +
                       "); raise settle_max_time, or hold the mass with a wall removed at t = 0");
    m.pos = w.positions();
    m.settle_time = w.time();
    m.settle_steps = w.step_count();
    m.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace demlab
