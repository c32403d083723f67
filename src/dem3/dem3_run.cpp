#include "dem3/dem3_run.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include "core/error.h"
#include "core/fileio.h"
#include "core/machine.h"
#include "dem3/close_packing.h"
#include "dem3/peak_rasters.h"
#include "dem3/sphere_bonds.h"
#include "dem3/world3.h"
#include "run/summary_file.h"

namespace demlab {

namespace {

bool is_grid_file(const std::string& path) {
    std::string ext = std::filesystem::path(path).extension().string();
    for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));  // .asc, .ASC, .Asc
    return ext == ".asc";
}

// a terrain file as a TIN, and the grid it came from (an empty grid for points); `key` names
// the key that gave the file in its errors
std::shared_ptr<const Tin> read_terrain(const std::string& path, const std::string& key, EsriGrid* grid) {
    if (is_grid_file(path)) {
        EsriGrid g = read_esri_grid(path, "elevation grid (" + key + ")");
        auto tin = std::make_shared<const Tin>(Tin::from_grid(g, path));
        if (grid) *grid = std::move(g);
        return tin;
    }
    return std::make_shared<const Tin>(Tin::from_points(read_xyz_points(path, "x y z point file (" + key + ")"), path));
}

class Dem3Loop final : public Solver {
public:
    explicit Dem3Loop(World3& w) : w_(w) {}
    void step() override { w_.step(); }
    double time() const override { return w_.time(); }
    double dt() const override { return w_.dt(); }
    long step_count() const override { return w_.step_count(); }
    double kinetic_energy() const override { return w_.kinetic_energy(); }
    EnergyReport energy() const override {
        const Energy3 e = w_.energy();
        EnergyReport r;
        r.kinetic_translation = e.kinetic;
        r.potential = e.potential;
        r.elastic = e.elastic;
        r.dissipated_contacts = e.dissipated;
        r.bond_elastic = e.bond_elastic;
        r.bond_break_loss = e.bond_broken;
        r.lost_with_discs = e.lost;
        return r;
    }
    void save_state(BinaryWriter& out) const override { w_.save_state(out); }
    void load_state(BinaryReader& in) override { w_.load_state(in); }

private:
    World3& w_;
};

constexpr const char* kSeriesColumns =
    "t_s,kinetic_J,potential_J,elastic_J,dissipated_J,balance_J,centre_x_m,centre_y_m,centre_z_m,max_travel_m,"
    "max_speed_m_per_s,moving_spheres,contacts,lost_spheres,dt_s,intact_bonds,bond_elastic_J,bond_broken_J";

