#include "scenario/scenario.h"

#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>

#include "core/error.h"
#include "core/fileio.h"
#include "core/validate.h"
#include "geometry/esri_grid.h"
#include "geometry/profile.h"
#include "scenario/key_registry.h"

namespace demlab {

using namespace keys;

namespace {

constexpr double kInf = INFINITY;

// Bounds on the magnitudes a scenario may give (docs/scenario-reference.md): far beyond any
// flow the model is for, and far enough below overflow that a ledger of such discs stays finite.
constexpr double kMaxSpeed = 1e4;        // m/s, a disc's or a wall's velocity
constexpr double kMaxSpin = 1e6;         // rad/s, a disc's omega
constexpr double kMaxDiscForce = 1e12;   // N/m, a disc's constant force
constexpr double kMaxDiscRadius = 1e3;   // m

// A vector read as read_vec2 does, with its length at most `limit`.
Vec2 read_bounded_vec2(const toml::node& n, const std::string& where, const std::string& unit, double limit) {
    const Vec2 v = read_vec2(n, where, unit);
    if (!(v.norm() <= limit))
        throw InputError(where + " = [" + format_number(v.x()) + ", " + format_number(v.y()) + "] " + unit +
                         ": its magnitude must be at most " + format_number(limit) + " " + unit);
    return v;
}

// ---------------------------------------------------------------- [[walls]] and [[discs]]

// A [[walls]] entry and its own material (kn, ks, friction_deg as a coefficient).
WallDef read_wall(const toml::table& t, const std::string& file, size_t index, MaterialDef& mat) {
    WallDef w;
    mat = MaterialDef{};
    w.name = "walls[" + std::to_string(index) + "]";
    const std::vector<std::string> names = {"name", "type", "start", "end", "solid", "centre", "radius", "start_deg",
                                            "end_deg", "kn", "ks", "friction_deg", "velocity", "move_from",
                                            "move_until", "remove_at", "cap_start", "cap_end"};
    std::string type = "segment", solid;
    double friction_deg = 21.7;
    bool has_start = false, has_end = false, has_centre = false, has_radius = false;
    for (const auto& entry : t) {  // not a structured binding: the lambdas below capture node
        const toml::node& node = entry.second;
        const std::string key(entry.first.str());
        const std::string where = where_of(file, node, "walls[" + std::to_string(index) + "]." + key);
        auto str = [&](std::vector<std::string> choices) {
            auto v = node.value_exact<std::string>();
            std::string acc;
            for (auto& c : choices) acc += " \"" + c + "\"";
            if (!v || std::find(choices.begin(), choices.end(), *v) == choices.end())
                throw InputError(where + " = " + node_text(node) + ": must be one of" + acc);
            return *v;
        };
        auto num = [&](const char* unit, double lo, double hi, bool lo_open) {
            const double v = read_number(node, where, unit);
            if (!(lo_open ? v > lo : v >= lo) || !(v <= hi))
                throw InputError(where + " = " + format_number(v) + ": must be in " + (lo_open ? "(" : "[") +
                                 toml_number(lo) + ", " + toml_number(hi) + "] " + unit);
            return v;
        };
        if (key == "name") {
            auto v = node.value_exact<std::string>();
            if (!v) throw InputError(where + ": must be a string");
            w.name = *v;
        } else if (key == "type") type = str({"segment", "arc"});
        else if (key == "start") {
            w.p0 = read_vec2(node, where, "m");
            has_start = true;
        } else if (key == "end") {
            w.p1 = read_vec2(node, where, "m");
            has_end = true;
        }
        else if (key == "solid") solid = str({"both", "left", "right", "outside", "inside"});
        else if (key == "centre") {
            w.centre = read_vec2(node, where, "m");
            has_centre = true;
        } else if (key == "radius") {
            w.radius = num("m", 0, 1e3, true);
            has_radius = true;
        }
        else if (key == "start_deg") w.angle_start_deg = num("deg", -360, 720, false);
        else if (key == "end_deg") w.angle_end_deg = num("deg", -360, 720, false);
        else if (key == "kn") mat.kn = num("N/m", 0, 1e15, true);
        else if (key == "ks") mat.ks = num("N/m", 0, 1e15, true);
        else if (key == "friction_deg") friction_deg = num("deg", 0, 89, false);
        else if (key == "velocity") w.velocity = read_bounded_vec2(node, where, "m/s", kMaxSpeed);
        else if (key == "move_from") w.move_from = num("s", 0, 1e9, false);
        else if (key == "move_until") w.move_until = num("s", 0, kInf, false);
        else if (key == "remove_at") w.remove_at = num("s", 0, kInf, false);
        else if (key == "cap_start" || key == "cap_end") {
            const std::string v = str({"auto", "capped", "open"});
            const EndCap c = v == "auto" ? EndCap::Auto : (v == "capped" ? EndCap::Capped : EndCap::Open);
            (key == "cap_start" ? w.cap_start : w.cap_end) = c;
        } else unknown_key(where, key, names);
    }
    w.shape = type == "arc" ? WallShape::Arc : WallShape::Segment;
    mat.friction = std::tan(deg_to_rad(friction_deg));  // the angle's one conversion
    w.material = kFirstWallEntryMaterial + int(index);
    const std::string where = file + ": walls[" + std::to_string(index) + "]";
    // a point left out is refused, as a disc's position is: it would silently be (0, 0)
    auto require = [&](bool given, const char* key, const char* what) {
        if (!given) throw InputError(where + ": missing key '" + key + "' (" + what + ")");
    };
    if (w.shape == WallShape::Segment) {
        require(has_start, "start", "a segment's first end [x, y] in m");
        require(has_end, "end", "a segment's second end [x, y] in m");
        if (solid == "outside" || solid == "inside") throw InputError(where + ".solid: a segment takes both, left or right");
        w.segment_solid = solid == "left" ? SegmentSolid::Left : (solid == "right" ? SegmentSolid::Right : SegmentSolid::Both);
    } else {
        require(has_centre, "centre", "an arc's centre [x, y] in m");
        require(has_radius, "radius", "an arc's radius in m, > 0");
        if (solid == "left" || solid == "right" || solid == "both") throw InputError(where + ".solid: an arc takes outside or inside");
        w.arc_solid = solid == "inside" ? ArcSolid::Inside : ArcSolid::Outside;
    }
    validate(w, where);
    validate(mat, where);
    return w;
}

DiscDef read_disc(const toml::table& t, const std::string& file, size_t index) {
    DiscDef d;
    bool has_pos = false, has_r = false;
    const std::vector<std::string> names = {"position", "radius", "velocity", "omega", "angle", "force"};
    for (const auto& [k, node] : t) {
        const std::string key(k.str());
        const std::string where = where_of(file, node, "discs[" + std::to_string(index) + "]." + key);
        if (key == "position") {
            d.pos = read_vec2(node, where, "m");
            has_pos = true;
        } else if (key == "radius") {
            d.radius = read_number(node, where, "m");
            if (!(d.radius > 0) || !(d.radius <= kMaxDiscRadius))
                throw InputError(where + " = " + format_number(d.radius) + ": must be in (0, " + format_number(kMaxDiscRadius) + "] m");
            has_r = true;
        } else if (key == "velocity") d.vel = read_bounded_vec2(node, where, "m/s", kMaxSpeed);
        else if (key == "omega") {
            d.omega = read_number(node, where, "rad/s");
            if (!(std::abs(d.omega) <= kMaxSpin))
                throw InputError(where + " = " + format_number(d.omega) + ": must be in [-" + format_number(kMaxSpin) + ", " +
                                 format_number(kMaxSpin) + "] rad/s");
        } else if (key == "angle") d.angle = read_number(node, where, "rad");
        else if (key == "force") d.force = read_bounded_vec2(node, where, "N/m", kMaxDiscForce);
        else unknown_key(where, key, names);
    }
    const std::string where = file + ": discs[" + std::to_string(index) + "]";
    if (!has_pos) throw InputError(where + ": missing key 'position' ([x, y] in m)");
    if (!has_r) throw InputError(where + ": missing key 'radius' (m, > 0)");
    require_finite(where + ".omega", d.omega, "rad/s");
    return d;
}

void read_table(Scenario& s, const toml::table& t, const std::string& prefix, const std::string& file) {
    for (const auto& [k, node] : t) {
        const std::string key = prefix.empty() ? std::string(k.str()) : prefix + "." + std::string(k.str());
        if (prefix.empty() && (key == "walls" || key == "discs")) {
            const toml::array* arr = node.as_array();
            if (!arr || !arr->is_array_of_tables())
                throw InputError(where_of(file, node, key) + ": must be an array of tables ([[" + key + "]])");
            size_t i = 0;
            for (const auto& e : *arr) {
                if (key == "walls") {
                    MaterialDef mat;
                    s.walls.push_back(read_wall(*e.as_table(), file, i++, mat));
                    s.wall_entry_materials.push_back(mat);
                } else s.discs.push_back(read_disc(*e.as_table(), file, i++));
            }
            continue;
        }
        if (key == "flume") s.flume.enabled = true;
        if (key == "dam_break") s.dam_break.enabled = true;
        if (key == "terrain") s.terrain.enabled = true;
        if (key == "cohesion") s.cohesion.given = true;
        if (key == "lattice_release") s.lattice_release.enabled = true;
        if (key == "dan") s.dan_given = true;
        if (key == "dem3") s.dem3_given = true;
        if (const toml::table* sub = node.as_table()) {
            read_table(s, *sub, key, file);
            continue;
        }
        const Key* spec = find_key(key);
        if (!spec) unknown_key(where_of(file, node, key), key, key_names());
        spec->set(s, node, where_of(file, node, key));
    }
}

}  // namespace

Scenario parse_scenario(const std::string& text, const std::string& path) {
    Scenario s;
    s.source = path;
    toml::table t;
    try {
        t = toml::parse(text, path);
    } catch (const toml::parse_error& e) {
        throw InputError(path + ":" + std::to_string(e.source().begin.line) + ": TOML syntax error: " +
                         std::string(e.description()));
    }
    read_table(s, t, "", path);
    return s;
}

Scenario load_scenario(const std::string& path) {
    return parse_scenario(read_input_file(path, kMaxScenarioBytes, "scenario file"), path);
}

void apply_override(Scenario& s, const std::string& assignment) {
    const auto eq = assignment.find('=');
    if (eq == std::string::npos || eq == 0)
        throw InputError("--set '" + assignment + "': expected key=value, e.g. --set material.friction_disc_deg=16");
    const std::string key = assignment.substr(0, eq);
    std::string value = assignment.substr(eq + 1);
    const Key* spec = find_key(key);
    if (!spec) unknown_key("--set '" + assignment + "'", key, key_names());
    toml::table t;
    try {
        t = toml::parse("v = " + value);
    } catch (const toml::parse_error&) {
        // a bare word: take it as a string
        t = toml::table{{"v", value}};
    }
    spec->set(s, *t.get("v"), "--set key '" + key + "'");
    if (key.rfind("flume.", 0) == 0) s.flume.enabled = true;
    if (key.rfind("dam_break.", 0) == 0) s.dam_break.enabled = true;
    if (key.rfind("terrain.", 0) == 0) s.terrain.enabled = true;
    if (key.rfind("cohesion.", 0) == 0) s.cohesion.given = true;
    if (key.rfind("lattice_release.", 0) == 0) s.lattice_release.enabled = true;
    if (key.rfind("dan.", 0) == 0) s.dan_given = true;
    if (key.rfind("dem3.", 0) == 0) s.dem3_given = true;
}

// A relative path is the scenario file's neighbour; resolved, it is written absolute, so the
// run folder's copy of the scenario (and a resume) reads the same file.
static void resolve_beside_scenario(const Scenario& s, std::string& file) {
    const std::filesystem::path p(file);
    if (p.is_relative() && std::filesystem::is_regular_file(s.source))
        file = (std::filesystem::absolute(std::filesystem::path(s.source)).parent_path() / p).lexically_normal().string();
}

// The ground's height at x on a profile (x increasing; x within its range).
static double ground_at(const std::vector<Vec2>& line, double x) {
    size_t k = 0;
    while (k + 2 < line.size() && line[k + 1].x() < x) ++k;
    const Vec2 a = line[k], b = line[k + 1];
    return a.y() + (b.y() - a.y()) * (x - a.x()) / (b.x() - a.x());
}

// A polygon that discs fill must lie above the ground: every corner within the profile's x
// range and on or above the ground at its x (a corner under the ground is named), and no part
// of the ground inside it (a profile point inside, or a profile segment crossing an edge: a
// ridge through the polygon). Otherwise discs would be made over no ground or inside it.
// `tol` is "on the ground": a corner that far below it, or the ground that far inside, passes.
// `margin`: the ground must reach that far beyond the corners in x (a disc's radius: a disc at
// a corner reaches that far).
static void require_above_ground(const std::vector<Vec2>& poly, const std::vector<Vec2>& ground, double tol,
                                 const std::string& what, double margin = 0.0) {
    const double gx0 = ground.front().x() + margin, gx1 = ground.back().x() - margin;
    const size_t n = poly.size();
    for (size_t k = 0; k < n; ++k) {
        const Vec2 c = poly[k];
        const std::string corner = what + ": corner " + std::to_string(k) + " [" + format_number(c.x()) + ", " + format_number(c.y()) + "]";
        if (c.x() < gx0 || c.x() > gx1)
            throw InputError(corner + " lies beyond the terrain's profile (x from " + format_number(ground.front().x()) + " to " +
                             format_number(ground.back().x()) + " m" +
                             (margin > 0.0 ? ", less the largest disc's radius " + format_number(margin) + " m at each end" : "") +
                             "): the polygon must lie above the ground, within the profile's x range");
        const double g = ground_at(ground, std::clamp(c.x(), ground.front().x(), ground.back().x()));
        if (c.y() < g - tol)
            throw InputError(corner + " lies " + format_number(g - c.y()) + " m under the ground (the ground is at y = " +
                             format_number(g) + " m there): the polygon must lie on or above the ground");
    }
    // signed distance of p from the line a-b, positive on its left
    auto side = [](const Vec2& a, const Vec2& b, const Vec2& p) { return cross(b - a, p - a) / (b - a).norm(); };
    for (size_t j = 0; j < ground.size(); ++j) {
        const Vec2 q = ground[j];
        // strictly inside (more than tol from every edge): even-odd crossings
        bool in = false;
        double edge_distance = INFINITY;
        for (size_t a = 0, b = n - 1; a < n; b = a++) {
            const Vec2 pa = poly[a], pb = poly[b], e = pb - pa;
            const double t = std::clamp((q - pa).dot(e) / e.squaredNorm(), 0.0, 1.0);
            edge_distance = std::min(edge_distance, (pa + t * e - q).norm());
            if ((pa.y() > q.y()) != (pb.y() > q.y()) && q.x() < pa.x() + (q.y() - pa.y()) / (pb.y() - pa.y()) * e.x()) in = !in;
        }
        if (in && edge_distance > tol)
            throw InputError(what + ": the ground's point [" + format_number(q.x()) + ", " + format_number(q.y()) +
                             "] (point " + std::to_string(j + 1) + " of the profile) lies inside the polygon: it must lie above the ground");
    }
    for (size_t j = 0; j + 1 < ground.size(); ++j) {
        const Vec2 q = ground[j], r = ground[j + 1];
        for (size_t a = 0; a < n; ++a) {
            const Vec2 pa = poly[a], pb = poly[(a + 1) % n];
            const double d1 = side(q, r, pa), d2 = side(q, r, pb), d3 = side(pa, pb, q), d4 = side(pa, pb, r);
            if (((d1 > tol && d2 < -tol) || (d1 < -tol && d2 > tol)) && ((d3 > tol && d4 < -tol) || (d3 < -tol && d4 > tol)))
                throw InputError(what + ": the ground from [" + format_number(q.x()) + ", " + format_number(q.y()) + "] to [" +
                                 format_number(r.x()) + ", " + format_number(r.y()) + "] crosses the polygon's edge " +
                                 std::to_string(a) + ": the polygon must lie above the ground");
        }
    }
}

// The profile read and the release polygon checked: a convex polygon of >= 3 corners that
// holds discs of the release's radii, above the ground.
void finish_terrain(Scenario& s) {
    const std::string where = s.source + ": ";
    TerrainDef& t = s.terrain;
    if (t.profile.empty() == t.grid.empty())
        throw InputError(where + (t.profile.empty() ? "terrain.profile: a [terrain] needs its profile (a CSV file of x,y rows in m) "
                                                      "or an elevation grid (terrain.grid with terrain.section)"
                                                    : "terrain.profile and terrain.grid: give one of the two"));
    if (!t.profile.empty()) {
        resolve_beside_scenario(s, t.profile);
        t.points = read_profile_csv(t.profile);
    } else {
        resolve_beside_scenario(s, t.grid);
        if (t.section.size() != 2)
            throw InputError(where + "terrain.section: " + std::to_string(t.section.size()) +
                             " points; a section through terrain.grid is a line of 2 points [[x0, y0], [x1, y1]]");
        const EsriGrid g = read_esri_grid(t.grid);
        t.points = sample_section(g, t.grid, t.section[0], t.section[1], t.spacing > 0.0 ? t.spacing : g.cellsize);
    }
    if (!t.barrier.empty()) {
        const auto& b = t.barrier;
        if (b.size() < 2) throw InputError(where + "terrain.barrier: 1 point; a barrier needs at least 2 (its foot and its top)");
        for (size_t k = 0; k + 1 < b.size(); ++k)
            if ((b[k + 1] - b[k]).norm() < 1e-6)
                throw InputError(where + "terrain.barrier: points " + std::to_string(k) + " and " + std::to_string(k + 1) +
                                 " coincide (a segment must be longer than 1 um)");
        // none of it back over the flow: the bed path runs on up the barrier's last segment, and
        // one leaning upstream reached back over the release (the front measured past the
        // barrier at t = 0)
        for (size_t k = 0; k + 1 < b.size(); ++k)
            if (b[k + 1].x() < b[k].x())
                throw InputError(where + "terrain.barrier: from point " + std::to_string(k) + " to " + std::to_string(k + 1) + " it goes back upstream (x from " +
                                 format_number(b[k].x()) + " to " + format_number(b[k + 1].x()) +
                                 " m); a barrier may rise vertically or lean downstream, not over the flow");
        // the foot on a profile segment (x increasing): within 1 mm of the ground at its x
        const Vec2 foot = b[0];
        t.barrier_on_segment = -1;
        for (size_t k = 0; k + 1 < t.points.size(); ++k) {
            const Vec2 a = t.points[k], c = t.points[k + 1];
            if (foot.x() < a.x() || foot.x() > c.x()) continue;
            const double y = a.y() + (c.y() - a.y()) * (foot.x() - a.x()) / (c.x() - a.x());
            if (std::abs(y - foot.y()) <= 1e-3) {
                t.barrier_on_segment = int(k);
                break;
            }
        }
        if (t.barrier_on_segment < 0)
            throw InputError(where + "terrain.barrier: its first point [" + format_number(foot.x()) + ", " + format_number(foot.y()) +
                             "] is not on the profile (within 1 mm of the ground at that x); the barrier stands on the ground");
        const Vec2 face = b[1] - b[0], ground = t.points[size_t(t.barrier_on_segment) + 1] - t.points[size_t(t.barrier_on_segment)];
        if (cross(ground, face) <= 0.0)
            throw InputError(where + "terrain.barrier: its first segment goes down or along the ground; it must rise from the "
                             "foot (the upstream face first, the flow on its left)");
    }
    const auto& p = t.release;
    if (p.empty()) return;
    if (p.size() < 3) throw InputError(where + "terrain.release: " + std::to_string(p.size()) + " points; a polygon needs at least 3");
    double turn = 0.0;
    for (size_t k = 0; k < p.size(); ++k) {
        const double c = cross(p[(k + 1) % p.size()] - p[k], p[(k + 2) % p.size()] - p[(k + 1) % p.size()]);
        if (c == 0.0 || (turn != 0.0 && (c > 0.0) != (turn > 0.0)))
            throw InputError(where + "terrain.release: corner " + std::to_string((k + 1) % p.size()) +
                             " makes the polygon non-convex or degenerate (the release box must be convex)");
        turn = c;
    }
    double lo = INFINITY, hi = -INFINITY, x0 = INFINITY, x1 = -INFINITY;
    for (const Vec2& q : p) {
        lo = std::min(lo, q.y());
        hi = std::max(hi, q.y());
        x0 = std::min(x0, q.x());
        x1 = std::max(x1, q.x());
    }
    // "on the ground": a millionth of the polygon's size (coordinates typed to a few digits)
    require_above_ground(p, t.points, 1e-6 * std::max(x1 - x0, hi - lo), where + "terrain.release", s.release.r_max);
    const ReleaseDef& r = s.release;
    if (s.world.rotation.model >= 2 && !(s.world.rotation.u_rr < 0.6 * r.r_min * (1.0 - r.radius_reduction)))
        throw InputError(where + "rotation.u_rr = " + format_number(s.world.rotation.u_rr) +
                         " m must be < 0.6 times the smallest radius after the reduction = " +
                         format_number(0.6 * r.r_min * (1.0 - r.radius_reduction)) + " m (eq. 2.71 needs r_rr > 2/5 r)");
    const double size = std::min(hi - lo, x1 - x0);
    if (2.0 * s.release.r_max > 0.25 * size)
        throw InputError(where + "release.r_max = " + format_number(s.release.r_max) + " m is too large for the release polygon (" +
                         format_number(size) + " m across): at most " + format_number(size / 8) + " m");
}

// Explicit discs that overlap beyond world.max_overlap_ratio of the smaller radius at t = 0
// would be a blow-up at step 0: an input error naming the two (a sweep along x).
void finish_explicit_discs(const Scenario& s) {
    const auto& d = s.discs;
    if (d.size() < 2) return;
    std::vector<size_t> order(d.size());
    for (size_t i = 0; i < d.size(); ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return d[a].pos.x() - d[a].radius < d[b].pos.x() - d[b].radius; });
    for (size_t a = 0; a < order.size(); ++a) {
        const DiscDef& p = d[order[a]];
        for (size_t b = a + 1; b < order.size(); ++b) {
            const DiscDef& q = d[order[b]];
            if (q.pos.x() - q.radius > p.pos.x() + p.radius) break;
            const double overlap = p.radius + q.radius - (q.pos - p.pos).norm();
            if (overlap > s.world.max_overlap_ratio * std::min(p.radius, q.radius)) {
                const size_t i = std::min(order[a], order[b]), j = std::max(order[a], order[b]);
                throw InputError(s.source + ": discs[" + std::to_string(i) + "] and discs[" + std::to_string(j) + "] overlap by " +
                                 format_number(overlap) + " m at t = 0, more than world.max_overlap_ratio = " +
                                 format_number(s.world.max_overlap_ratio) + " of the smaller radius: move them apart");
            }
        }
    }
}

