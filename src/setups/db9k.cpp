#include "setups/db9k.h"

#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>

#include "core/error.h"
#include "core/fileio.h"

namespace demlab {

std::vector<XyrDisc> read_xyr(const std::string& path) {
    std::istringstream in(read_input_file(path, kMaxTableBytes, "disc file ('id x y r' rows)"));
    std::vector<XyrDisc> out;
    std::string line;
    long lineno = 0;
    while (std::getline(in, line)) {
        ++lineno;
        const auto hash = line.find('#');
        if (hash != std::string::npos) line.resize(hash);
        if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
        std::istringstream s(line);
        XyrDisc d{};
        if (!(s >> d.id >> d.x >> d.y >> d.r))
            throw InputError(path + ":" + std::to_string(lineno) + ": expected 'id x y r' (metres), got '" + line + "'");
        std::string extra;
        if (s >> extra) throw InputError(path + ":" + std::to_string(lineno) + ": unexpected '" + extra + "' after 'id x y r'");
        if (!(d.r > 0.0) || !std::isfinite(d.x) || !std::isfinite(d.y) || !std::isfinite(d.r))
            throw InputError(path + ":" + std::to_string(lineno) + ": radius must be > 0 and coordinates finite");
        out.push_back(d);
    }
    if (out.empty()) throw InputError(path + ": no discs in the file");
    return out;
}

WorldDef db9k_world_def(int copies) {
    WorldDef def;
    def.gravity = Vec2(0.0, -9.81);
    def.damping.beta_n = 0.5;
    def.damping.beta_s = 0.0;
    def.damping.dp_mode = DashpotMode::Full;
    def.timestep.automatic = false;
    def.timestep.fixed = 5e-6;
    // the dashpots from the velocities half a step back, as LAMMPS' velocity Verlet takes them:
    // the benchmark's peer does the same work (the flume's default centres them, engine.md)
    def.timestep.dashpots = DashpotScheme::Lagged;
    def.rotation.model = 2;
    def.rotation.u_rr = 0.0;  // free rotation, no rolling resistance
    def.space_order = SpaceOrder::Off;  // the discs numbered as the file (its checksum; --file orders)
    def.friction_rule_disc_wall = FrictionRule::Max;
    def.broadphase_margin = 0.0;
    def.domain_lo = Vec2(-0.1, -0.1);
    def.domain_hi = Vec2(3.0 + kCopySpacing * (copies - 1), 2.0);
    return def;
}

void build_db9k(World& world, const std::vector<XyrDisc>& discs, int copies) {
    MaterialDef sand;
    sand.density = 2672.0;
    sand.kn = 2.0e8;
    sand.ks = 2.0e8;
    sand.friction = 0.2773;
    const int m = world.add_material(sand);
    for (int k = 0; k < copies; ++k)
        for (const XyrDisc& d : discs) world.add_disc({Vec2(d.x + kCopySpacing * k, d.y), d.r, Vec2::Zero(), 0.0, 0.0, m});
    WallDef floor;
    floor.name = "floor";
    floor.p0 = Vec2(0.0, 0.0);
    floor.p1 = Vec2(1.5 + kCopySpacing * (copies - 1), 0.0);
    floor.segment_solid = SegmentSolid::Right;  // free side up
    MaterialDef sheet;  // the walls' (a wall's density is not used)
    sheet.kn = sheet.ks = 2.0e8;
    sheet.friction = 0.3979;
    floor.material = world.add_material(sheet);
    WallDef left = floor;
    left.name = "left";
    left.p0 = Vec2(0.0, 0.6);
    left.p1 = Vec2(0.0, 0.0);  // walking down, the free side (+x) is on the left
    world.add_wall(floor);
    world.add_wall(left);
    for (int k = 1; k < copies; ++k) {
        WallDef next = left;
        next.name = "left" + std::to_string(k);
        next.p0.x() += kCopySpacing * k;
        next.p1.x() += kCopySpacing * k;
        world.add_wall(next);
    }
}

uint64_t state_hash(const World& world) {
    uint64_t h = 1469598103934665603ull;
    auto mix = [&h](const void* data, size_t bytes) {
        const unsigned char* p = static_cast<const unsigned char*>(data);
        for (size_t k = 0; k < bytes; ++k) {
            h ^= p[k];
            h *= 1099511628211ull;
        }
    };
    const size_t n = world.disc_count();
    mix(world.positions().data(), n * sizeof(Vec2));
    mix(world.velocities().data(), n * sizeof(Vec2));
    mix(world.angles().data(), n * sizeof(double));
    mix(world.omegas().data(), n * sizeof(double));
    return h;
}

std::string default_db9k_path() { return std::string(DEMLAB_SOURCE_DIR) + "/bench/db9k/db9k_initial.xyr"; }

}  // namespace demlab