class Dem3Run final : public SolverRun {
public:
    Dem3Run(const Scenario& s, const RunOptions& o)
        : s_(s), dir_(o.out_dir), frames_(o.frames), terrain_frames_(o.terrain_frames), raster_picture_(o.raster_picture),
          on_snapshot_(o.on_snapshot) {
        const Dem3Scenario& d = s.dem3;
        EsriGrid grid;
        tin_ = read_terrain(d.terrain, "dem3.terrain", &grid);
        std::shared_ptr<const Tin> top;
        if (!d.release_top.empty()) top = read_terrain(d.release_top, "dem3.release_top", nullptr);
        auto top_at = [&](double x, double y, double& z) {
            if (top) return top->height_at(x, y, z);
            if (!tin_->height_at(x, y, z)) return false;
            z += d.release_thickness;
            return true;
        };
        try {
            release_ = close_packed_release(*tin_, top_at, d.release_lo, d.release_hi, d.radius, d.release_layers);
        } catch (const InputError& e) {
            throw InputError(s.source + ": " + e.what());
        }
        if (release_.centres.empty())
            throw InputError(s.source + ": the release box [" + format_number(d.release_lo.x()) + ", " + format_number(d.release_lo.y()) +
                             "] - [" + format_number(d.release_hi.x()) + ", " + format_number(d.release_hi.y()) +
                             "] m holds no sphere of dem3.radius = " + format_number(d.radius) +
                             " m between the bed and the top: check the box, the top surface or the thickness");
        Dem3Def law = d.law;
        law.threads = std::max(1, s.world.threads);
        world_ = std::make_unique<World3>(law, tin_);
        for (const Vec3& p : release_.centres) world_->add_sphere(p, Vec3::Zero(), d.radius, d.density);
        start_ = world_->positions();
        if (s.cohesion.enabled) {
            // the slab's bonds: the filtered Delaunay edges between the release's centres
            std::vector<double> radii(release_.centres.size(), d.radius);
            const auto bonds = delaunay_bonds3(release_.centres, radii, with_default_gap(s.cohesion.build, d.radius), &bond_report_);
            if (bonds.empty())
                throw InputError(s.source + ": cohesion.enabled = true, but the triangulation of the " +
                                 std::to_string(release_.centres.size()) + " sphere centres gave no bond with cohesion.filter's rule");
            world_->set_bonds(s.cohesion.bond, bonds);
        }
        world_->measure();  // the first row's ledger
        solver_ = std::make_unique<Dem3Loop>(*world_);
        // the rasters: the terrain's grid, or one over the TIN's box
        if (grid.ncols == 0 || d.raster_cell > 0.0) {
            const double cell = d.raster_cell > 0.0 ? d.raster_cell : 2.0 * d.radius;
            const Vec3 lo = tin_->lower_corner(), hi = tin_->upper_corner();
            grid = EsriGrid{};
            grid.cellsize = cell;
            grid.x0 = lo.x() + 0.5 * cell;
            grid.y0 = lo.y() + 0.5 * cell;
            // counted in doubles: a wide terrain over a small cell would overflow an int
            const double cols = std::max(1.0, std::ceil((hi.x() - lo.x()) / cell));
            const double rows = std::max(1.0, std::ceil((hi.y() - lo.y()) / cell));
            if (!(cols * rows <= 5e7))
                throw InputError(s.source + ": the peak rasters over the terrain's " + format_number(hi.x() - lo.x()) + " m x " +
                                 format_number(hi.y() - lo.y()) + " m at cells of " + format_number(cell) + " m (dem3.raster_cell" +
                                 (d.raster_cell > 0.0 ? "" : " 0: two radii") + ") would have " + format_number(cols * rows) +
                                 " cells, more than 50 million: give a larger dem3.raster_cell");
            grid.ncols = int(cols);
            grid.nrows = int(rows);
            grid.z.assign(size_t(grid.ncols) * size_t(grid.nrows), 0.0);
            for (int r = 0; r < grid.nrows; ++r)
                for (int c = 0; c < grid.ncols; ++c) {
                    double z = 0.0;
                    grid.z[size_t(r) * size_t(grid.ncols) + size_t(c)] = tin_->height_at(grid.x0 + c * cell, grid.y0 + r * cell, z) ? z : NAN;
                }
        }
        terrain_grid_ = grid;
        // the bulk density of the release's packing: the rasters' thickness holds its volume
        solid_fraction_ = release_.bulk_volume > 0.0 ? std::min(1.0, release_.solid_volume / release_.bulk_volume) : 0.7405;
        rasters_ = std::make_unique<PeakRasters>(grid, d.density * solid_fraction_);
        dt_min_ = INFINITY;
    }

    Solver& solver() override { return *solver_; }
    LoopClock clock() override { return LoopClock{next_series_, next_snap_, peak_ke_, rest_since_}; }

    RunParts parts(const RunOptions&) override {
        RunParts p;
        p.sample = [this] { sample(); };
        if (s_.output.snapshot_interval > 0) p.snapshot = [this] { snapshot(); };
        p.after_step = [this]() -> std::string {
            dt_min_ = std::min(dt_min_, world_->dt());
            dt_max_ = std::max(dt_max_, world_->dt());
            if (world_->lost_count() == world_->size()) return "all spheres left the terrain";
            return "";
        };
        return p;
    }

    void open() override {
        series_.open(dir_ + "/series.csv");
        series_.out() << kSeriesColumns << '\n';
        if (s_.output.snapshot_interval > 0) write_terrain_vtp();
    }

    void save(BinaryWriter& out, double elapsed) override {
        for (double v : {next_series_, next_snap_, peak_ke_, rest_since_, dt_min_, dt_max_, max_speed_, max_travel_, elapsed}) out.put(v);
        out.put(std::uint64_t(snap_times_.size()));
        for (double t : snap_times_) out.put(t);
        out.put(series_.flush());
        world_->save_state(out);
        rasters_->save(out);
    }

    void load(BinaryReader& in, double& elapsed) override {
        for (double* v : {&next_series_, &next_snap_, &peak_ke_, &rest_since_, &dt_min_, &dt_max_, &max_speed_, &max_travel_, &elapsed})
            in.get(*v);
        std::uint64_t n = 0;
        in.get(n);
        snap_times_.assign(size_t(n), 0.0);
        for (double& t : snap_times_) in.get(t);
        std::uint64_t size = 0;
        in.get(size);
        series_.reopen(dir_ + "/series.csv", size);
        world_->load_state(in);
        rasters_->load(in);
        if (!in.at_end()) throw InputError(dir_ + "/" + kCheckpointFile + ": corrupt checkpoint (trailing bytes)");
    }

