// Peak fields on the terrain's grid, AvaFrame's convention for a run's results (com1DFA and
// com5SnowSlide write them as ESRI ASCII rasters a GIS opens): the peak flow thickness, the
// peak flow speed and the deposit's thickness, each cell's value from the spheres whose centres
// lie in it.
//
// Thickness is AvaFrame's: the mass in a cell over its bulk density and its map-view area,
// h = sum m / (rho_bulk A), rho_bulk = rho * solid_fraction (the release's own: its spheres'
// volume over the volume they fill). So the rasters' volume, sum h A, is the spheres' bulk
// volume exactly, whatever the cell size; a cell's h is the depth of a layer of the release's
// packing holding that mass. Speed is the cell's mass-weighted mean speed, as AvaFrame
// interpolates its particles' velocities. "Peak": the largest value a cell took over the run's
// samples (every series interval, and the last instant); the deposit: the last instant.
#pragma once
#include <string>
#include <vector>

#include "core/binary_io.h"
#include "core/vec3.h"
#include "geometry/esri_grid.h"

namespace demlab {

class PeakRasters {
public:
    // grid: the terrain's (its cells centred on its nodes, x0 + col cellsize); rho_bulk in kg/m3
    PeakRasters(const EsriGrid& grid, double rho_bulk);

    // the spheres now (velocities in m/s, masses in kg): raises each cell's peaks
    void sample(const std::vector<Vec3>& position, const std::vector<Vec3>& velocity, const std::vector<double>& mass);
    // the spheres at rest: the deposit (also a sample)
    void finish(const std::vector<Vec3>& position, const std::vector<Vec3>& velocity, const std::vector<double>& mass);

    const std::vector<double>& peak_thickness() const { return peak_h_; }  // m, row-major from the south
    const std::vector<double>& peak_speed() const { return peak_v_; }      // m/s
    const std::vector<double>& deposit_thickness() const { return deposit_h_; }  // m
    double cell_area() const { return grid_.cellsize * grid_.cellsize; }         // m2
    // m3, sum h A of a field
    double volume(const std::vector<double>& field) const;

    // peak_thickness.asc, peak_speed.asc, deposit_thickness.asc in dir (atomically each)
    void write(const std::string& dir) const;
    const EsriGrid& grid() const { return grid_; }
    // the peaks so far, for a checkpoint
    void save(BinaryWriter& out) const;
    void load(BinaryReader& in);

private:
    // the cell of (x, y), or -1 outside the grid
    long cell_of(double x, double y) const;
    void thickness_and_speed(const std::vector<Vec3>& position, const std::vector<Vec3>& velocity, const std::vector<double>& mass);
    EsriGrid grid_;  // (its elevations unused: the header)
    double rho_bulk_;
    std::vector<double> mass_, momentum_;  // this sample's, per cell (kept: no allocation a sample)
    std::vector<double> now_h_, now_v_;
    std::vector<double> peak_h_, peak_v_, deposit_h_;
    double outside_mass_ = 0.0;            // kg, in the last sample outside the grid
};

// An ESRI ASCII grid with g's header (xllcenter, yllcenter, cellsize, NODATA_value -9999) and
// values row-major from the south, written northernmost row first as the format wants.
std::string esri_grid_text(const EsriGrid& g, const std::vector<double>& values);

}  // namespace demlab
