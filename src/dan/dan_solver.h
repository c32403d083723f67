// DAN, the depth-averaged "equivalent fluid" of Hungr (1995) as the thesis uses it
// (docs/spec/DAN.md, equations D1-D15): boundary blocks i = 0 (tail) .. n-1 (front) that move
// along the path, mass blocks j between boundary blocks j and j+1 of constant volume,
// frictional basal resistance with the centripetal term, an earth-pressure coefficient
// between active and passive from the blocks' strains, and the thesis' velocity smoothing
// with a momentum correction. The state is a few arrays over the blocks: a step is O(n).
#pragma once
#include <vector>

#include "core/binary_io.h"
#include "core/vec2.h"
#include "dan/dan_def.h"
#include "dan/dan_path.h"

namespace demlab {

// The initial blocks: positions along the path (m), the mass blocks' volumes (m3, B
// included) and the boundary blocks' velocities (m/s; empty: at rest).
struct DanInitial {
    std::vector<double> s, volume, v;
};

// The release polygon (convex or not) cut into n - 1 mass blocks: vertical columns between
// x = x(0) and the polygon's largest x, or bed-normal ones between s = 0 and the largest s of
// its corners (DAN.md section 2, "Initial state").
DanInitial dan_release(const DanDef& d, const DanPath& path, const std::vector<Vec2>& polygon);

// A polygon's area (m2) and the part of it on the side (p - a) . dir >= 0 of a line.
double polygon_area(const std::vector<Vec2>& p);
std::vector<Vec2> clip_half_plane(const std::vector<Vec2>& p, const Vec2& a, const Vec2& dir);

// Earth-pressure limits (D5): k_a and k_p for the internal angle and a basal friction tan.
struct EarthPressure {
    double active, passive;
};
EarthPressure earth_pressure_limits(double phi_internal_rad, double tan_basal);

struct DanEnergy {
    double kinetic = 0, potential = 0, dissipated_friction = 0;
};

class DanSolver {
public:
    DanSolver(const DanDef& def, DanPath path, Vec2 gravity, const DanInitial& init);

    void step();
    double time() const { return time_; }
    double dt() const { return dt_; }
    long step_count() const { return steps_; }

    size_t blocks() const { return s_.size(); }
    const std::vector<double>& s() const { return s_; }          // m, boundary blocks
    const std::vector<double>& v() const { return v_; }          // m/s
    const std::vector<double>& mass() const { return m_; }       // kg, lumped (D8)
    const std::vector<double>& volume() const { return vol_; }   // m3, mass blocks
    const std::vector<double>& k() const { return k_; }          // -, mass blocks
    const std::vector<double>& h() const { return h_; }          // m, mass blocks (D1)
    const std::vector<double>& height() const { return H_; }     // m, boundary blocks (D2)
    // the bed's load by each boundary block this step (D15), N per width B
    const std::vector<Vec2>& bed_force() const { return bed_force_; }
    const DanPath& path() const { return path_; }
    const DanDef& def() const { return def_; }

    double kinetic_energy() const;
    DanEnergy energy() const;
    double momentum() const;               // kg m/s, sum m v along the path
    double max_cfl() const { return max_cfl_; }
    double momentum_corrected() const { return momentum_corrected_; }  // sum |sum m delta| of D13
    double cfl_now() const;                // D's stability number at the current state

    void save_state(BinaryWriter& out) const;
    void load_state(BinaryReader& in);

private:
    void update_geometry();                // alpha, kappa, x at the blocks; l, h, H
    void update_k(const std::vector<double>& l_before);
    double stability_rate() const;         // max_j (sqrt(k g cos a h) + |dv|) / l, 1/s
    double surface_height(double x, size_t& seg) const;  // m, H between the boundary blocks (D4's window)
    // one step's stages, in order
    double choose_step();                  // s, this step's dt (throws when it collapses or breaks the limit)
    bool bore_viscosity();                 // q_ (D16); false when it is off
    void accelerate(double dt, bool viscous);  // v_star_, v_plus_, the bed's load (D7, D10, D11, D15)
    void smooth(double dt);                // v_hat_ (D12, D13)
    void move(double dt);                  // s_ and v_ (D14)
    DanDef def_;
    DanPath path_;
    double g_;                             // m/s2, |gravity| (along -y)
    double tan_basal_, phi_internal_;
    std::vector<double> s_, v_, m_, vol_, k_;
    // per step: boundary blocks' point data, mass blocks' lengths and heights
    std::vector<DanPathPoint> at_;
    std::vector<double> l_, h_, H_, cos_mid_, l_before_;
    std::vector<Vec2> bed_force_;
    std::vector<double> v_star_, v_plus_, v_hat_, accel_, q_;
    double time_ = 0.0, dt_ = 0.0, dissipated_ = 0.0, max_cfl_ = 0.0, momentum_corrected_ = 0.0;
    long steps_ = 0;
};

}  // namespace demlab