    RunSummary finish(const std::string& stop_reason, const std::vector<ScenarioInput>&, double wall_seconds) override;

private:
    void sample();
    void snapshot();
    void write_terrain_vtp() const;
    void write_frames(const std::string& tag) const;

    const Scenario& s_;
    std::string dir_;
    bool frames_ = false;
    decltype(RunOptions::terrain_frames) terrain_frames_;
    decltype(RunOptions::raster_picture) raster_picture_;
    decltype(RunOptions::on_snapshot) on_snapshot_;
    std::shared_ptr<const Tin> tin_;
    EsriGrid terrain_grid_;
    ClosePackedRelease release_;
    BondBuildReport bond_report_;
    double solid_fraction_ = 0.0;
    std::unique_ptr<World3> world_;
    std::unique_ptr<Dem3Loop> solver_;
    std::unique_ptr<PeakRasters> rasters_;
    std::vector<Vec3> start_;
    SeriesFile series_;
    std::vector<double> snap_times_;
    double next_series_ = 0, next_snap_ = 0, peak_ke_ = 0, rest_since_ = -1;
    double dt_min_ = INFINITY, dt_max_ = 0.0, max_speed_ = 0.0, max_travel_ = 0.0;
};

void Dem3Run::sample() {
    const World3& w = *world_;
    const Energy3 e = w.energy();
    Vec3 centre = Vec3::Zero();
    double mass = 0.0, speed = 0.0, travel = 0.0;
    long moving = 0;
    for (size_t i = 0; i < w.size(); ++i) {
        if (w.lost()[i]) continue;
        centre += w.masses()[i] * w.positions()[i];
        mass += w.masses()[i];
        const double v = w.velocities()[i].norm();
        speed = std::max(speed, v);
        moving += v > 0.01;  // 1 cm/s
        travel = std::max(travel, (w.positions()[i] - start_[i]).head<2>().norm());
    }
    if (mass > 0.0) centre /= mass;
    max_speed_ = std::max(max_speed_, speed);
    max_travel_ = std::max(max_travel_, travel);
    char row[512];
    std::snprintf(row, sizeof row, "%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%ld,%ld,%zu,%.6g,%zu,%.9g,%.9g\n", w.time(),
                  e.kinetic, e.potential, e.elastic, e.dissipated, e.balance(), centre.x(), centre.y(), centre.z(), travel, speed,
                  moving, w.contacts(), w.lost_count(), w.dt(), w.intact_bonds(), e.bond_elastic, e.bond_broken);
    series_.out() << row;
    series_.check();
    rasters_->sample(w.positions(), w.velocities(), w.masses());
}

void Dem3Run::write_terrain_vtp() const {
    std::filesystem::create_directories(dir_ + "/snapshots");
    std::ostringstream o;
    o.precision(10);
    const auto& v = tin_->vertices();
    const auto& t = tin_->triangles();
    o << "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"0.1\" byte_order=\"LittleEndian\">\n<PolyData>\n"
      << "<Piece NumberOfPoints=\"" << v.size() << "\" NumberOfPolys=\"" << t.size() << "\">\n<Points>\n"
      << "<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n";
    for (const Vec3& p : v) o << p.x() << ' ' << p.y() << ' ' << p.z() << '\n';
    o << "</DataArray>\n</Points>\n<Polys>\n<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n";
    for (const auto& tri : t) o << tri[0] << ' ' << tri[1] << ' ' << tri[2] << '\n';
    o << "</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n";
    for (size_t k = 0; k < t.size(); ++k) o << 3 * (k + 1) << '\n';
    o << "</DataArray>\n</Polys>\n</Piece>\n</PolyData>\n</VTKFile>\n";
    write_file_atomic(dir_ + "/snapshots/terrain.vtp", o.str());
}

