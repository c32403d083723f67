#include "run/snapshot.h"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "core/fileio.h"

namespace demlab {

SnapshotWriter::SnapshotWriter(std::string dir, std::vector<int> layer, std::vector<int> grid)
    : dir_(std::move(dir)), layer_(std::move(layer)), grid_(std::move(grid)) {
    std::filesystem::create_directories(dir_);
}

namespace {
// Appends v as an ostream with precision p writes it in the default format: std::to_chars
// with a precision is printf's %.pg in the "C" locale, the same text. A std::ostringstream per
// disc, as before, made a snapshot of geometry A's 9,101 discs take 25 ms (about 3 s of a run
// to rest, with the other thread idle).
void put_g(std::string& o, double v, int p) {
    char b[40];
    const auto r = std::to_chars(b, b + sizeof b, v, std::chars_format::general, p);
    o.append(b, r.ptr);
}
void put_int(std::string& o, long v) {
    char b[24];
    const auto r = std::to_chars(b, b + sizeof b, v);
    o.append(b, r.ptr);
}
// a 2D point as "x y 0"
void put_xy0(std::string& o, const Vec2& v, int p) {
    put_g(o, v.x(), p);
    o += ' ';
    put_g(o, v.y(), p);
    o += " 0";
}

// put(o, i) appends item i
template <typename F>
void data_array(std::string& o, const char* type, const char* name, int components, size_t n, F put) {
    o += "        <DataArray type=\"";
    o += type;
    o += "\" Name=\"";
    o += name;
    o += "\" NumberOfComponents=\"";
    put_int(o, components);
    o += "\" format=\"ascii\">\n";
    for (size_t i = 0; i < n; ++i) {
        put(o, i);
        o += i + 1 == n ? '\n' : ' ';
    }
    o += "        </DataArray>\n";
}
}  // namespace

void SnapshotWriter::write(const World& w) {
    const int index = int(times_.size());
    char name[64];
    const size_t n = w.disc_count();
    std::string o;
    o.reserve(160 * n + 4096);
    o += "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
         "  <PolyData>\n    <FieldData>\n      <DataArray type=\"Float64\" Name=\"TIME\" NumberOfTuples=\"1\" format=\"ascii\">";
    put_g(o, w.time(), 9);
    o += "</DataArray>\n    </FieldData>\n    <Piece NumberOfPoints=\"";
    put_int(o, long(n));
    o += "\" NumberOfVerts=\"";
    put_int(o, long(n));
    // intact bonds as line cells between the disc centres; per disc its intact and broken bonds
    const std::vector<Bond>& bonds = w.bonds();
    std::vector<long> bond_ends;
    std::vector<int> intact, broken;
    if (!bonds.empty()) {
        intact.assign(n, 0);
        broken.assign(n, 0);
        for (const Bond& b : bonds) {
            std::vector<int>& count = b.broken ? broken : intact;
            ++count[size_t(b.k)];
            ++count[size_t(b.l)];
            if (!b.broken) bond_ends.insert(bond_ends.end(), {long(b.k), long(b.l)});
        }
        o += "\" NumberOfLines=\"";
        put_int(o, long(bond_ends.size() / 2));
    }
    o += "\">\n      <Points>\n";
    data_array(o, "Float64", "Points", 3, n, [&](std::string& s, size_t i) { put_xy0(s, w.positions()[i], 12); });
    o += "      </Points>\n      <PointData Scalars=\"radius\">\n";
    data_array(o, "Float64", "radius", 1, n, [&](std::string& s, size_t i) { put_g(s, w.radii()[i], 9); });
    data_array(o, "Float64", "velocity", 3, n, [&](std::string& s, size_t i) { put_xy0(s, w.velocities()[i], 9); });
    data_array(o, "Float64", "speed", 1, n, [&](std::string& s, size_t i) { put_g(s, w.velocities()[i].norm(), 9); });
    data_array(o, "Float64", "angle", 1, n, [&](std::string& s, size_t i) { put_g(s, w.angles()[i], 9); });
    data_array(o, "Float64", "omega", 1, n, [&](std::string& s, size_t i) { put_g(s, w.omegas()[i], 9); });
    // by the id each disc was added with (a lost disc leaves the world: World::disc_ids)
    const std::vector<int32_t>& ids = w.disc_ids();
    data_array(o, "Int32", "layer", 1, n, [&](std::string& s, size_t i) { const size_t k = size_t(ids[i]); put_int(s, k < layer_.size() ? layer_[k] : 0); });
    data_array(o, "Int32", "grid", 1, n, [&](std::string& s, size_t i) { const size_t k = size_t(ids[i]); put_int(s, k < grid_.size() ? grid_[k] : 0); });
    data_array(o, "Int32", "id", 1, n, [&](std::string& s, size_t i) { put_int(s, long(ids[i])); });
    if (!bonds.empty()) {
        data_array(o, "Int32", "bonds_intact", 1, n, [&](std::string& s, size_t i) { put_int(s, intact[i]); });
        data_array(o, "Int32", "bonds_broken", 1, n, [&](std::string& s, size_t i) { put_int(s, broken[i]); });
    }
    o += "      </PointData>\n      <Verts>\n";
    data_array(o, "Int64", "connectivity", 1, n, [&](std::string& s, size_t i) { put_int(s, long(i)); });
    data_array(o, "Int64", "offsets", 1, n, [&](std::string& s, size_t i) { put_int(s, long(i + 1)); });
    o += "      </Verts>\n";
    if (!bonds.empty()) {
        o += "      <Lines>\n";
        data_array(o, "Int64", "connectivity", 1, bond_ends.size(), [&](std::string& s, size_t i) { put_int(s, bond_ends[i]); });
        data_array(o, "Int64", "offsets", 1, bond_ends.size() / 2, [&](std::string& s, size_t i) { put_int(s, long(2 * i + 2)); });
        o += "      </Lines>\n";
    }
    o += "    </Piece>\n  </PolyData>\n</VTKFile>\n";
    std::snprintf(name, sizeof name, "/discs_%05d.vtp", index);
    write_file_atomic(dir_ + name, o);

    // walls as polylines (arcs in 48 pieces), only those present at this instant
    std::vector<Vec2> pts;
    std::vector<long> offsets;
    std::vector<int> wall_id;
    for (int k = 0; k < int(w.wall_count()); ++k) {
        if (!w.wall_active(k)) continue;
        const WallGeom& g = w.wall_geom(k);
        if (g.shape == WallShape::Segment) {
            pts.push_back(g.p0);
            pts.push_back(g.p1);
        } else {
            for (int j = 0; j <= 48; ++j) {
                const double a = g.angle0 + g.extent * j / 48.0;
                pts.push_back(g.centre + g.radius * Vec2(std::cos(a), std::sin(a)));
            }
        }
        offsets.push_back(long(pts.size()));
        wall_id.push_back(k);
    }
    std::string wo;
    wo += "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
          "  <PolyData>\n    <Piece NumberOfPoints=\"";
    put_int(wo, long(pts.size()));
    wo += "\" NumberOfLines=\"";
    put_int(wo, long(offsets.size()));
    wo += "\">\n      <Points>\n";
    data_array(wo, "Float64", "Points", 3, pts.size(), [&](std::string& s, size_t i) { put_xy0(s, pts[i], 12); });
    wo += "      </Points>\n      <CellData>\n";
    data_array(wo, "Int32", "wall", 1, wall_id.size(), [&](std::string& s, size_t i) { put_int(s, wall_id[i]); });
    wo += "      </CellData>\n      <Lines>\n";
    data_array(wo, "Int64", "connectivity", 1, pts.size(), [&](std::string& s, size_t i) { put_int(s, long(i)); });
    data_array(wo, "Int64", "offsets", 1, offsets.size(), [&](std::string& s, size_t i) { put_int(s, offsets[i]); });
    wo += "      </Lines>\n    </Piece>\n  </PolyData>\n</VTKFile>\n";
    std::snprintf(name, sizeof name, "/walls_%05d.vtp", index);
    write_file_atomic(dir_ + name, wo);
    times_.push_back(w.time());
}

static std::string numbered(const std::string& dir, const char* kind, int index) {
    char name[64];
    std::snprintf(name, sizeof name, "/%s_%05d.vtp", kind, index);
    return dir + name;
}
std::string SnapshotWriter::last_discs() const { return numbered(dir_, "discs", count() - 1); }
std::string SnapshotWriter::last_walls() const { return numbered(dir_, "walls", count() - 1); }

void SnapshotWriter::finish() {
    for (const char* kind : {"discs", "walls"}) {
        std::ostringstream o;
        o.precision(12);
        o << "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n  <Collection>\n";
        for (size_t i = 0; i < times_.size(); ++i) {
            char name[64];
            std::snprintf(name, sizeof name, "%s_%05zu.vtp", kind, i);
            o << "    <DataSet timestep=\"" << times_[i] << "\" file=\"" << name << "\"/>\n";
        }
        o << "  </Collection>\n</VTKFile>\n";
        write_file_atomic(dir_ + "/" + kind + ".pvd", o.str());
    }
}

}  // namespace demlab
