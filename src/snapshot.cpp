#include "snapshot.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include "fileio.h"

namespace demlab {

SnapshotWriter::SnapshotWriter(std::string dir, std::vector<int> layer, std::vector<int> grid)
    : dir_(std::move(dir)), layer_(std::move(layer)), grid_(std::move(grid)) {
    std::filesystem::create_directories(dir_);
}

namespace {
template <typename F>
void data_array(std::ostringstream& o, const char* type, const char* name, int components, size_t n, F value) {
    o << "        <DataArray type=\"" << type << "\" Name=\"" << name << "\" NumberOfComponents=\"" << components
      << "\" format=\"ascii\">\n";
    for (size_t i = 0; i < n; ++i) o << value(i) << (i + 1 == n ? "\n" : " ");
    o << "        </DataArray>\n";
}
}  // namespace

void SnapshotWriter::write(const World& w) {
    const int index = int(times_.size());
    char name[64];
    const size_t n = w.disc_count();
    std::ostringstream o;
    o.precision(9);
    o << "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
      << "  <PolyData>\n    <FieldData>\n      <DataArray type=\"Float64\" Name=\"TIME\" NumberOfTuples=\"1\" format=\"ascii\">"
      << w.time() << "</DataArray>\n    </FieldData>\n"
      << "    <Piece NumberOfPoints=\"" << n << "\" NumberOfVerts=\"" << n << "\">\n      <Points>\n";
    data_array(o, "Float64", "Points", 3, n, [&](size_t i) {
        std::ostringstream s;
        s.precision(12);
        s << w.positions()[i].x() << ' ' << w.positions()[i].y() << " 0";
        return s.str();
    });
    o << "      </Points>\n      <PointData Scalars=\"radius\">\n";
    data_array(o, "Float64", "radius", 1, n, [&](size_t i) { return w.radii()[i]; });
    data_array(o, "Float64", "velocity", 3, n, [&](size_t i) {
        std::ostringstream s;
        s.precision(9);
        s << w.velocities()[i].x() << ' ' << w.velocities()[i].y() << " 0";
        return s.str();
    });
    data_array(o, "Float64", "speed", 1, n, [&](size_t i) { return w.velocities()[i].norm(); });
    data_array(o, "Float64", "angle", 1, n, [&](size_t i) { return w.angles()[i]; });
    data_array(o, "Float64", "omega", 1, n, [&](size_t i) { return w.omegas()[i]; });
    data_array(o, "Int32", "layer", 1, n, [&](size_t i) { return i < layer_.size() ? layer_[i] : 0; });
    data_array(o, "Int32", "grid", 1, n, [&](size_t i) { return i < grid_.size() ? grid_[i] : 0; });
    data_array(o, "Int32", "id", 1, n, [&](size_t i) { return long(i); });
    o << "      </PointData>\n      <Verts>\n";
    data_array(o, "Int64", "connectivity", 1, n, [&](size_t i) { return long(i); });
    data_array(o, "Int64", "offsets", 1, n, [&](size_t i) { return long(i + 1); });
    o << "      </Verts>\n    </Piece>\n  </PolyData>\n</VTKFile>\n";
    std::snprintf(name, sizeof name, "/discs_%05d.vtp", index);
    write_file_atomic(dir_ + name, o.str());

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
    std::ostringstream wo;
    wo.precision(12);
    wo << "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
       << "  <PolyData>\n    <Piece NumberOfPoints=\"" << pts.size() << "\" NumberOfLines=\"" << offsets.size()
       << "\">\n      <Points>\n";
    data_array(wo, "Float64", "Points", 3, pts.size(), [&](size_t i) {
        std::ostringstream s;
        s.precision(12);
        s << pts[i].x() << ' ' << pts[i].y() << " 0";
        return s.str();
    });
    wo << "      </Points>\n      <CellData>\n";
    data_array(wo, "Int32", "wall", 1, wall_id.size(), [&](size_t i) { return wall_id[i]; });
    wo << "      </CellData>\n      <Lines>\n";
    data_array(wo, "Int64", "connectivity", 1, pts.size(), [&](size_t i) { return long(i); });
    data_array(wo, "Int64", "offsets", 1, offsets.size(), [&](size_t i) { return offsets[i]; });
    wo << "      </Lines>\n    </Piece>\n  </PolyData>\n</VTKFile>\n";
    std::snprintf(name, sizeof name, "/walls_%05d.vtp", index);
    write_file_atomic(dir_ + name, wo.str());
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