// The continuum solver's constraints (DAN.md section 3): a flume's path, gravity along -y, no
// discs of the scenario's own; its reference front resolved like a profile.
void finish_dan(Scenario& s) {
    const std::string where = s.source + ": ";
    if (s.solver != "dan") return;
    if (!s.flume.enabled)
        throw InputError(where + "scenario.solver = \"dan\" runs on a flume's path: the scenario needs a [flume] (the "
                         "geometries of scenarios/flume-*.toml and geometry-*.toml)");
    if (s.cohesion.enabled || s.lattice_release.enabled || !s.discs.empty() || !s.walls.empty())
        throw InputError(where + "scenario.solver = \"dan\": the continuum model has no discs, bonds or walls of its own; "
                         "leave out [cohesion], [lattice_release], [[discs]] and [[walls]]");
    if (s.world.gravity.x() != 0.0 || !(s.world.gravity.y() <= 0.0))
        throw InputError(where + "world.gravity = [" + format_number(s.world.gravity.x()) + ", " + format_number(s.world.gravity.y()) +
                         "] m/s2: scenario.solver = \"dan\" needs gravity along -y");
    DanDef& d = s.dan;
    if (!d.sync_front.empty()) {
        const std::filesystem::path f(d.sync_front);
        if (f.is_relative() && std::filesystem::is_regular_file(s.source))
            d.sync_front = (std::filesystem::absolute(std::filesystem::path(s.source)).parent_path() / f).lexically_normal().string();
        if (!std::filesystem::is_regular_file(d.sync_front))
            throw InputError(where + "dan.sync_front = \"" + d.sync_front + "\": not a file (a front.csv with t,s_front columns)");
    }
}

