#include "setups/setup.h"

#include <algorithm>

#include "core/error.h"
#include "core/validate.h"
#include "dem/world.h"

namespace demlab {

ReleaseBox Setup::release_box() const { throw InputError(kind() + ": this set-up has no release box"); }

namespace {

class FlumeSetup final : public Setup {
public:
    explicit FlumeSetup(const Scenario& s) : s_(s) {}
    std::string kind() const override { return "flume"; }
    std::vector<WallDef> walls() const override { return flume_walls(s_, false); }
    bool has_release() const override { return true; }
    ReleaseBox release_box() const override { return demlab::release_box(s_); }
    // the bed: W1, the arc, W3 as the world joined them
    std::unique_ptr<BedPath> bed_path(const World& w) const override {
        return std::make_unique<BedPath>(std::vector<WallGeom>{w.wall_geom(kW1), w.wall_geom(kW2), w.wall_geom(kW3)});
    }
    BarrierMarks barrier(const BedPath& path) const override { return {path.part_start(2), path.part(2).p0}; }
    ForceWalls force_walls() const override {
        ForceWalls f;
        f.slope = {kW1};
        f.arc = {kW2};
        f.barrier = {kW3};
        f.gate = kGate;
        return f;
    }
    std::vector<Vec2> extent() const override {
        const FlumeDef& f = s_.flume;
        return {f.w1_p0, f.w1_p1, f.w3_p0, f.w3_p1};
    }

private:
    const Scenario& s_;
};

class DamBreakSetup final : public Setup {
public:
    explicit DamBreakSetup(const Scenario& s) : s_(s) {}
    std::string kind() const override { return "dam_break"; }
    std::vector<WallDef> walls() const override { return dam_break_walls(s_, false); }
    bool has_release() const override { return true; }
    ReleaseBox release_box() const override { return demlab::release_box(s_); }
    bool measures_envelope() const override { return true; }
    // the floor as the bed path (s from the back wall): the front's run-out over time
    // (front.csv), the deposit's depth along it (deposit.csv) and the flow's peaks (peaks.csv)
    std::unique_ptr<BedPath> bed_path(const World& w) const override {
        return std::make_unique<BedPath>(std::vector<WallGeom>{w.wall_geom(kFloor)});
    }
    // the floor carries the column's weight, the back wall holds it; the gate as the flume's
    ForceWalls force_walls() const override {
        ForceWalls f;
        f.others = {{"floor", {kFloor}}, {"back_wall", {kBack}}};
        f.gate = kDamGate;
        return f;
    }
    double envelope_length() const override { return s_.dam_break.floor_length; }

private:
    const Scenario& s_;
};

// The profile's segments, left to right, the ground below them (the flow on their left).
class TerrainSetup final : public Setup {
public:
    explicit TerrainSetup(const Scenario& s) : s_(s) {}
    std::string kind() const override { return "terrain"; }
    std::vector<WallDef> walls() const override {
        WallDef base;
        base.material = kWallMaterial;
        base.segment_solid = SegmentSolid::Right;
        std::vector<WallDef> w;
        // a wall per segment of a polyline: the profile's, then the barrier's
        auto add_polyline = [&](const std::vector<Vec2>& p, const std::string& name) {
            for (size_t k = 0; k + 1 < p.size(); ++k) {
                WallDef d = base;
                d.name = name + "[" + std::to_string(k) + "]";
                d.p0 = p[k];
                d.p1 = p[k + 1];
                w.push_back(d);
            }
        };
        add_polyline(s_.terrain.points, "terrain");
        add_polyline(s_.terrain.barrier, "barrier");
        return w;
    }
    bool has_release() const override { return !s_.terrain.release.empty(); }
    // The release polygon's edges hold the mass while it is generated and settles; the run
    // starts without them, so the mass drops onto the profile. The lid, which the mass settles
    // last without, is the edge that faces most upwards (its outward normal's y the largest; of
    // equals the higher): the top. The highest edge by its middle was once taken, and in a
    // polygon whose top slopes that is a vertical side, over which the mass poured out.
    ReleaseBox release_box() const override {
        ReleaseBox b;
        b.polygon = s_.terrain.release;
        const size_t n = b.polygon.size();
        double signed_area = 0.0;  // > 0: counter-clockwise, the outward normal of an edge d is (d.y, -d.x)
        for (size_t k = 0; k < n; ++k) signed_area += cross(b.polygon[k], b.polygon[(k + 1) % n]);
        const double orient = signed_area > 0.0 ? 1.0 : -1.0;
        double best_up = -INFINITY, best_mid = -INFINITY;
        for (size_t k = 0; k < n; ++k) {
            WallDef d;
            d.name = "release[" + std::to_string(k) + "]";
            d.p0 = b.polygon[k];
            d.p1 = b.polygon[(k + 1) % n];
            d.material = kWallMaterial;
            d.cap_start = d.cap_end = EndCap::Capped;
            const Vec2 along = d.p1 - d.p0;
            const double up = -orient * along.x() / along.norm();  // the outward unit normal's y
            const double mid = 0.5 * (d.p0.y() + d.p1.y());
            if (up > best_up + 1e-12 || (up > best_up - 1e-12 && mid > best_mid)) {
                best_up = up;
                best_mid = mid;
                b.lid = int(k);
            }
            b.walls.push_back(d);
        }
        return b;
    }
    // The profile; with a barrier, the profile up to the barrier's foot and then the barrier,
    // so the front arrives at the foot and the run-up is measured on its face (as the flume's
    // W3). The ground behind the barrier is not on the path.
    std::unique_ptr<BedPath> bed_path(const World& w) const override {
        const TerrainDef& t = s_.terrain;
        const int profile_walls = int(t.points.size()) - 1;
        std::vector<WallGeom> parts;
        const int upto = t.barrier.empty() ? profile_walls : t.barrier_on_segment;
        for (int k = 0; k < upto; ++k) parts.push_back(w.wall_geom(k));
        if (!t.barrier.empty()) {
            WallDef cut;  // the foot's segment up to the foot (none when the foot is its start)
            cut.p0 = t.points[size_t(upto)];
            cut.p1 = t.barrier[0];
            if ((cut.p1 - cut.p0).norm() > 1e-9) parts.push_back(make_geom(cut));
            for (int k = 0; k + 1 < int(t.barrier.size()); ++k) parts.push_back(w.wall_geom(profile_walls + k));
        }
        return std::make_unique<BedPath>(std::move(parts));
    }
    BarrierMarks barrier(const BedPath& path) const override {
        if (s_.terrain.barrier.empty()) return {};
        double s, h;
        path.project(s_.terrain.barrier[0], s, h);
        return {s, s_.terrain.barrier[0]};
    }
    // the profile's load in forces.csv's slope columns, the barrier's in its barrier columns
    ForceWalls force_walls() const override {
        ForceWalls f;
        const int profile_walls = int(s_.terrain.points.size()) - 1;
        for (int k = 0; k < profile_walls; ++k) f.slope.push_back(k);
        for (int k = 0; k + 1 < int(s_.terrain.barrier.size()); ++k) f.barrier.push_back(profile_walls + k);
        return f;
    }
    std::vector<Vec2> extent() const override {
        std::vector<Vec2> e = s_.terrain.points;
        e.insert(e.end(), s_.terrain.release.begin(), s_.terrain.release.end());
        e.insert(e.end(), s_.terrain.barrier.begin(), s_.terrain.barrier.end());
        return e;
    }

private:
    const Scenario& s_;
};

class ExplicitSetup final : public Setup {
public:
    std::string kind() const override { return "explicit"; }
    std::vector<WallDef> walls() const override { return {}; }
};

}  // namespace

std::unique_ptr<Setup> make_setup(const Scenario& s) {
    if (s.flume.enabled) return std::make_unique<FlumeSetup>(s);
    if (s.dam_break.enabled) return std::make_unique<DamBreakSetup>(s);
    if (s.terrain.enabled) return std::make_unique<TerrainSetup>(s);
    return std::make_unique<ExplicitSetup>();
}

}  // namespace demlab