void Dem3Run::snapshot() {
    const World3& w = *world_;
    std::filesystem::create_directories(dir_ + "/snapshots");
    std::ostringstream o;
    o.precision(10);
    o << "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"0.1\" byte_order=\"LittleEndian\">\n<PolyData>\n"
      << "<Piece NumberOfPoints=\"" << w.size() << "\" NumberOfVerts=\"" << w.size() << "\" NumberOfLines=\"" << w.intact_bonds()
      << "\">\n<PointData Scalars=\"radius\">\n"
      << "<DataArray type=\"Float64\" Name=\"radius\" format=\"ascii\">\n";
    for (double r : w.radii()) o << r << '\n';
    o << "</DataArray>\n<DataArray type=\"Float64\" Name=\"velocity\" NumberOfComponents=\"3\" format=\"ascii\">\n";
    for (const Vec3& v : w.velocities()) o << v.x() << ' ' << v.y() << ' ' << v.z() << '\n';
    o << "</DataArray>\n<DataArray type=\"UInt8\" Name=\"lost\" format=\"ascii\">\n";
    for (std::uint8_t l : w.lost()) o << int(l) << '\n';
    o << "</DataArray>\n</PointData>\n<Points>\n<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n";
    for (const Vec3& p : w.positions()) o << p.x() << ' ' << p.y() << ' ' << p.z() << '\n';
    o << "</DataArray>\n</Points>\n<Verts>\n<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n";
    for (size_t k = 0; k < w.size(); ++k) o << k << '\n';
    o << "</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n";
    for (size_t k = 0; k < w.size(); ++k) o << k + 1 << '\n';
    o << "</DataArray>\n</Verts>\n";
    if (w.intact_bonds() > 0) {  // the intact bonds as lines between the centres
        o << "<Lines>\n<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n";
        for (const Bond& b : w.bonds())
            if (!b.broken) o << b.k << ' ' << b.l << '\n';
        o << "</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n";
        for (size_t k = 0; k < w.intact_bonds(); ++k) o << 2 * (k + 1) << '\n';
        o << "</DataArray>\n</Lines>\n";
    }
    o << "</Piece>\n</PolyData>\n</VTKFile>\n";
    char name[64];
    std::snprintf(name, sizeof name, "/snapshots/spheres_%04zu.vtp", snap_times_.size());
    write_file_atomic(dir_ + name, o.str());
    snap_times_.push_back(w.time());
    std::ostringstream pvd;
    pvd.precision(10);
    pvd << "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n<Collection>\n";
    for (size_t k = 0; k < snap_times_.size(); ++k) {
        std::snprintf(name, sizeof name, "spheres_%04zu.vtp", k);
        pvd << "<DataSet timestep=\"" << snap_times_[k] << "\" file=\"" << name << "\"/>\n";
    }
    pvd << "</Collection>\n</VTKFile>\n";
    write_file_atomic(dir_ + "/snapshots/spheres.pvd", pvd.str());
    if (frames_) {
        std::snprintf(name, sizeof name, "%04zu", snap_times_.size() - 1);
        write_frames(name);
    }
    if (on_snapshot_) {
        std::snprintf(name, sizeof name, "/snapshots/spheres_%04zu.vtp", snap_times_.size() - 1);
        on_snapshot_(dir_ + name, "", int(snap_times_.size()) - 1);
    }
}

void Dem3Run::write_frames(const std::string& tag) const {
    if (!terrain_frames_) return;
    const World3& w = *world_;
    std::vector<Vec3> centres;
    std::vector<double> radius, speed;
    for (size_t i = 0; i < w.size(); ++i) {
        if (w.lost()[i]) continue;
        centres.push_back(w.positions()[i]);
        radius.push_back(w.radii()[i]);
        speed.push_back(w.velocities()[i].norm());
    }
    std::filesystem::create_directories(dir_ + "/frames");
    terrain_frames_(dir_, tag, *tin_, centres, radius, speed, std::max(1.0, max_speed_));
}

