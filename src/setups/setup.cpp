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
    ForceWalls force_walls() const override { return {{kW1}, {kW2}, {kW3}, kGate}; }
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
        base.kn = s_.wall_kn;
        base.ks = s_.wall_ks;
        base.friction = std::tan(deg_to_rad(s_.wall_friction_deg));
        base.segment_solid = SegmentSolid::Right;
        std::vector<WallDef> w;
        const auto& p = s_.terrain.points;
        for (size_t k = 0; k + 1 < p.size(); ++k) {
            WallDef d = base;
            d.name = "terrain[" + std::to_string(k) + "]";
            d.p0 = p[k];
            d.p1 = p[k + 1];
            w.push_back(d);
        }
        return w;
    }
    bool has_release() const override { return !s_.terrain.release.empty(); }
    // The release polygon's edges hold the mass while it is generated and settles; the run
    // starts without them, so the mass drops onto the profile. The lid is the highest edge.
    ReleaseBox release_box() const override {
        ReleaseBox b;
        b.polygon = s_.terrain.release;
        const size_t n = b.polygon.size();
        double top = -INFINITY;
        for (size_t k = 0; k < n; ++k) {
            WallDef d;
            d.name = "release[" + std::to_string(k) + "]";
            d.p0 = b.polygon[k];
            d.p1 = b.polygon[(k + 1) % n];
            d.kn = s_.wall_kn;
            d.ks = s_.wall_ks;
            d.friction = std::tan(deg_to_rad(s_.wall_friction_deg));
            d.cap_start = d.cap_end = EndCap::Capped;
            const double mid = 0.5 * (d.p0.y() + d.p1.y());
            if (mid > top) {
                top = mid;
                b.lid = int(k);
            }
            b.walls.push_back(d);
        }
        return b;
    }
    std::unique_ptr<BedPath> bed_path(const World& w) const override {
        std::vector<WallGeom> parts;
        for (size_t k = 0; k + 1 < s_.terrain.points.size(); ++k) parts.push_back(w.wall_geom(int(k)));
        return std::make_unique<BedPath>(std::move(parts));
    }
    // the whole profile's load in forces.csv's slope columns
    ForceWalls force_walls() const override {
        ForceWalls f;
        for (size_t k = 0; k + 1 < s_.terrain.points.size(); ++k) f.slope.push_back(int(k));
        return f;
    }
    std::vector<Vec2> extent() const override {
        std::vector<Vec2> e = s_.terrain.points;
        e.insert(e.end(), s_.terrain.release.begin(), s_.terrain.release.end());
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
