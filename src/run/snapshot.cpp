#include "run/snapshot.h"

#include <charconv>
#include <cstring>
#include <type_traits>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "core/fileio.h"
#include "run/vtk_zlib_blocks.h"

namespace demlab {

SnapshotWriter::SnapshotWriter(std::string dir, std::vector<int> layer, std::vector<int> grid, bool binary)
    : dir_(std::move(dir)), layer_(std::move(layer)), grid_(std::move(grid)), binary_(binary) {
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
// The arrays of one file: inline text (ascii) or appended raw binary, zlib-compressed
// (vtk_zlib_blocks.h). value(i, c) gives component c of item i: a double (Float64, written
// as text with `precision` significant digits) or an integer (Int32 or Int64).
class VtpArrays {
public:
    explicit VtpArrays(bool binary) : binary_(binary) {}

    template <typename F>
    void add(std::string& o, const char* type, const char* name, int components, size_t n, F value, int precision = 9) {
        o += "        <DataArray type=\"";
        o += type;
        o += "\" Name=\"";
        o += name;
        o += "\" NumberOfComponents=\"";
        put_int(o, components);
        using V = decltype(value(size_t(0), 0));
        if (!binary_) {
            o += "\" format=\"ascii\">\n";
            for (size_t i = 0; i < n; ++i) {
                for (int c = 0; c < components; ++c) {
                    if (c) o += ' ';
                    if constexpr (std::is_floating_point_v<V>) put_g(o, value(i, c), precision);
                    else put_int(o, long(value(i, c)));
                }
                o += i + 1 == n ? '\n' : ' ';
            }
            o += "        </DataArray>\n";
            return;
        }
        o += "\" format=\"appended\" offset=\"";
        put_int(o, long(appended_.size()));
        o += "\"/>\n";
        const bool wide = std::strcmp(type, "Int64") == 0;
        raw_.clear();
        for (size_t i = 0; i < n; ++i)
            for (int c = 0; c < components; ++c) {
                if constexpr (std::is_floating_point_v<V>) put_raw(double(value(i, c)));
                else if (wide) put_raw(int64_t(value(i, c)));
                else put_raw(int32_t(value(i, c)));
            }
        append_zlib_blocks(appended_, raw_.data(), raw_.size());
    }
    // the file's root element and its end (with the appended data)
    std::string root() const {
        return binary_ ? "<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\" "
                         "compressor=\"vtkZLibDataCompressor\">\n"
                       : "<VTKFile type=\"PolyData\" version=\"0.1\" byte_order=\"LittleEndian\">\n";
    }
    void end(std::string& o) const {
        o += "  </PolyData>\n";
        if (binary_) {
            o += "  <AppendedData encoding=\"raw\">\n   _";
            o += appended_;
            o += "\n  </AppendedData>\n";
        }
        o += "</VTKFile>\n";
    }

private:
    template <typename T>
    void put_raw(T v) {
        const size_t at = raw_.size();
        raw_.resize(at + sizeof(T));
        std::memcpy(raw_.data() + at, &v, sizeof(T));
    }
    bool binary_;
    std::string appended_;
    std::vector<unsigned char> raw_;
};
}  // namespace

void SnapshotWriter::write(const World& w) {
    const int index = int(times_.size());
    char name[64];
    const size_t n = w.disc_count();
    VtpArrays arrays(binary_);
    std::string o;
    o.reserve((binary_ ? 64 : 160) * n + 4096);
    o += "<?xml version=\"1.0\"?>\n";
    o += arrays.root();
    o += "  <PolyData>\n    <FieldData>\n      <DataArray type=\"Float64\" Name=\"TIME\" NumberOfTuples=\"1\" format=\"ascii\">";
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
    const std::vector<Vec2>& pos = w.positions();
    const std::vector<Vec2>& vel = w.velocities();
    // a 2-D point or vector as (x, y, 0)
    auto xy0 = [](const std::vector<Vec2>& v) { return [&v](size_t i, int c) { return c < 2 ? v[i][c] : 0.0; }; };
    o += "\">\n      <Points>\n";
    arrays.add(o, "Float64", "Points", 3, n, xy0(pos), 12);
    o += "      </Points>\n      <PointData Scalars=\"radius\">\n";
    arrays.add(o, "Float64", "radius", 1, n, [&](size_t i, int) { return w.radii()[i]; });
    arrays.add(o, "Float64", "velocity", 3, n, xy0(vel));
    arrays.add(o, "Float64", "speed", 1, n, [&](size_t i, int) { return vel[i].norm(); });
    arrays.add(o, "Float64", "angle", 1, n, [&](size_t i, int) { return w.angles()[i]; });
    arrays.add(o, "Float64", "omega", 1, n, [&](size_t i, int) { return w.omegas()[i]; });
    // by the id each disc was added with (a lost disc leaves the world: World::disc_ids)
    const std::vector<int32_t>& ids = w.disc_ids();
    arrays.add(o, "Int32", "layer", 1, n, [&](size_t i, int) { const size_t k = size_t(ids[i]); return long(k < layer_.size() ? layer_[k] : 0); });
    arrays.add(o, "Int32", "grid", 1, n, [&](size_t i, int) { const size_t k = size_t(ids[i]); return long(k < grid_.size() ? grid_[k] : 0); });
    arrays.add(o, "Int32", "id", 1, n, [&](size_t i, int) { return long(ids[i]); });
    if (!bonds.empty()) {
        arrays.add(o, "Int32", "bonds_intact", 1, n, [&](size_t i, int) { return long(intact[i]); });
        arrays.add(o, "Int32", "bonds_broken", 1, n, [&](size_t i, int) { return long(broken[i]); });
    }
    o += "      </PointData>\n      <Verts>\n";
    arrays.add(o, "Int64", "connectivity", 1, n, [](size_t i, int) { return long(i); });
    arrays.add(o, "Int64", "offsets", 1, n, [](size_t i, int) { return long(i + 1); });
    o += "      </Verts>\n";
    if (!bonds.empty()) {
        o += "      <Lines>\n";
        arrays.add(o, "Int64", "connectivity", 1, bond_ends.size(), [&](size_t i, int) { return bond_ends[i]; });
        arrays.add(o, "Int64", "offsets", 1, bond_ends.size() / 2, [](size_t i, int) { return long(2 * i + 2); });
        o += "      </Lines>\n";
    }
    o += "    </Piece>\n";
    arrays.end(o);
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
    VtpArrays wall_arrays(binary_);
    std::string wo;
    wo += "<?xml version=\"1.0\"?>\n";
    wo += wall_arrays.root();
    wo += "  <PolyData>\n    <Piece NumberOfPoints=\"";
    put_int(wo, long(pts.size()));
    wo += "\" NumberOfLines=\"";
    put_int(wo, long(offsets.size()));
    wo += "\">\n      <Points>\n";
    wall_arrays.add(wo, "Float64", "Points", 3, pts.size(), xy0(pts), 12);
    wo += "      </Points>\n      <CellData>\n";
    wall_arrays.add(wo, "Int32", "wall", 1, wall_id.size(), [&](size_t i, int) { return long(wall_id[i]); });
    wo += "      </CellData>\n      <Lines>\n";
    wall_arrays.add(wo, "Int64", "connectivity", 1, pts.size(), [](size_t i, int) { return long(i); });
    wall_arrays.add(wo, "Int64", "offsets", 1, offsets.size(), [&](size_t i, int) { return offsets[i]; });
    wo += "      </Lines>\n    </Piece>\n";
    wall_arrays.end(wo);
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