RunSummary Dem3Run::finish(const std::string& stop_reason, const std::vector<ScenarioInput>& inputs, double wall_seconds) {
    const World3& w = *world_;
    // (the loop has sampled the last instant already; the rasters take it as the deposit)
    if (s_.output.snapshot_interval > 0 && (snap_times_.empty() || snap_times_.back() != w.time())) snapshot();
    series_.close();
    rasters_->finish(w.positions(), w.velocities(), w.masses());
    rasters_->write(dir_);
    const double h_max = *std::max_element(rasters_->peak_thickness().begin(), rasters_->peak_thickness().end());
    const double v_max = *std::max_element(rasters_->peak_speed().begin(), rasters_->peak_speed().end());
    const std::vector<double>& deposit = rasters_->deposit_thickness();
    const double d_max = *std::max_element(deposit.begin(), deposit.end());
    if (raster_picture_) {
        raster_picture_(dir_ + "/peak_thickness.png", terrain_grid_, rasters_->peak_thickness(), std::max(h_max, 1e-9));
        raster_picture_(dir_ + "/peak_speed.png", terrain_grid_, rasters_->peak_speed(), std::max(v_max, 1e-9));
        raster_picture_(dir_ + "/deposit_thickness.png", terrain_grid_, deposit, std::max(d_max, 1e-9));
    }
    write_frames("last");
    // the deposit's extent in map view: the cells it covers
    const EsriGrid& g = rasters_->grid();
    double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
    for (int r = 0; r < g.nrows; ++r)
        for (int c = 0; c < g.ncols; ++c)
            if (deposit[size_t(r) * size_t(g.ncols) + size_t(c)] > 0.0) {
                x0 = std::min(x0, g.x0 + c * g.cellsize);
                x1 = std::max(x1, g.x0 + c * g.cellsize);
                y0 = std::min(y0, g.y0 + r * g.cellsize);
                y1 = std::max(y1, g.y0 + r * g.cellsize);
            }
    RunSummary sum;
    sum.n_discs = long(w.size());
    sum.steps = w.step_count();
    sum.t_end = w.time();
    sum.dt = w.dt();
    sum.dt_min = dt_min_;
    sum.dt_max = dt_max_;
    sum.stop_reason = stop_reason;
    sum.wall_seconds = wall_seconds;
    sum.particle_steps_per_second = double(w.size()) * double(w.step_count()) / std::max(wall_seconds, 1e-9);
    const Energy3 e = w.energy();
    SummaryJson j;
    j.text("scenario", s_.name);
    j.text("scenario_fingerprint", scenario_fingerprint(s_, inputs));
    j.text("model", "dem3");
    j.integer("spheres", long(w.size()));
    j.number("radius", s_.dem3.radius, "m");
    j.number("solid_volume", release_.solid_volume, "m3");
    j.number("release_bulk_volume", release_.bulk_volume, "m3");
    j.number("release_solid_fraction", solid_fraction_, "-");
    j.integer("steps", sum.steps);
    j.number("t_end", sum.t_end, "s");
    j.text("stop_reason", sum.stop_reason);
    j.number("dt_min", sum.dt_min, "s");
    j.number("dt_max", sum.dt_max, "s");
    j.number("wall_seconds", sum.wall_seconds, "s");
    j.number("particle_steps_per_second", sum.particle_steps_per_second, "1/s");
    j.text("machine", machine_summary(machine_info()));
    j.number("max_speed", max_speed_, "m/s");
    j.number("max_travel", max_travel_, "m");
    j.number("deposit_max_thickness", d_max, "m");
    j.number("deposit_x_min", x0, "m");
    j.number("deposit_x_max", x1, "m");
    j.number("deposit_y_min", y0, "m");
    j.number("deposit_y_max", y1, "m");
    j.number("deposit_volume", rasters_->volume(deposit), "m3");
    j.number("peak_thickness_max", h_max, "m");
    j.number("peak_speed_max", v_max, "m/s");
    j.integer("lost_spheres", long(w.lost_count()));
    j.number("energy_kinetic", e.kinetic, "J");
    j.number("energy_dissipated", e.dissipated, "J");
    if (!w.bonds().empty()) {
        j.integer("bonds", long(w.bonds().size()));
        j.integer("bonds_broken", long(w.bonds().size() - w.intact_bonds()));
        j.number("bonds_broken_fraction", double(w.bonds().size() - w.intact_bonds()) / double(w.bonds().size()), "-");
        j.number("bond_mean_rest_length", bond_report_.mean_rest_length, "m");
        j.number("first_bond_break", w.bond_breaks().empty() ? NAN : w.bond_breaks().front().t, "s");
        j.number("energy_bond_broken", e.bond_broken, "J");
        std::ostringstream csv;
        csv.precision(9);
        csv << "t_s,k,l,strain,energy_J\n";
        for (const BondBreakEvent& b : w.bond_breaks()) csv << b.t << ',' << b.k << ',' << b.l << ',' << b.strain << ',' << b.energy << '\n';
        write_file_atomic(dir_ + "/bond_breaks.csv", csv.str());
    }
    write_file_atomic(dir_ + "/summary.json", j.str());
    return sum;
}

}  // namespace

std::unique_ptr<SolverRun> make_dem3_run(const Scenario& s, const RunOptions& o) { return std::make_unique<Dem3Run>(s, o); }

}  // namespace demlab
