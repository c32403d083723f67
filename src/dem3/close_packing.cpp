#include "dem3/close_packing.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Dense>

#include "core/error.h"
#include "core/validate.h"

namespace demlab {

namespace {
// the most samples of the release box and lattice sites a release may test: each costs a
// terrain query (about a microsecond), so a minute of set-up at most
constexpr double kMaxReleaseSamples = 2e7;
constexpr double kMaxReleaseSites = 5e7;
}  // namespace

ClosePackedRelease close_packed_release(const Tin& bed, const std::function<bool(double, double, double&)>& top, const Vec2& lo,
                                        const Vec2& hi, double R, LatticeLayers layering) {
    ClosePackedRelease out;
    // the bulk volume and the elevations' range, on samples a quarter radius apart
    const double step = 0.25 * R;
    // bounded before any work: a box of kilometres, or a radius of a millimetre, took minutes
    // or hours of sampling without a word (and a box of 1e9 m overflowed the counts)
    const double columns = std::max(1.0, std::ceil((hi.x() - lo.x()) / step)), lines = std::max(1.0, std::ceil((hi.y() - lo.y()) / step));
    const double samples = columns * lines;
    if (!(samples <= kMaxReleaseSamples))
        throw InputError("the release box dem3.release_lo - dem3.release_hi (" + format_number(hi.x() - lo.x()) + " m x " +
                         format_number(hi.y() - lo.y()) + " m) is sampled every quarter of dem3.radius = " + format_number(R) +
                         " m: " + format_number(samples) + " samples, more than " + format_number(kMaxReleaseSamples) +
                         "; give a box within the release area or larger spheres");
    const int nx = int(columns), ny = int(lines);
    const double cx = (hi.x() - lo.x()) / nx, cy = (hi.y() - lo.y()) / ny;
    double z_lo = INFINITY, z_hi = -INFINITY;
    // the bed's plane z = c0 + c1 (x - xm) + c2 (y - ym) by least squares over the samples
    const double xm = 0.5 * (lo.x() + hi.x()), ym = 0.5 * (lo.y() + hi.y());
    Eigen::Matrix3d normal_eq = Eigen::Matrix3d::Zero();
    Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
    for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
            const double x = lo.x() + (i + 0.5) * cx, y = lo.y() + (j + 0.5) * cy;
            double zb = 0.0, zt = 0.0;
            if (!bed.height_at(x, y, zb) || !top(x, y, zt)) continue;
            z_lo = std::min(z_lo, zb);
            z_hi = std::max(z_hi, zt);
            const Eigen::Vector3d row(1.0, x - xm, y - ym);
            normal_eq += row * row.transpose();
            rhs += row * zb;
            if (zt > zb) out.bulk_volume += (zt - zb) * cx * cy;
        }
    if (!std::isfinite(z_lo) || !(z_hi > z_lo)) return out;
    const double s3 = std::sqrt(3.0), layer = 2.0 * std::sqrt(2.0 / 3.0) * R;
    const Vec3 a1(2.0 * R, 0, 0), a2(R, s3 * R, 0), a3(R, R / s3, layer);
    // the lattice's sites, counted before they are tested (the box's columns and rows, the
    // layers between the lowest bed and the highest top: on a slope far more than are kept)
    const double sites = (std::ceil((z_hi - z_lo) / layer) + 1.0) * (std::ceil((hi.y() - lo.y()) / (s3 * R)) + 4.0) *
                         (std::ceil((hi.x() - lo.x()) / (2.0 * R)) + 4.0);
    if (!(sites <= kMaxReleaseSites))
        throw InputError("the release's lattice of spheres of dem3.radius = " + format_number(R) + " m has " + format_number(sites) +
                         " sites to test over the box dem3.release_lo - dem3.release_hi, from the lowest bed to the highest top (" +
                         format_number(z_lo) + " to " + format_number(z_hi) + " m), more than " + format_number(kMaxReleaseSites) +
                         ": give larger spheres, a smaller box or a lower top (dem3.release_top, dem3.release_thickness)");
    const int layers = int(std::ceil((z_hi - z_lo) / layer)) + 1;
    const int rows = int(std::ceil((hi.y() - lo.y()) / (s3 * R))) + 2;
    const double span_x = hi.x() - lo.x();
    std::vector<TinContact> touch;
    // a lattice site is kept inside the box, at least R below the top, above the bed and clear of it
    auto keep = [&](const Vec3& p) {
        if (p.x() < lo.x() || p.x() > hi.x() || p.y() < lo.y() || p.y() > hi.y()) return false;
        double zt = 0.0;
        if (!top(p.x(), p.y(), zt) || p.z() > zt - R) return false;
        double zb = 0.0;
        if (!bed.height_at(p.x(), p.y(), zb) || p.z() < zb) return false;
        touch.clear();
        bed.sphere_contacts(p, R, touch);
        return touch.empty();
    };
    if (layering == LatticeLayers::Bed) {
        const Eigen::Vector3d c = normal_eq.ldlt().solve(rhs);
        const Vec3 n = Vec3(-c(1), -c(2), 1.0).normalized();
        const Vec3 e1 = (Vec3(1, 0, 0) - n.x() * n).normalized(), e2 = n.cross(e1);
        // the first layer's sites a radius (and a hair, so that they are clear) above the plane
        const Vec3 origin = Vec3(xm, ym, c(0)) + (1.0 + 1e-6) * R * n;
        const double reach = 0.5 * std::hypot(hi.x() - lo.x(), hi.y() - lo.y()) / std::max(n.z(), 0.05) + 4.0 * R;
        const int half_cols = int(std::ceil(reach / R)) + 2, half_rows = int(std::ceil(reach / (s3 * R))) + 2;
        for (int k = 0; k < layers; ++k)
            for (int j = -half_rows; j <= half_rows; ++j)
                for (int i = -half_cols; i <= half_cols; ++i) {
                    const Vec3 l = double(i) * a1 + double(j) * a2 + double(k) * a3;  // in the plane's frame
                    const Vec3 p = origin + l.x() * e1 + l.y() * e2 + l.z() * n;
                    if (keep(p)) out.centres.push_back(p);
                }
        out.solid_volume = double(out.centres.size()) * 4.0 / 3.0 * kPi * R * R * R;
        return out;
    }
    for (int k = 0; k < layers; ++k)
        // each layer starts R/sqrt(3) further north (a3): its rows from below the box's south side
        for (int j = -(k / 3) - 1; j < rows; ++j) {
            // the row's shift along x from the stacking and the rows below, undone so that each
            // row starts at the box's west side
            const Vec3 row0 = Vec3(lo.x(), lo.y(), z_lo) + double(j) * a2 + double(k) * a3;
            const int shift = int(std::floor((row0.x() - lo.x()) / (2.0 * R)));
            const int cols = int(std::ceil(span_x / (2.0 * R))) + 2;
            for (int i = -shift - 1; i < -shift + cols; ++i) {
                const Vec3 p = row0 + double(i) * a1;
                if (keep(p)) out.centres.push_back(p);
            }
        }
    out.solid_volume = double(out.centres.size()) * 4.0 / 3.0 * kPi * R * R * R;
    return out;
}

}  // namespace demlab
