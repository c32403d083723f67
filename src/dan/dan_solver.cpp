#include "dan/dan_solver.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "core/validate.h"

namespace demlab {

double polygon_area(const std::vector<Vec2>& p) {
    double a = 0.0;
    for (size_t k = 0; k < p.size(); ++k) a += cross(p[k], p[(k + 1) % p.size()]);
    return 0.5 * std::abs(a);
}

// Sutherland-Hodgman against one half-plane: exact for any simple polygon cut by a line into
// pieces whose areas are what the blocks need (a non-convex polygon may leave zero-width
// bridges along the line, which carry no area)
std::vector<Vec2> clip_half_plane(const std::vector<Vec2>& p, const Vec2& a, const Vec2& dir) {
    std::vector<Vec2> out;
    const size_t n = p.size();
    for (size_t k = 0; k < n; ++k) {
        const Vec2& c = p[k];
        const Vec2& d = p[(k + 1) % n];
        const double fc = (c - a).dot(dir), fd = (d - a).dot(dir);
        if (fc >= 0.0) out.push_back(c);
        if ((fc >= 0.0) != (fd >= 0.0)) out.push_back(c + (fc / (fc - fd)) * (d - c));
    }
    return out;
}

DanInitial dan_release(const DanDef& d, const DanPath& path, const std::vector<Vec2>& polygon) {
    if (polygon.size() < 3) throw InputError("dan: the release polygon has fewer than 3 corners");
    const int n = d.blocks;
    DanInitial init;
    init.s.resize(size_t(n));
    init.volume.resize(size_t(n - 1));
    if (d.columns == DanColumns::Vertical) {
        // columns between verticals from x(0) to the polygon's largest x (the gate's face)
        double x_gate = -INFINITY;
        for (const Vec2& p : polygon) x_gate = std::max(x_gate, p.x());
        const double x0 = path.at(0.0).p.x();
        if (!(x_gate > x0)) throw InputError("dan: the release polygon lies before the path's start");
        double s_hi = 0.0;
        while (path.at(s_hi).p.x() < x_gate) s_hi += 0.1;
        std::vector<double> x(static_cast<size_t>(n));
        for (int i = 0; i < n; ++i) {
            x[size_t(i)] = x0 + (x_gate - x0) * double(i) / double(n - 1);
            init.s[size_t(i)] = i == 0 ? 0.0 : path.s_of_x(x[size_t(i)], 0.0, s_hi);
        }
        for (int j = 0; j + 1 < n; ++j) {
            const auto right_of = clip_half_plane(polygon, Vec2(x[size_t(j)], 0.0), Vec2(1.0, 0.0));
            const auto between = clip_half_plane(right_of, Vec2(x[size_t(j + 1)], 0.0), Vec2(-1.0, 0.0));
            init.volume[size_t(j)] = d.width * polygon_area(between);
        }
    } else {
        // bed-normal columns from s = 0 to the largest s of the polygon's corners (the gate's foot)
        double s_gate = -INFINITY;
        for (const Vec2& p : polygon) {
            double sp, hp;
            path.bed().project(p, sp, hp);
            s_gate = std::max(s_gate, sp);
        }
        if (!(s_gate > 0.0)) throw InputError("dan: the release polygon lies before the path's start");
        for (int i = 0; i < n; ++i) init.s[size_t(i)] = s_gate * double(i) / double(n - 1);
        for (int j = 0; j + 1 < n; ++j) {
            const DanPathPoint a = path.at(init.s[size_t(j)]), b = path.at(init.s[size_t(j + 1)]);
            const auto after = clip_half_plane(polygon, a.p, a.tangent());
            const auto between = clip_half_plane(after, b.p, -b.tangent());
            init.volume[size_t(j)] = d.width * polygon_area(between);
        }
    }
    for (size_t j = 0; j < init.volume.size(); ++j)
        if (!(init.volume[j] > 0.0))
            throw InputError("dan: mass block " + std::to_string(j) + " of the release holds no volume (the polygon does not "
                             "reach the path there); fewer dan.blocks or another dan.columns");
    return init;
}

EarthPressure earth_pressure_limits(double phi_internal_rad, double tan_basal) {
    // D5 (eq. 2.37): 2 [1 -+ sqrt(1 - cos^2 phi_i (1 + tan^2 phi_b))] / cos^2 phi_i - 1; a
    // negative radicand (phi_b > phi_i) is taken as 0
    const double c2 = std::cos(phi_internal_rad) * std::cos(phi_internal_rad);
    const double root = std::sqrt(std::max(0.0, 1.0 - c2 * (1.0 + tan_basal * tan_basal)));
    return {2.0 * (1.0 - root) / c2 - 1.0, 2.0 * (1.0 + root) / c2 - 1.0};
}

DanSolver::DanSolver(const DanDef& def, DanPath path, Vec2 gravity, const DanInitial& init)
    : def_(def), path_(std::move(path)) {
    if (gravity.x() != 0.0 || !(gravity.y() <= 0.0))
        throw InputError("world.gravity = [" + format_number(gravity.x()) + ", " + format_number(gravity.y()) +
                         "] m/s2: the continuum solver needs gravity along -y (the path's x is horizontal)");
    g_ = -gravity.y();
    const size_t n = init.s.size();
    if (n < 2 || init.volume.size() + 1 != n) throw InputError("dan: at least 2 boundary blocks and one volume per mass block");
    tan_basal_ = std::tan(deg_to_rad(def.phi_basal_deg));
    phi_internal_ = deg_to_rad(def.phi_internal_deg);
    s_ = init.s;
    vol_ = init.volume;
    v_ = init.v.empty() ? std::vector<double>(n, 0.0) : init.v;
    if (v_.size() != n) throw InputError("dan: one initial velocity per boundary block");
    k_.assign(n - 1, def.k_mode == DanKMode::Fixed ? def.k_fixed : def.k_initial);
    // D8: each mass block's mass split between its two boundary blocks, half and half; an end
    // block takes the share e of its block (the tip of a triangular end block: 1/4 with
    // end_height "zero"), its neighbour the rest
    const double e = def.end_height == DanEndHeight::Half ? 0.5 : 0.25;
    m_.assign(n, 0.0);
    for (size_t j = 0; j + 1 < n; ++j) {
        const double mj = def.density * vol_[j];
        double left = 0.5, right = 0.5;
        if (n > 2 && j == 0) left = e, right = 1.0 - e;
        if (n > 2 && j == n - 2) left = 1.0 - e, right = e;
        m_[j] += left * mj;
        m_[j + 1] += right * mj;
    }
    at_.resize(n);
    l_.resize(n - 1);
    h_.resize(n - 1);
    cos_mid_.resize(n - 1);
    H_.resize(n);
    bed_force_.assign(n, Vec2::Zero());
    v_star_.resize(n);
    v_plus_.resize(n);
    v_hat_.resize(n);
    accel_.resize(n);
    q_.assign(n - 1, 0.0);
    dt_ = def.dt;
    for (size_t j = 0; j + 1 < n; ++j)
        if (!(s_[j + 1] > s_[j])) throw InputError("dan: the initial blocks are not in order along the path");
    update_geometry();
}

void DanSolver::update_geometry() {
    const size_t n = s_.size();
    for (size_t i = 0; i < n; ++i) at_[i] = path_.at(s_[i]);
    for (size_t j = 0; j + 1 < n; ++j) {
        l_[j] = s_[j + 1] - s_[j];
        cos_mid_[j] = std::cos(path_.at(0.5 * (s_[j] + s_[j + 1])).alpha);
        // D1: bed-normal columns, or vertical ones (their width along x, the height normal to the bed)
        h_[j] = def_.columns == DanColumns::Normal ? vol_[j] / (def_.width * l_[j])
                                                   : vol_[j] * cos_mid_[j] / (def_.width * (at_[j + 1].p.x() - at_[j].p.x()));
    }
    // D2
    H_[0] = 0.5 * h_[0];
    H_[n - 1] = 0.5 * h_[n - 2];
    for (size_t i = 1; i + 1 < n; ++i) H_[i] = 0.5 * (h_[i - 1] + h_[i]);
}

double DanSolver::stability_rate() const {
    double rate = 0.0;
    for (size_t j = 0; j + 1 < s_.size(); ++j)
        rate = std::max(rate, (std::sqrt(std::max(0.0, k_[j] * g_ * cos_mid_[j] * h_[j])) + std::abs(v_[j + 1] - v_[j])) / l_[j]);
    return rate;
}

double DanSolver::cfl_now() const { return def_.dt * stability_rate(); }

// The step: fixed (refused past the stability limit) or the largest the limit allows.
double DanSolver::choose_step() {
    const DanDef& d = def_;
    const double rate = stability_rate();
    double dt = d.dt;
    if (d.dt_mode == DanStep::Auto && rate > 0.0) dt = std::min(d.dt, d.cfl_max / rate);
    // a step that collapses (blocks crowding: where the mass comes to rest with many blocks,
    // at the dam-break tip with thousands) would make the run crawl for ever: refused at a
    // ten-thousandth of dan.dt
    if (dt < 1e-4 * d.dt)
        throw RunError("dan: the automatic step fell to " + format_number(dt) + " s at t = " + format_number(time_) +
                       " s (below 1e-4 of dan.dt): the blocks crowd; use fewer dan.blocks (or a larger dan.cfl_max)");
    const double cfl = dt * rate;
    max_cfl_ = std::max(max_cfl_, cfl);
    if (cfl > d.cfl_max * (1.0 + 1e-12))
        throw RunError("dan: the step " + format_number(dt) + " s is beyond the stability limit at t = " + format_number(time_) +
                       " s (CFL " + format_number(cfl) + " > dan.cfl_max = " + format_number(d.cfl_max) +
                       "): lower dan.dt, or dan.dt_mode = \"auto\"");
    return dt;
}

// The bore's artificial viscosity on each compressed block pair (q_); false when it is off.
bool DanSolver::bore_viscosity() {
    const size_t n = s_.size();
    const DanDef& d = def_;
    // D16: the bore's dissipation, an artificial viscosity (von Neumann & Richtmyer 1950) on
    // the compressed mass blocks. Where the arriving flow meets the mass that has stopped at
    // the barrier, the depth-averaged equations (D0) have a bore: h and u jump, and the jump
    // loses kinetic energy at a rate its conditions fix, whatever the scheme. The Lagrangian
    // blocks have no such loss: D0's pressure is reversible, friction acts on the bed only, and
    // the smoothing D12 is a diffusion of about c_s dX^2 / dt_ref that vanishes as the blocks
    // are refined. The energy the bore must lose stays in block-scale oscillations behind it
    // (neighbours at +-0.5 m/s, heights alternating by a factor 2 at 656 blocks), which crowd
    // the blocks until friction slowly takes them: the step falls, and the deposit sloshes.
    // The thrust Q_j = rho B h_j (c_quad dv_j^2 + c_lin a_j |dv_j|), dv_j = v_{j+1} - v_j < 0,
    // a_j = sqrt(k_j g cos(alpha_j) h_j), acts like the blocks' own thrust: +Q_j on block j + 1,
    // -Q_j on block j. It conserves momentum, its power Q_j dv_j is never positive, and a block
    // that is stretched or at rest feels nothing (the deposit's equilibrium is unchanged).
    // Per unit mass it is c_quad |dv|^2 / l (m_j ~ rho B h_j l_j): smooth flow, dv ~ l du/ds,
    // feels c_quad l (du/ds)^2, which vanishes as the blocks are refined, while a bore,
    // dv ~ the jump over the two or three blocks it spans, loses its energy there at any n.
    // Explicitly it is a damping of rate 2 c |dv| / l on a block pair: within the CFL limit
    // (dt |dv| / l <= cfl_max = 0.5) the pair's relative speed is not reversed for c <= 1.
    // The quadratic term alone leaves the bore ringing: its damping rate falls with the
    // ringing's amplitude, so block-scale waves of a few cm/s stay behind the bore in the
    // deposit. There k flips between its limits from one block to the next (D4-D6 see each
    // block's own strain and surface slope), and DAN's pressure k dH/ds (D7), blind to dk/ds,
    // feeds the waves: from about 600 blocks on they grow into pulses that remobilise the
    // deposit at rest (A, without D12's smoothing or at 4,100 blocks: run-out 2.39 m against
    // 2.16-2.19 m). The linear term damps a compressed pair at the rate 2 c_lin a / l, its own
    // wave frequency, whatever the amplitude (Landshoff's linear viscosity): the ringing dies
    // within a few steps, while in smooth flow it is c_lin a l du/ds per unit mass, which
    // vanishes as the blocks are refined. Its stable range: 2 c_lin a dt / l <= 2 c_lin cfl_max <= 1.
    const bool viscous = d.shock_viscosity > 0.0 || d.shock_viscosity_linear > 0.0;
    if (viscous)
        for (size_t j = 0; j + 1 < n; ++j) {
            const double dv = v_[j + 1] - v_[j];
            if (dv >= 0.0) {
                q_[j] = 0.0;
                continue;
            }
            const double a = std::sqrt(std::max(0.0, k_[j] * g_ * cos_mid_[j] * h_[j]));
            q_[j] = d.density * d.width * h_[j] * (d.shock_viscosity * dv * dv + d.shock_viscosity_linear * a * -dv);
        }
    return viscous;
}

// The blocks' accelerations and their friction-limited velocities v+ (D7, D10, D11, D15, D16).
void DanSolver::accelerate(double dt, bool viscous) {
    const size_t n = s_.size();
    const DanDef& d = def_;
    // D7: the pressure acceleration at each boundary block
    const bool half = d.end_height == DanEndHeight::Half;
    for (size_t i = 0; i < n; ++i) {
        const DanPathPoint& q = at_[i];
        double p;
        if (d.pressure_form == DanPressure::Dan) {
            double kdh;
            if (i == 0) kdh = k_[0] * (h_[0] - (half ? H_[0] : 0.0)) / (0.5 * l_[0]);
            else if (i == n - 1) kdh = k_[n - 2] * ((half ? H_[n - 1] : 0.0) - h_[n - 2]) / (0.5 * l_[n - 2]);
            else kdh = 0.5 * (h_[i] - h_[i - 1]) * (k_[i] / l_[i] + k_[i - 1] / l_[i - 1]);
            p = -g_ * std::cos(q.alpha) * kdh;
        } else {
            // the blocks' thrusts Q_j = rho g B k h^2 cos(alpha) / 2, none beyond the ends
            auto thrust = [&](size_t j) { return 0.5 * d.density * g_ * d.width * k_[j] * h_[j] * h_[j] * cos_mid_[j]; };
            const double behind = i > 0 ? thrust(i - 1) : 0.0, ahead = i + 1 < n ? thrust(i) : 0.0;
            p = (behind - ahead) / m_[i];
        }
        const double normal_acc = g_ * std::cos(q.alpha) + (d.centripetal ? q.kappa * v_[i] * v_[i] : 0.0);
        if (d.pressure_centripetal && g_ * std::cos(q.alpha) > 0.0) p *= normal_acc / (g_ * std::cos(q.alpha));
        if (viscous) p += ((i > 0 ? q_[i - 1] : 0.0) - (i + 1 < n ? q_[i] : 0.0)) / m_[i];  // D16
        accel_[i] = g_ * std::sin(q.alpha) + p;
        // D10, D11: friction slows motion towards 0 and never reverses it
        const double friction = (1.0 - d.pore_pressure_ratio) * tan_basal_ * std::max(0.0, normal_acc);
        v_star_[i] = v_[i] + dt * accel_[i];
        const double speed = std::max(0.0, std::abs(v_star_[i]) - dt * friction);
        v_plus_[i] = v_star_[i] > 0.0 ? speed : v_star_[i] < 0.0 ? -speed : 0.0;
        // D15: the block's load on the bed, its normal force and the friction it felt
        const double normal_force = m_[i] * std::max(0.0, normal_acc);
        const double friction_force = m_[i] * (v_plus_[i] - v_star_[i]) / dt;
        bed_force_[i] = -normal_force * q.normal() - friction_force * q.tangent();
        dissipated_ += 0.5 * m_[i] * (v_star_[i] * v_star_[i] - v_plus_[i] * v_plus_[i]);
    }
}

// v-hat from v+: the smoothing and the momentum it moved (D12, D13).
void DanSolver::smooth(double dt) {
    const size_t n = s_.size();
    const DanDef& d = def_;
    // D12: the thesis' smoothing, a Jacobi sweep from v+ (c scaled to the reference step)
    if (d.smoothing) {
        const double scale = d.smoothing_dt_ref > 0.0 ? dt / d.smoothing_dt_ref : 1.0;
        auto X = [&](size_t i) { return d.smoothing_spacing == DanSpacing::Horizontal ? at_[i].p.x() : s_[i]; };
        const double spacing = (X(n - 1) - X(0)) / double(n - 1);
        for (size_t i = 0; i < n; ++i) {
            const double c = (i == 0 || i == n - 1 ? d.cs_ends : d.cs_interior) * scale;
            const double wl = i > 0 ? spacing * c / (X(i) - X(i - 1)) : 0.0;
            const double wr = i + 1 < n ? spacing * c / (X(i + 1) - X(i)) : 0.0;
            v_hat_[i] = ((i > 0 ? wl * v_plus_[i - 1] : 0.0) + v_plus_[i] + (i + 1 < n ? wr * v_plus_[i + 1] : 0.0)) / (wl + 1.0 + wr);
        }
    } else {
        v_hat_ = v_plus_;
    }
    // D13: the momentum the smoothing moved, given back to the moving blocks
    if (d.smoothing && d.momentum_correction == DanMomentum::Global) {
        double before = 0.0, after = 0.0, moving = 0.0;
        for (size_t i = 0; i < n; ++i) {
            before += m_[i] * v_plus_[i];
            after += m_[i] * v_hat_[i];
            if (v_hat_[i] != 0.0) moving += m_[i];
        }
        if (moving > 0.0) {
            const double delta = (before - after) / moving;
            for (size_t i = 0; i < n; ++i)
                if (v_hat_[i] != 0.0) v_hat_[i] += delta;
            momentum_corrected_ += std::abs(before - after);
        }
    }
}

// The blocks moved by v-hat, and checked (D14).
void DanSolver::move(double dt) {
    const size_t n = s_.size();
    const DanDef& d = def_;
    // D14. The thesis' form (2.31), S += dt (v + v-hat) / 2, takes the pressure at the old
    // positions with weight dt into the velocity but dt^2 / 2 into the position: for a mode of
    // frequency w (the pressure's stiffness between neighbouring blocks, w ~ 2 sqrt(k g h) / l)
    // the step's matrix [[1 - (w dt)^2 / 2, dt], [-w^2 dt, 1]] has the determinant
    // 1 + (w dt)^2 / 2, so every mode grows by sqrt(1 + (w dt)^2 / 2) a step whatever dt. The
    // smoothing damps the shortest mode by about 1 - 4 c a step, a c that does not grow with the
    // blocks, while (w dt)^2 grows as n^2 at a fixed step (and stays near (2 C)^2 at the automatic
    // one, where c falls as 1/n): past about 300 blocks on the flume the growth wins and a block
    // collapses ("the blocks crowd"). Moving by the new velocity (symplectic Euler) has the
    // determinant 1: stable up to w dt = 2, i.e. within the CFL limit, for any number of blocks.
    // On a constant acceleration a it puts a block a t dt / 2 further than the exact a t^2 / 2
    // (the trapezoid is exact there); the 41-block flume's landmarks are the same to 1 mm and 1 ms.
    l_before_ = l_;  // (a member: no allocation a step)
    const bool trapezoid = d.position_update == DanPosition::Trapezoid;
    for (size_t i = 0; i < n; ++i) {
        s_[i] += trapezoid ? 0.5 * dt * (v_hat_[i] + v_[i]) : dt * v_hat_[i];
        v_[i] = v_hat_[i];
    }
    for (size_t j = 0; j + 1 < n; ++j)
        if (!(s_[j + 1] > s_[j]))
            throw RunError("dan: blocks " + std::to_string(j) + " and " + std::to_string(j + 1) + " crossed at s = " +
                           format_number(s_[j]) + " m, t = " + format_number(time_ + dt) +
                           " s: lower dan.dt or raise dan.blocks");
    const double s_max = path_.length() + d.path_extension;
    if (s_[n - 1] > s_max || s_[0] < -d.path_extension)
        throw RunError("dan: the flow left the path and its extension (dan.path_extension = " + format_number(d.path_extension) +
                       " m) at t = " + format_number(time_ + dt) + " s");
}

void DanSolver::step() {
    const double dt = choose_step();
    accelerate(dt, bore_viscosity());
    smooth(dt);
    move(dt);
    update_geometry();
    update_k(l_before_);
    time_ += dt;
    dt_ = dt;
    ++steps_;
}

void DanSolver::update_k(const std::vector<double>& l_before) {
    const DanDef& d = def_;
    if (d.k_mode == DanKMode::Fixed) {
        std::fill(k_.begin(), k_.end(), d.k_fixed);
        return;
    }
    size_t seg_a = 0, seg_b = 0;  // the windows' ends' segments, moved from block to block
    for (size_t j = 0; j < k_.size(); ++j) {
        const double strain = (l_[j] - l_before[j]) / l_before[j];  // D3, > 0 extension
        // D4 with the surface's slope rise / run: over the block (eq. 2.38), or over the window
        double rise = H_[j + 1] - H_[j], run = l_[j];
        const double window = d.slope_window * h_[j];
        if (window > l_[j]) {
            const double mid = 0.5 * (s_[j] + s_[j + 1]);
            const double a = std::max(s_.front(), mid - 0.5 * window), b = std::min(s_.back(), mid + 0.5 * window);
            rise = surface_height(b, seg_b) - surface_height(a, seg_a);
            run = b - a;  // >= l_j: the window holds the block
        }
        const double tan_mod = tan_basal_ - d.lambda * k_[j] * rise / run;                 // D4
        const EarthPressure lim = earth_pressure_limits(phi_internal_, tan_mod);           // D5
        double k = k_[j];
        if (d.k_stiffness > 0.0) k -= d.k_stiffness * strain;                               // D6
        else if (strain > 0.0) k = lim.active;
        else if (strain < 0.0) k = lim.passive;
        k_[j] = std::clamp(k, lim.active, lim.passive);
    }
}

// The free surface H(x), linear between the boundary blocks, at x in [s_0, s_(n-1)]. seg is the
// segment [s_seg, s_(seg+1)] found for the previous x; the windows of neighbouring blocks
// overlap, so it moves by a block or two, not a search over all of them.
double DanSolver::surface_height(double x, size_t& seg) const {
    const size_t n = s_.size();
    while (seg + 2 < n && s_[seg + 1] < x) ++seg;
    while (seg > 0 && s_[seg] > x) --seg;
    const double w = (x - s_[seg]) / (s_[seg + 1] - s_[seg]);
    return H_[seg] + w * (H_[seg + 1] - H_[seg]);
}

double DanSolver::kinetic_energy() const {
    double e = 0.0;
    for (size_t i = 0; i < s_.size(); ++i) e += 0.5 * m_[i] * v_[i] * v_[i];
    return e;
}

double DanSolver::momentum() const {
    double p = 0.0;
    for (size_t i = 0; i < s_.size(); ++i) p += m_[i] * v_[i];
    return p;
}

DanEnergy DanSolver::energy() const {
    DanEnergy e;
    e.kinetic = kinetic_energy();
    for (size_t i = 0; i < s_.size(); ++i) e.potential += m_[i] * g_ * at_[i].p.y();
    e.dissipated_friction = dissipated_;
    return e;
}

void DanSolver::save_state(BinaryWriter& out) const {
    out.tag("DAN ");
    out.put(time_);
    out.put(dt_);
    out.put(steps_);
    out.put(dissipated_);
    out.put(max_cfl_);
    out.put(momentum_corrected_);
    out.put(s_);
    out.put(v_);
    out.put(k_);
}

void DanSolver::load_state(BinaryReader& in) {
    in.expect_tag("DAN ");
    in.get(time_);
    in.get(dt_);
    in.get(steps_);
    in.get(dissipated_);
    in.get(max_cfl_);
    in.get(momentum_corrected_);
    const size_t n = s_.size();
    in.get(s_, n);
    in.get(v_, n);
    in.get(k_, n - 1);
    if (s_.size() != n || v_.size() != n || k_.size() + 1 != n) throw InputError("checkpoint: its blocks are not this set-up's");
    update_geometry();
}

}  // namespace demlab
