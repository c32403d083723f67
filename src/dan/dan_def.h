// The DAN continuum model's parameters (Hungr 1995, as the thesis uses it: docs/spec/DAN.md
// section 3), one field a key of [dan], with its unit and default. The flume's geometry, the
// stop rule, the output intervals and the gravity are the scenario's own keys.
#pragma once
#include <string>

namespace demlab {

enum class DanColumns { Vertical, Normal };            // D1 and the initial mass
enum class DanKMode { Dan, Fixed };                    // D6, or k = k_fixed
enum class DanPressure { Dan, Conservative };          // D7
enum class DanEndHeight { Half, Zero };                // D7, D8 at the end blocks
enum class DanSpacing { Horizontal, Path };            // X of the smoothing, D12
enum class DanMomentum { None, Global };               // D13
enum class DanStep { Fixed, Auto };                    // the step size, section 2
enum class DanPosition { Symplectic, Trapezoid };      // D14: S += dt v-hat, or the thesis' (2.31)

struct DanDef {
    int blocks = 41;                       // -, n boundary blocks (n - 1 mass blocks), [3, 100000]
    DanColumns columns = DanColumns::Vertical;
    double density = 1630.0;               // kg/m3, bulk density of the flow (lab, section 3.1)
    double width = 1.0;                    // m, B (1 m as PFC2D: results per metre of width)
    double phi_internal_deg = 30.9;        // deg, dynamic internal friction angle (Table 16)
    double phi_basal_deg = 21.7;           // deg, basal friction angle (Table 16)
    double pore_pressure_ratio = 0.0;      // -, r_u in [0, 1)
    DanKMode k_mode = DanKMode::Dan;
    double k_fixed = 1.0;                  // -, k with k_mode fixed (1: a fluid)
    double k_initial = 1.0;                // -, k at t = 0, clamped at the first update
    double k_stiffness = 200.0;            // -, E_k of D6 (0: the Savage-Hutter switch)
    double lambda = 0.333;                 // -, D4 (eq. 2.38)
    // D4 reads the free surface's slope over this many flow depths h_j, centred on the block
    // (never less than the block itself); 0: the block's own slope, eq. 2.38 literally
    double slope_window = 1.0;             // - (flow depths), [0, 10]
    DanPressure pressure_form = DanPressure::Dan;
    DanEndHeight end_height = DanEndHeight::Half;
    bool pressure_centripetal = false;     // also scale p by (1 + kappa v^2 / (g cos alpha))
    bool centripetal = true;               // the kappa v^2 term of the basal resistance (D10)
    double curvature_window = 0.0;         // m, running mean of kappa over this length (0: none)
    bool smoothing = true;                 // D12
    double cs_interior = 0.02;             // -, c_s of the inner boundary blocks
    double cs_ends = 0.004;                // -, c_s of the front and tail blocks
    DanSpacing smoothing_spacing = DanSpacing::Horizontal;
    double smoothing_dt_ref = 1e-3;        // s, D12's reference step (0: c_s per step, literally)
    DanMomentum momentum_correction = DanMomentum::Global;
    // the bore's dissipation (dan_solver.cpp, D16): a mass block that is compressed
    // (v_{j+1} < v_j) pushes its boundary blocks apart with rho B h (c_quad dv^2 + c_lin a |dv|)
    double shock_viscosity = 1.0;          // -, c_quad (0: none)
    double shock_viscosity_linear = 1.0;   // -, c_lin, a = sqrt(k g h cos alpha) (0: none)
    double dt = 1e-4;                      // s, the time step
    DanStep dt_mode = DanStep::Fixed;
    DanPosition position_update = DanPosition::Symplectic;  // D14 (dan_solver.cpp says why)
    double cfl_max = 0.5;                  // -, stability limit
    double path_extension = 1.0;           // m, straight continuation past the path's ends
    double sync_time = 0.4;                // s, t_sync of the front's time synchronisation
    std::string sync_front;                // a reference front.csv (empty: no front_synced.csv)
};

}  // namespace demlab