// The 3-D solver's inputs (src/dem3/): its own terrain and release, none of the 2-D set-ups;
// the files beside the scenario, the release box in map view.
void finish_dem3(Scenario& s) {
    const std::string where = s.source + ": ";
    if (s.solver != "dem3") {
        if (s.dem3_given)
            throw InputError(where + "a [dem3] table is read only by scenario.solver = \"dem3\" (this scenario's is \"" + s.solver + "\")");
        return;
    }
    Dem3Scenario& d = s.dem3;
    if (s.flume.enabled || s.dam_break.enabled || s.terrain.enabled || s.lattice_release.enabled || !s.discs.empty() ||
        !s.walls.empty())
        throw InputError(where + "scenario.solver = \"dem3\" has its own terrain and release ([dem3]); leave out [flume], "
                         "[dam_break], [terrain], [lattice_release], [[discs]] and [[walls]]");
    // bonds between the spheres come from their triangulation; the predicted length (C5) is the
    // discs' leapfrog's and not built for spheres
    if (s.cohesion.enabled && !s.cohesion.bonds.empty())
        throw InputError(where + "cohesion.bonds: the 3-D solver bonds the release's spheres from their Delaunay triangulation; "
                         "explicit pairs are not read (leave cohesion.bonds out)");
    if (s.cohesion.enabled && s.cohesion.bond.predict)
        throw InputError(where + "cohesion.predict = true: not offered by the 3-D solver (accepted: false)");
    if (d.terrain.empty()) throw InputError(where + "dem3.terrain: the 3-D solver needs a terrain (an .asc grid or an .xyz point file)");
    resolve_beside_scenario(s, d.terrain);
    if (!d.release_top.empty()) resolve_beside_scenario(s, d.release_top);
    else if (!(d.release_thickness > 0.0))
        throw InputError(where + "dem3.release_thickness = " + format_number(d.release_thickness) +
                         " m: give the release a thickness above the bed, or a top surface (dem3.release_top)");
    if (!(d.release_hi.x() > d.release_lo.x() && d.release_hi.y() > d.release_lo.y()))
        throw InputError(where + "dem3.release_lo = [" + format_number(d.release_lo.x()) + ", " + format_number(d.release_lo.y()) +
                         "], dem3.release_hi = [" + format_number(d.release_hi.x()) + ", " + format_number(d.release_hi.y()) +
                         "] m: the release box needs its north-east corner beyond its south-west one");
}

