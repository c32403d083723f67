#include "dem3/peak_rasters.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "core/error.h"
#include "core/fileio.h"

namespace demlab {

PeakRasters::PeakRasters(const EsriGrid& grid, double rho_bulk) : grid_(grid), rho_bulk_(rho_bulk) {
    if (!(rho_bulk > 0.0)) throw InputError("the peak rasters' bulk density must be positive");
    grid_.z.clear();
    const size_t cells = size_t(grid.ncols) * size_t(grid.nrows);
    mass_.assign(cells, 0.0);
    momentum_.assign(cells, 0.0);
    now_h_.assign(cells, 0.0);
    now_v_.assign(cells, 0.0);
    peak_h_.assign(cells, 0.0);
    peak_v_.assign(cells, 0.0);
    deposit_h_.assign(cells, 0.0);
}

long PeakRasters::cell_of(double x, double y) const {
    // cells centred on the grid's nodes: node (col, row) owns [x0 + (col - 1/2) c, x0 + (col + 1/2) c)
    const double u = std::floor((x - grid_.x0) / grid_.cellsize + 0.5), v = std::floor((y - grid_.y0) / grid_.cellsize + 0.5);
    if (!(u >= 0.0 && v >= 0.0 && u < double(grid_.ncols) && v < double(grid_.nrows))) return -1;
    return long(v) * long(grid_.ncols) + long(u);
}

void PeakRasters::thickness_and_speed(const std::vector<Vec3>& position, const std::vector<Vec3>& velocity,
                                      const std::vector<double>& mass) {
    std::fill(mass_.begin(), mass_.end(), 0.0);
    std::fill(momentum_.begin(), momentum_.end(), 0.0);
    outside_mass_ = 0.0;
    for (size_t i = 0; i < position.size(); ++i) {
        const long c = cell_of(position[i].x(), position[i].y());
        if (c < 0) {
            outside_mass_ += mass[i];
            continue;
        }
        mass_[size_t(c)] += mass[i];
        momentum_[size_t(c)] += mass[i] * velocity[i].norm();
    }
    const double area = cell_area();
    for (size_t c = 0; c < mass_.size(); ++c) {
        now_h_[c] = mass_[c] / (rho_bulk_ * area);
        now_v_[c] = mass_[c] > 0.0 ? momentum_[c] / mass_[c] : 0.0;
    }
}

void PeakRasters::sample(const std::vector<Vec3>& position, const std::vector<Vec3>& velocity, const std::vector<double>& mass) {
    thickness_and_speed(position, velocity, mass);
    for (size_t c = 0; c < mass_.size(); ++c) {
        peak_h_[c] = std::max(peak_h_[c], now_h_[c]);
        peak_v_[c] = std::max(peak_v_[c], now_v_[c]);
    }
}

void PeakRasters::finish(const std::vector<Vec3>& position, const std::vector<Vec3>& velocity, const std::vector<double>& mass) {
    sample(position, velocity, mass);
    deposit_h_ = now_h_;
}

double PeakRasters::volume(const std::vector<double>& field) const {
    double v = 0.0;
    for (double h : field) v += h;
    return v * cell_area();
}

std::string esri_grid_text(const EsriGrid& g, const std::vector<double>& values) {
    std::ostringstream o;
    o.precision(17);
    o << "ncols " << g.ncols << "\nnrows " << g.nrows << "\nxllcenter " << g.x0 << "\nyllcenter " << g.y0
      << "\ncellsize " << g.cellsize << "\nNODATA_value -9999\n";
    char buf[32];
    for (int row = g.nrows - 1; row >= 0; --row) {
        for (int col = 0; col < g.ncols; ++col) {
            const double v = values[size_t(row) * size_t(g.ncols) + size_t(col)];
            std::snprintf(buf, sizeof buf, col ? " %.6g" : "%.6g", std::isfinite(v) ? v : -9999.0);
            o << buf;
        }
        o << '\n';
    }
    return o.str();
}

void PeakRasters::save(BinaryWriter& out) const {
    out.put(peak_h_);
    out.put(peak_v_);
}

void PeakRasters::load(BinaryReader& in) {
    in.get(peak_h_, mass_.size());
    in.get(peak_v_, mass_.size());
}

void PeakRasters::write(const std::string& dir) const {
    write_file_atomic(dir + "/peak_thickness.asc", esri_grid_text(grid_, peak_h_));
    write_file_atomic(dir + "/peak_speed.asc", esri_grid_text(grid_, peak_v_));
    write_file_atomic(dir + "/deposit_thickness.asc", esri_grid_text(grid_, deposit_h_));
}

}  // namespace demlab
