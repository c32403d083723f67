#include "output/frame.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string_view>
#include <type_traits>

#include "core/csv.h"
#include "core/error.h"
#include "core/fileio.h"
#include "run/dan_run.h"
#include "run/vtk_zlib_blocks.h"
#include "scenario/scenario.h"
#include "setups/flume.h"

namespace demlab {

namespace {
std::string slurp(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError(path + ": cannot open the snapshot");
    in.seekg(0, std::ios::end);
    const std::streamoff size = in.tellg();
    in.seekg(0, std::ios::beg);
    std::string text(size > 0 ? size_t(size) : 0, '\0');
    if (size < 0 || !in.read(text.data(), std::streamsize(text.size()))) throw InputError(path + ": cannot read the snapshot");
    return text;
}

// One <DataArray> of our own VTK files: its text (format="ascii"), or its decoded bytes
// (format="appended": raw binary, zlib-compressed; vtk_zlib_blocks.h) and their type.
struct ArrayRef {
    std::string_view text;
    bool binary = false;
    std::string bytes;
    std::string type;  // Float64, Int32, Int64
};

std::string attribute(std::string_view tag, const char* name) {
    const std::string key = std::string(" ") + name + "=\"";
    const size_t at = tag.find(key);
    if (at == std::string_view::npos) return "";
    const size_t end = tag.find('"', at + key.size());
    return end == std::string_view::npos ? "" : std::string(tag.substr(at + key.size(), end - at - key.size()));
}

// Every <DataArray Name="..."> of a file, by name; a name met again (the bond lines'
// connectivity after the vertices') is stored as NAME#1, NAME#2, ... Text arrays are views
// into xml (no copies: a frame's text is about a megabyte).
std::map<std::string, ArrayRef> data_arrays(const std::string& xml, const std::string& path) {
    std::map<std::string, ArrayRef> out;
    const std::string_view all(xml);
    // the appended data: after "_" up to its closing tag (the arrays' offsets count from there)
    std::string_view appended;
    const size_t app = all.find("<AppendedData");
    if (app != std::string_view::npos) {
        const size_t start = all.find('_', app);
        const size_t stop = all.rfind("</AppendedData>");
        if (start == std::string_view::npos || stop == std::string_view::npos || stop < start)
            throw InputError(path + ": malformed AppendedData");
        appended = all.substr(start + 1, stop - start - 1);
    }
    const std::string_view head = all.substr(0, app);
    const size_t root = head.find("<VTKFile");
    const std::string_view root_tag = root == std::string_view::npos ? std::string_view() : head.substr(root, head.find('>', root) - root);
    const bool zlib = attribute(root_tag, "compressor") == "vtkZLibDataCompressor";
    size_t pos = 0;
    while ((pos = head.find("<DataArray", pos)) != std::string_view::npos) {
        const size_t tag_end = head.find('>', pos);
        if (tag_end == std::string_view::npos) throw InputError(path + ": malformed DataArray");
        const std::string_view tag = head.substr(pos, tag_end - pos + 1);
        std::string key = attribute(tag, "Name");
        if (key.empty()) throw InputError(path + ": malformed DataArray");
        for (int k = 1; out.count(key); ++k) key = attribute(tag, "Name") + "#" + std::to_string(k);
        ArrayRef& a = out[key];
        if (attribute(tag, "format") == "appended") {
            if (!zlib || attribute(root_tag, "header_type") != "UInt64")
                throw InputError(path + ": appended data other than demlab's (zlib-compressed, UInt64 headers)");
            const std::string offset = attribute(tag, "offset");
            size_t off = 0;
            const auto r = std::from_chars(offset.data(), offset.data() + offset.size(), off);
            if (r.ec != std::errc() || r.ptr != offset.data() + offset.size()) throw InputError(path + ": DataArray '" + key + "' has a bad offset");
            a.binary = true;
            a.type = attribute(tag, "type");
            a.bytes = read_zlib_blocks(appended, off, path);
            pos = tag_end;
            continue;
        }
        const size_t close = head.find("</DataArray>", tag_end);
        if (close == std::string_view::npos) throw InputError(path + ": unterminated DataArray '" + key + "'");
        a.text = head.substr(tag_end + 1, close - tag_end - 1);
        pos = close;
    }
    return out;
}

std::map<std::string, ArrayRef> data_arrays(std::string&&, const std::string&) = delete;  // views into a temporary

// The values of decoded bytes of type V as T, up to the first that is not finite.
template <typename T, typename V>
void decode(const std::string& bytes, std::vector<T>& v) {
    const size_t n = bytes.size() / sizeof(V);
    v.reserve(n);
    for (size_t i = 0; i < n; ++i) {
        V x;
        std::memcpy(&x, bytes.data() + i * sizeof(V), sizeof(V));
        if constexpr (std::is_floating_point_v<V>)
            if (!std::isfinite(x)) break;
        v.push_back(T(x));
    }
}

// The numbers of an array, up to the first text that is not one (as reading it with
// operator>> did; the callers check the lengths). std::from_chars rounds correctly, as
// strtod under operator>> does, so the values are the same, and it takes a fifth of the time
// (the parsing was a tenth of rendering a frame).
template <typename T>
std::vector<T> numbers(const std::map<std::string, ArrayRef>& a, const std::string& key, const std::string& path) {
    auto it = a.find(key);
    if (it == a.end()) throw InputError(path + ": no DataArray '" + key + "'");
    std::vector<T> v;
    if (it->second.binary) {
        const ArrayRef& r = it->second;
        if (r.type == "Float64") decode<T, double>(r.bytes, v);
        else if (r.type == "Int32") decode<T, int32_t>(r.bytes, v);
        else if (r.type == "Int64") decode<T, int64_t>(r.bytes, v);
        else throw InputError(path + ": DataArray '" + key + "' of type '" + r.type + "' (Float64, Int32 or Int64 expected)");
        return v;
    }
    const char* p = it->second.text.data();
    const char* const end = p + it->second.text.size();
    while (true) {
        while (p < end && (*p == ' ' || *p == '\n' || *p == '\t' || *p == '\r')) ++p;
        if (p == end) break;
        T x{};
        const auto r = std::from_chars(p, end, x);
        if (r.ec != std::errc()) break;
        // "nan" and "inf" end the array as operator>> did (it reads neither): a frame is not
        // drawn from a state that is not finite
        if constexpr (std::is_floating_point_v<T>)
            if (!std::isfinite(x)) break;
        v.push_back(x);
        p = r.ptr;
    }
    return v;
}
}  // namespace

Frame read_frame(const std::string& discs_vtp, const std::string& walls_vtp) {
    Frame f;
    {
        const std::string text = slurp(discs_vtp);  // data_arrays' views point into it
        const auto a = data_arrays(text, discs_vtp);
        const auto time = numbers<double>(a, "TIME", discs_vtp);
        f.time = time.empty() ? 0.0 : time[0];
        const auto pts = numbers<double>(a, "Points", discs_vtp);
        f.radius = numbers<double>(a, "radius", discs_vtp);
        f.angle = numbers<double>(a, "angle", discs_vtp);
        f.speed = numbers<double>(a, "speed", discs_vtp);
        f.layer = numbers<int>(a, "layer", discs_vtp);
        f.grid = numbers<int>(a, "grid", discs_vtp);
        const size_t n = f.radius.size();
        if (pts.size() != 3 * n || f.angle.size() != n || f.speed.size() != n || f.layer.size() != n || f.grid.size() != n)
            throw InputError(discs_vtp + ": arrays of different lengths");
        for (size_t i = 0; i < n; ++i) f.pos.emplace_back(pts[3 * i], pts[3 * i + 1]);
        if (a.count("bonds_intact")) {
            f.bonds_intact = numbers<int>(a, "bonds_intact", discs_vtp);
            f.bonds_broken = numbers<int>(a, "bonds_broken", discs_vtp);
            if (f.bonds_intact.size() != n || f.bonds_broken.size() != n)
                throw InputError(discs_vtp + ": arrays of different lengths");
            // the intact bonds: the connectivity of the <Lines> cells (pairs of disc ids), the
            // second connectivity array after the vertices'
            if (a.count("connectivity#1")) {
                const auto ends = numbers<long>(a, "connectivity#1", discs_vtp);
                if (ends.size() % 2) throw InputError(discs_vtp + ": a bond line without its second disc");
                for (size_t k = 0; k + 1 < ends.size(); k += 2) {
                    if (ends[k] < 0 || ends[k + 1] < 0 || size_t(ends[k]) >= n || size_t(ends[k + 1]) >= n)
                        throw InputError(discs_vtp + ": a bond names a disc that is not in the file");
                    f.bonds.emplace_back(int(ends[k]), int(ends[k + 1]));
                }
            }
        }
    }
    {
        const std::string text = slurp(walls_vtp);
        const auto a = data_arrays(text, walls_vtp);
        const auto pts = numbers<double>(a, "Points", walls_vtp);
        const auto offsets = numbers<long>(a, "offsets", walls_vtp);
        f.wall_id = numbers<int>(a, "wall", walls_vtp);
        long start = 0;
        for (long end : offsets) {
            if (end < start || size_t(3 * end) > pts.size()) throw InputError(walls_vtp + ": bad offsets");
            std::vector<Vec2> line;
            for (long k = start; k < end; ++k) line.emplace_back(pts[size_t(3 * k)], pts[size_t(3 * k + 1)]);
            f.walls.push_back(line);
            start = end;
        }
        if (f.wall_id.size() != f.walls.size()) throw InputError(walls_vtp + ": wall ids do not match the lines");
    }
    return f;
}

std::vector<Frame> read_dan_frames(const std::string& run_dir) {
    const std::string scenario_file = run_dir + "/scenario.toml", blocks_file = run_dir + "/blocks.csv";
    Scenario s = parse_scenario(read_input_file(scenario_file, kMaxScenarioBytes, "scenario file"), scenario_file);
    finish_scenario(s);
    const DanPath path = flume_dan_path(s);
    // the flume's walls as the DEM snapshots draw them: segments, the arc in 48 pieces
    std::vector<std::vector<Vec2>> walls;
    const std::vector<WallDef> defs = flume_walls(s, false);
    for (int k = 0; k <= kW3; ++k) {
        const WallGeom g = make_geom(defs[size_t(k)]);
        std::vector<Vec2> line;
        if (g.shape == WallShape::Segment) {
            line = {g.p0, g.p1};
        } else {
            for (int j = 0; j <= 48; ++j) {
                const double a = g.angle0 + g.extent * j / 48.0;
                line.push_back(g.centre + g.radius * Vec2(std::cos(a), std::sin(a)));
            }
        }
        walls.push_back(line);
    }
    std::ifstream in(blocks_file);
    if (!in) throw InputError(run_dir + ": no blocks.csv (was output.snapshot_interval 0?)");
    std::string line;
    std::getline(in, line);
    const CsvHeader header(line, blocks_file);
    const size_t ct = header.column("t_s", "t"), cs = header.column("s_m", "s"), ch = header.column("H_m", "H");
    const size_t columns = header.names().size();
    std::vector<Frame> frames;
    std::vector<std::pair<Vec2, Vec2>> column;  // bed point, surface point of each boundary block
    double t_now = NAN;
    auto close_frame = [&] {
        if (column.empty()) return;
        Frame f;
        f.time = t_now;
        f.walls = walls;
        f.wall_id = {0, 1, 2};
        for (size_t i = 0; i + 1 < column.size(); ++i)
            f.fills.push_back({{column[i].first, column[i + 1].first, column[i + 1].second, column[i].second}});
        frames.push_back(std::move(f));
        column.clear();
    };
    long row = 1;
    while (std::getline(in, line)) {
        ++row;
        std::vector<double> v;
        const std::string at = blocks_file + ":" + std::to_string(row);
        for (const std::string& cell : csv_cells(line)) v.push_back(parse_number_cell(cell, at));
        if (v.size() != columns) throw InputError(at + ": expected " + std::to_string(columns) + " columns");
        if (!std::isfinite(v[ct]) || !std::isfinite(v[cs]) || !(v[ch] >= 0.0 && std::isfinite(v[ch])))
            throw InputError(at + ": t_s and s_m must be finite numbers and H_m a finite thickness from 0");
        if (v[ct] != t_now) {
            close_frame();
            t_now = v[ct];
        }
        // H is the thickness normal to the bed; a vertical column's surface lies H / cos(alpha)
        // straight above its bed point
        const DanPathPoint q = path.at(v[cs]);
        const double H = v[ch];
        const Vec2 up = s.dan.columns == DanColumns::Vertical ? Vec2(0.0, H / std::cos(q.alpha)) : Vec2(H * q.normal());
        column.emplace_back(q.p, q.p + up);
    }
    close_frame();
    if (frames.empty()) throw InputError(blocks_file + ": no rows");
    return frames;
}

std::vector<SnapshotEntry> list_snapshots(const std::string& run_dir) {
    namespace fs = std::filesystem;
    const std::string dir = run_dir + "/snapshots";
    if (!fs::is_directory(dir)) throw InputError(run_dir + ": no snapshots/ folder (was output.snapshot_interval 0?)");
    std::vector<SnapshotEntry> out;
    const std::string index = dir + "/discs.pvd";
    std::ifstream pvd(index);
    if (pvd) {
        std::string line;
        long row = 0;
        // the attribute's value between its quotes ("" when it has no closing quote)
        auto attribute = [&](size_t at, size_t name_length) {
            const size_t from = at + name_length, to = line.find('"', from);
            return to == std::string::npos ? std::string() : line.substr(from, to - from);
        };
        while (std::getline(pvd, line)) {
            ++row;
            const size_t ts = line.find("timestep=\""), file = line.find("file=\"");
            if (ts == std::string::npos || file == std::string::npos) continue;
            // the index is the run's own: a time that is not a finite number, or a file that is
            // not one of the folder's discs_*.vtp (a path elsewhere), is a damaged index
            const std::string where = index + ":" + std::to_string(row);
            const double t = parse_number_cell(attribute(ts, 10), where);
            if (!std::isfinite(t)) throw InputError(where + ": the snapshot's time must be a finite number");
            const std::string name = attribute(file, 6);
            if (name.rfind("discs_", 0) != 0 || name.find('/') != std::string::npos || name.find('\\') != std::string::npos ||
                name.size() < 11 || name.compare(name.size() - 4, 4, ".vtp") != 0)
                throw InputError(where + ": '" + name + "' is not a snapshot file of this folder (discs_NNNNN.vtp)");
            std::string walls = name;
            walls.replace(0, 5, "walls");
            out.push_back({t, dir + "/" + name, dir + "/" + walls});
        }
    }
    if (out.empty()) {
        // an interrupted run has no collection yet: take the files in order
        std::vector<std::string> names;
        for (const auto& e : fs::directory_iterator(dir)) {
            const std::string n = e.path().filename().string();
            if (n.rfind("discs_", 0) == 0 && e.path().extension() == ".vtp") names.push_back(n);
        }
        std::sort(names.begin(), names.end());
        for (const auto& n : names) {
            std::string walls = n;
            walls.replace(0, 5, "walls");
            out.push_back({-1.0, dir + "/" + n, dir + "/" + walls});
        }
    }
    if (out.empty()) throw InputError(run_dir + ": the snapshots/ folder holds no snapshot");
    return out;
}

}  // namespace demlab