// Bonds listed in a [cohesion] that is not enabled would be silently unused.
static bool c_enabled_or_no_bonds(const Scenario& s) { return s.cohesion.enabled || s.cohesion.bonds.empty(); }

// The bonds' keys together (COHESION.md section 7's choices).
void finish_cohesion(Scenario& s) {
    const std::string where = s.source + ": ";
    const CohesionDef& c = s.cohesion;
    if (!c.enabled) return;
    // with explicit discs only, their count is known now: a bond naming a missing disc is
    // refused before any output (with generated discs, when the world is built)
    if (!has_release(s) && !s.lattice_release.enabled)
        for (const auto& [k, l] : c.bonds)
            if (size_t(std::max(k, l)) >= s.discs.size())
                throw InputError(where + "cohesion.bonds: [" + std::to_string(k) + ", " + std::to_string(l) +
                                 "] names a disc that does not exist (" + std::to_string(s.discs.size()) + " discs)");
    if (c.build.filter == BondFilter::Length && c.bonds.empty() && !(c.build.max_bond_length > 0.0))
        throw InputError(where + "cohesion.filter = \"length\" needs cohesion.max_bond_length > 0 m (it is " +
                         format_number(c.build.max_bond_length) + ")");
}

// The polygon between a mass's top surface and the bed below it, over the top's x range:
// the top from left to right, then the bed back from right to left (its heights interpolated
// at the top's ends, which are left out where the top starts or ends on the bed). The top
// must lie within the bed's x range and nowhere below it.
static std::vector<Vec2> region_under_top(const std::vector<Vec2>& top, const std::vector<Vec2>& bed, const std::string& what) {
    if (top.size() < 2) throw InputError(what + ": " + std::to_string(top.size()) + " point(s); the top needs at least 2");
    const double xa = top.front().x(), xb = top.back().x();
    if (xa < bed.front().x() || xb > bed.back().x())
        throw InputError(what + ": x from " + format_number(xa) + " to " + format_number(xb) +
                         " m, beyond the terrain's profile (x from " + format_number(bed.front().x()) + " to " +
                         format_number(bed.back().x()) + " m)");
    auto height = [](const std::vector<Vec2>& line, double x) {
        size_t k = 0;
        while (k + 2 < line.size() && line[k + 1].x() < x) ++k;
        const Vec2 a = line[k], b = line[k + 1];
        return a.y() + (b.y() - a.y()) * (x - a.x()) / (b.x() - a.x());
    };
    // a tolerance for "on the bed": a millionth of the mass's extent
    const double extent = std::max({xb - xa, std::abs(top.front().y()), std::abs(top.back().y()), 1.0});
    const double tol = 1e-6 * extent;
    double thickest = 0.0;
    auto check = [&](double x, double above) {
        if (above < -tol)
            throw InputError(what + ": at x = " + format_number(x) + " m the top is " + format_number(-above) +
                             " m below the terrain; it must lie on or above it");
        thickest = std::max(thickest, above);
    };
    for (const Vec2& p : top) check(p.x(), p.y() - height(bed, p.x()));
    for (const Vec2& p : bed)
        if (p.x() > xa && p.x() < xb) check(p.x(), height(top, p.x()) - p.y());
    if (!(thickest > tol)) throw InputError(what + ": the top lies on the terrain everywhere: no mass between them");
    std::vector<Vec2> poly(top.begin(), top.end());
    const double yb = height(bed, xb), ya = height(bed, xa);
    if (top.back().y() - yb > tol) poly.emplace_back(xb, yb);
    for (size_t k = bed.size(); k-- > 0;)
        if (bed[k].x() > xa + tol && bed[k].x() < xb - tol) poly.push_back(bed[k]);
    if (top.front().y() - ya > tol) poly.emplace_back(xa, ya);
    return poly;
}

// The lattice's keys together: a region and an origin, radii, a spacing that keeps discs apart.
void finish_lattice(Scenario& s) {
    const std::string where = s.source + ": ";
    LatticeReleaseDef& l = s.lattice_release;
    if (!l.enabled) return;
    if (s.flume.enabled || s.dam_break.enabled || (s.terrain.enabled && !s.terrain.release.empty()))
        throw InputError(where + "[lattice_release] fills its own region: it cannot go with a [flume], a [dam_break] "
                         "or a terrain.release (they generate a release mass)");
    if (!l.top.empty()) {
        if (!l.region.empty())
            throw InputError(where + "lattice_release.region and lattice_release.top: give one of the two (a polygon, or the "
                             "mass's top surface filled down to the terrain)");
        if (!s.terrain.enabled)
            throw InputError(where + "lattice_release.top: the mass's top is filled down to the terrain's profile: it needs a "
                             "[terrain] (terrain.profile or terrain.grid)");
        resolve_beside_scenario(s, l.top);
        l.fill = region_under_top(read_profile_csv(l.top, "mass's top surface (lattice_release.top)"), s.terrain.points, where + "lattice_release.top");
    } else {
        if (l.region.size() < 3)
            throw InputError(where + "lattice_release.region: " + std::to_string(l.region.size()) +
                             " points; a polygon needs at least 3 ([[x, y], ...] in m), or give lattice_release.top");
        l.fill = l.region;
    }
    const size_t n = l.fill.size();
    const std::string name = l.top.empty() ? "lattice_release.region" : "lattice_release.top (the area down to the terrain)";
    for (size_t a = 0; a < n; ++a)
        for (size_t b = a + 1; b < n; ++b) {
            if (b == a + 1 || (a == 0 && b == n - 1)) continue;  // neighbours share a corner
            const Vec2 p = l.fill[a], q = l.fill[(a + 1) % n], r = l.fill[b], t = l.fill[(b + 1) % n];
            const double d1 = cross(q - p, r - p), d2 = cross(q - p, t - p), d3 = cross(t - r, p - r), d4 = cross(t - r, q - r);
            if (((d1 > 0) != (d2 > 0)) && ((d3 > 0) != (d4 > 0)) && d1 != 0 && d2 != 0 && d3 != 0 && d4 != 0)
                throw InputError(where + name + ": edges " + std::to_string(a) + " and " + std::to_string(b) +
                                 " cross: the polygon must be simple");
        }
    if (!std::isfinite(l.origin.x()) || !std::isfinite(l.origin.y()))
        throw InputError(where + "lattice_release.origin: required, a lattice node [x, y] in m");
    if (!(l.r_min > 0.0)) throw InputError(where + "lattice_release.r_min: required, > 0 m");
    if (l.r_max == 0.0) l.r_max = l.r_min;
    if (l.r_max < l.r_min)
        throw InputError(where + "lattice_release.r_max = " + format_number(l.r_max) + " m must be >= r_min = " +
                         format_number(l.r_min) + " m");
    if (l.spacing == 0.0) l.spacing = 2.0 * l.r_max;
    if (l.spacing < 2.0 * l.r_max)
        throw InputError(where + "lattice_release.spacing = " + format_number(l.spacing) + " m must be >= 2 r_max = " +
                         format_number(2.0 * l.r_max) + " m: neighbouring discs would overlap");
    // a region on a terrain lies above its ground (as terrain.release); a node closer than its
    // radius to the ground is left out (lattice_mass), so the region may reach half of r_min
    // into it (a row meant to touch the bed, given to 0.1 mm) without a disc under the ground
    if (s.terrain.enabled && l.top.empty()) require_above_ground(l.fill, s.terrain.points, 0.5 * l.r_min, where + "lattice_release.region");
}

// The shared keys the chosen law does not read (law_part.h, kUnusedKeys): set to anything but
// their defaults they would be silently unused.
static void refuse_keys_the_law_does_not_read(const Scenario& s) {
    with_contact_law(s.world.law, [&](auto law) {
        using Law = decltype(law);
        if (Law::kUnusedKeys.empty()) return;
        const Scenario defaults;
        for (const Key& k : registry()) {
            const bool unused = std::any_of(Law::kUnusedKeys.begin(), Law::kUnusedKeys.end(), [&](const char* u) {
                const std::string p(u);
                const bool prefix = p.back() == '.' || p.back() == '_';
                return prefix ? k.name.rfind(p, 0) == 0 : k.name == p;
            });
            if (unused && k.get(s) != k.get(defaults))
                throw InputError(s.source + ": " + k.name + " = " + k.get(s) + ": not used by contact.law = \"" + Law::kName +
                                 "\" (" + Law::kUnusedWhy + "); remove it");
        }
    });
}

void finish_scenario(Scenario& s) {
    const std::string where = s.source + ": ";
    refuse_keys_the_law_does_not_read(s);
    // the keys' friction angles become their materials' coefficients here, once
    s.disc.friction = std::tan(deg_to_rad(s.disc_friction_deg));
    s.wall.friction = std::tan(deg_to_rad(s.wall_friction_deg));
    ReleaseDef& r = s.release;
    if (r.r_min == 0.0) r.r_min = scale_r_min(r.scale);
    if (r.r_max == 0.0) r.r_max = scale_r_max(r.scale);
    if (int(s.flume.enabled) + int(s.dam_break.enabled) + int(s.terrain.enabled) > 1)
        throw InputError(where + "a scenario is one of [flume], [dam_break] and [terrain], not several");
    // the name makes the default run folder runs/<name>: no path of its own
    if (s.name.empty() || s.name.find('/') != std::string::npos || s.name.find('\\') != std::string::npos ||
        s.name.find("..") != std::string::npos || s.name[0] == '.')
        throw InputError(where + "scenario.name = \"" + s.name + "\": must be a plain name (no '/', '\\' or '..', not starting "
                         "with '.'); it names the run folder runs/<name>");
    // nor a control character: a NUL cut the folder's name short (runs/x for "x\0y", left
    // behind empty when the write failed), a line end or tab makes a name no one can type
    for (size_t k = 0; k < s.name.size(); ++k)
        if (const unsigned char c = static_cast<unsigned char>(s.name[k]); c < 0x20 || c == 0x7f)
            throw InputError(where + "scenario.name holds a control character (code " + std::to_string(int(c)) +
                             ") at character " + std::to_string(k + 1) + ": it names the run folder runs/<name>; "
                             "use letters, digits, spaces and punctuation");
    finish_explicit_discs(s);
    // the given discs' and the lattice's smallest radius bounds the rolling penetration as the
    // generated masses' does (below); the world checks it again, without the file's name
    if (s.world.rotation.model >= 2) {
        double r_small = INFINITY;
        for (const DiscDef& d : s.discs) r_small = std::min(r_small, d.radius);
        if (s.lattice_release.enabled && s.lattice_release.r_min > 0.0) r_small = std::min(r_small, s.lattice_release.r_min);
        if (std::isfinite(r_small) && !(s.world.rotation.u_rr < 0.6 * r_small))
            throw InputError(where + "rotation.u_rr = " + format_number(s.world.rotation.u_rr) + " m must be < 0.6 times the " +
                             "smallest disc radius, " + format_number(r_small) + " m, = " + format_number(0.6 * r_small) +
                             " m (eq. 2.71 needs r_rr = r - u_rr > 2/5 r)");
    }
    if (s.terrain.enabled) finish_terrain(s);
    finish_dan(s);
    finish_dem3(s);
    finish_lattice(s);
    finish_cohesion(s);
    if (!r.from_file.empty() && (!has_release(s) || s.lattice_release.enabled))
        throw InputError(where + "release.from_file (--release-from) = \"" + r.from_file + "\": does not apply: " +
                         (s.lattice_release.enabled ? "the discs are a [lattice_release]"
                                                    : "the discs are given ([[discs]]), not a release mass"));
    // the scenario file's neighbour, as every file a scenario names (a run folder's copy and a
    // resume then read the same mass from any working directory)
    if (!r.from_file.empty()) resolve_beside_scenario(s, s.release.from_file);
    if (!c_enabled_or_no_bonds(s))
        throw InputError(where + "cohesion.bonds: given without cohesion.enabled = true; the bonds would not be made");
    if (s.cohesion.enabled && s.world.space_order == SpaceOrder::On)
        throw InputError(where + "world.space_order = \"on\": a world with bonds (cohesion.enabled = true) keeps its disc "
                         "numbers (accepted: \"auto\" or \"off\")");
    if (has_release(s) && !(r.r_min <= r.r_max))
        throw InputError(where + "release.r_min = " + format_number(r.r_min) + " m must be <= release.r_max = " +
                         format_number(r.r_max) + " m");
    if (s.stop.rest_duration >= s.stop.t_max)
        throw InputError(where + "stop.rest_duration = " + format_number(s.stop.rest_duration) +
                         " s must be shorter than stop.t_max = " + format_number(s.stop.t_max) + " s");
    if (!has_release(s) && s.discs.empty() && !s.lattice_release.enabled && s.solver != "dem3")
        throw InputError(where + "no discs: give a [flume] or [dam_break] (its release mass is generated), a [terrain] with a release polygon, a [lattice_release], or [[discs]]");
    if (s.dam_break.enabled) {
        const DamBreakDef& d = s.dam_break;
        if (2.0 * r.r_max > 0.25 * std::min(d.width, d.height))
            throw InputError(where + "release.r_max = " + format_number(r.r_max) + " m is too large for the " +
                             format_number(d.width) + " m x " + format_number(d.height) + " m column: at most " +
                             format_number(std::min(d.width, d.height) / 8) + " m");
        if (d.floor_length <= d.width)
            throw InputError(where + "dam_break.floor_length = " + format_number(d.floor_length) +
                             " m must exceed dam_break.width = " + format_number(d.width) + " m");
        if (d.sections_start + 0.5 > d.floor_length)
            throw InputError(where + "dam_break.sections_start = " + format_number(d.sections_start) +
                             " m leaves the five 10 cm sections past the floor's end (dam_break.floor_length = " +
                             format_number(d.floor_length) + " m): at most " + format_number(d.floor_length - 0.5) + " m");
        if (s.world.rotation.model >= 2 && !(s.world.rotation.u_rr < 0.6 * r.r_min * (1.0 - r.radius_reduction)))
            throw InputError(where + "rotation.u_rr = " + format_number(s.world.rotation.u_rr) +
                             " m must be < 0.6 times the smallest radius after the reduction");
    }
    if (s.flume.enabled) {
        // the release box must close: the gate stands on W1 and meets the lid, the lid meets W1's start
        const double tol = std::max(s.world.joint_tolerance, 1e-6);
        const Vec2 d = s.flume.w1_p1 - s.flume.w1_p0;
        const double along = (s.flume.gate_p0 - s.flume.w1_p0).dot(d) / d.squaredNorm();
        const double off = std::abs(cross(d.normalized(), s.flume.gate_p0 - s.flume.w1_p0));
        if (along <= 0.0 || along >= 1.0 || off > tol)
            throw InputError(where + "flume.gate_start = (" + format_number(s.flume.gate_p0.x()) + ", " +
                             format_number(s.flume.gate_p0.y()) + ") must lie on W1 (within " + format_number(tol) +
                             " m): the release box does not close");
        if ((s.flume.gate_p1 - s.flume.lid_p0).norm() > tol)
            throw InputError(where + "flume.lid_start must meet flume.gate_end: the release box does not close");
        if ((s.flume.lid_p1 - s.flume.w1_p0).norm() > tol)
            throw InputError(where + "flume.lid_end must meet flume.w1_start: the release box does not close");
        const double height = (s.flume.gate_p1 - s.flume.gate_p0).norm();
        if (2.0 * r.r_max > 0.25 * height)
            throw InputError(where + "release.r_max = " + format_number(r.r_max) + " m is too large for the release box (gate " +
                             format_number(height) + " m high): at most " + format_number(height / 8) + " m");
        if (s.world.rotation.model >= 2 && !(s.world.rotation.u_rr < 0.6 * r.r_min * (1.0 - r.radius_reduction)))
            throw InputError(where + "rotation.u_rr = " + format_number(s.world.rotation.u_rr) +
                             " m must be < 0.6 times the smallest radius after the reduction = " +
                             format_number(0.6 * r.r_min * (1.0 - r.radius_reduction)) + " m (eq. 2.71 needs r_rr > 2/5 r)");
    }
    for (long id : s.output.track)
        if (!s.discs.empty() && id >= long(s.discs.size()))
            throw InputError(where + "output.track: disc id " + std::to_string(id) + " does not exist (" +
                             std::to_string(s.discs.size()) + " discs)");
    if (!s.domain.empty()) {
        if (s.domain.size() != 2)
            throw InputError(where + "world.domain: " + std::to_string(s.domain.size()) +
                             (s.domain.size() == 1 ? " point" : " points") + "; the domain's box is [[x_lo, y_lo], [x_hi, y_hi]] (m), or [] for the walls' box padded by 0.5 m");
        if (!(s.domain[0].x() < s.domain[1].x()) || !(s.domain[0].y() < s.domain[1].y()))
            throw InputError(where + "world.domain = [[" + format_number(s.domain[0].x()) + ", " + format_number(s.domain[0].y()) +
                             "], [" + format_number(s.domain[1].x()) + ", " + format_number(s.domain[1].y()) +
                             "]]: the first point is the lower left corner, the second the upper right (x_lo < x_hi, y_lo < y_hi)");
        // explicit discs are known now (a release mass's are checked when it exists, run.cpp)
        for (size_t i = 0; i < s.discs.size(); ++i) {
            const Vec2 p = s.discs[i].pos;
            if (p.x() < s.domain[0].x() || p.x() > s.domain[1].x() || p.y() < s.domain[0].y() || p.y() > s.domain[1].y())
                throw InputError(where + "world.domain: discs[" + std::to_string(i) + "] at [" + format_number(p.x()) + ", " +
                                 format_number(p.y()) + "] lies outside it: the domain must hold every disc at t = 0");
        }
    }
}

// A set-up's table is written only when the scenario has it (its presence chooses the set-up).
static bool section_in_use(const Scenario& s, const std::string& sec) {
    if (sec == "flume") return s.flume.enabled;
    if (sec == "dam_break") return s.dam_break.enabled;
    if (sec == "terrain") return s.terrain.enabled;
    if (sec == "cohesion") return s.cohesion.given;
    if (sec == "lattice_release") return s.lattice_release.enabled;
    if (sec == "dan") return s.dan_given || s.solver == "dan";
    if (sec == "dem3") return s.dem3_given || s.solver == "dem3";
    // a law's section, when it is the chosen law
    bool law_section = false, chosen = false;
    for_each_contact_law([&](auto law) {
        if (sec != decltype(law)::kSection) return;
        law_section = true;
        chosen = chosen || s.world.law == law_kind<decltype(law)>();
    });
    if (law_section) return chosen;
    return true;
}

std::string resolved_toml(const Scenario& s) {
    std::ostringstream o;
    o << "# Resolved scenario: every key with the value the run used (defaults included).\n";
    o << "# Source: " << s.source << "\n";
    std::string section;
    for (const Key& k : registry()) {
        const auto dot = k.name.find('.');
        const std::string sec = k.name.substr(0, dot);
        if (sec != section) {
            if (!section_in_use(s, sec)) continue;
            o << "\n[" << sec << "]\n";
            section = sec;
        }
        if (!section_in_use(s, sec)) continue;
        o << k.name.substr(dot + 1) << " = " << k.get(s) << "\n";
    }
    for (size_t i = 0; i < s.walls.size(); ++i) {
        const WallDef& w = s.walls[i];
        const MaterialDef& m = s.wall_entry_materials[i];
        o << "\n[[walls]]\nname = " << toml_string(w.name) << "\n";
        if (w.shape == WallShape::Segment) {
            o << "type = \"segment\"\nstart = [" << toml_number(w.p0.x()) << ", " << toml_number(w.p0.y()) << "]\nend = ["
              << toml_number(w.p1.x()) << ", " << toml_number(w.p1.y()) << "]\nsolid = \""
              << (w.segment_solid == SegmentSolid::Both ? "both" : (w.segment_solid == SegmentSolid::Left ? "left" : "right")) << "\"\n";
        } else {
            o << "type = \"arc\"\ncentre = [" << toml_number(w.centre.x()) << ", " << toml_number(w.centre.y())
              << "]\nradius = " << toml_number(w.radius) << "\nstart_deg = " << toml_number(w.angle_start_deg)
              << "\nend_deg = " << toml_number(w.angle_end_deg) << "\nsolid = \""
              << (w.arc_solid == ArcSolid::Outside ? "outside" : "inside") << "\"\n";
        }
        o << "kn = " << toml_number(m.kn) << "\nks = " << toml_number(m.ks) << "\nfriction_deg = "
          << toml_number(std::atan(m.friction) * 180.0 / kPi) << "\nvelocity = [" << toml_number(w.velocity.x()) << ", "
          << toml_number(w.velocity.y()) << "]\nmove_from = " << toml_number(w.move_from) << "\nmove_until = "
          << toml_number(w.move_until) << "\nremove_at = " << toml_number(w.remove_at) << "\n";
    }
    for (const DiscDef& d : s.discs)
        o << "\n[[discs]]\nposition = [" << toml_number(d.pos.x()) << ", " << toml_number(d.pos.y())
          << "]\nradius = " << toml_number(d.radius) << "\nvelocity = [" << toml_number(d.vel.x()) << ", "
          << toml_number(d.vel.y()) << "]\nomega = " << toml_number(d.omega) << "\nangle = " << toml_number(d.angle) << "\n"
          << (d.force.squaredNorm() > 0.0 ? "force = [" + toml_number(d.force.x()) + ", " + toml_number(d.force.y()) + "]\n" : std::string());
    return o.str();
}

std::string scenario_reference_markdown() {
    std::ostringstream o;
    const Scenario defaults;
    o << "# Scenario reference\n\n"
         "A scenario is a TOML file. Every key below is optional: the default is the thesis' value (Table 15) "
         "where it has one. Unknown keys, wrong types and values out of range are refused with the file, line, "
         "key and accepted range. Any key can be overridden on the command line: `--set key=value` (value in "
         "TOML syntax, e.g. `--set material.friction_disc_deg=16`, `--set release.variant=I`).\n\n"
         "Generated by `demlab keys`; do not edit by hand.\n\n"
         "| key | unit | default | accepted | meaning |\n|---|---|---|---|---|\n";
    for (const Key& k : registry()) {
        std::string def = k.get(defaults);
        if (k.name.rfind("release.r_m", 0) == 0) def = "0 (from the scale)";
        o << "| `" << k.name << "` | " << k.unit << " | `" << def << "` | " << k.accepted << " | " << k.doc << " |\n";
    }
    o << "\n## Explicit walls: `[[walls]]`\n\n"
         "| key | unit | default | meaning |\n|---|---|---|---|\n"
         "| `name` | - | `walls[i]` | name in messages and outputs |\n"
         "| `type` | - | `\"segment\"` | `\"segment\"` or `\"arc\"` |\n"
         "| `start`, `end` | m | required (segment) | segment ends `[x, y]` |\n"
         "| `solid` | - | `\"both\"` / `\"outside\"` | segment: `both`, `left`, `right` (looking from start to end); arc: `outside` (discs run on the inside) or `inside` |\n"
         "| `centre`, `radius` | m | required (arc) | arc's centre `[x, y]` and radius (0, 1e3] |\n"
         "| `start_deg`, `end_deg` | deg | 0 | arc, counter-clockwise from start_deg to end_deg, at most 360 deg apart |\n"
         "| `kn`, `ks` | N/m | 1e8 | stiffness, in series with the disc's |\n"
         "| `friction_deg` | deg | 21.7 | friction angle |\n"
         "| `velocity` | m/s | [0, 0] | prescribed velocity from `move_from` to `move_until` (s); magnitude at most 1e4 |\n"
         "| `remove_at` | s | inf | the wall disappears at this time |\n"
         "| `cap_start`, `cap_end` | - | `\"auto\"` | `auto`, `capped` or `open`: whether the end is a corner discs can touch |\n"
         "\n## Explicit discs: `[[discs]]`\n\n"
         "| key | unit | default | meaning |\n|---|---|---|---|\n"
         "| `position` | m | required | centre `[x, y]` |\n"
         "| `radius` | m | required | in (0, 1e3] |\n"
         "| `velocity` | m/s | [0, 0] | initial velocity; magnitude at most 1e4 |\n"
         "| `omega` | rad/s | 0 | initial angular velocity (counter-clockwise), in [-1e6, 1e6] |\n"
         "| `angle` | rad | 0 | initial angle |\n"
         "| `force` | N/m | [0, 0] | a constant force added every step (its work is in the ledger's potential); magnitude at most 1e12 |\n";
    return o.str();
}

}  // namespace demlab
