// A scenario: everything a run needs, read from TOML. Every parameter has a key, a unit, a
// default and an accepted range in one registry (scenario_keys.cpp), which also writes the
// reference page docs/scenario-reference.md and the resolved scenario of a run.
#pragma once
#include <cmath>
#include <string>
#include <vector>

#include "dem/material.h"
#include "dem/bonds/bond_builder.h"
#include "geometry/wall.h"
#include "dan/dan_def.h"
#include "dem3/close_packing.h"
#include "dem3/world3.h"
#include "dem/world.h"

namespace demlab {

// The flume of Table 2 (geometry rows) and the release box of Table 3.
struct FlumeDef {
    bool enabled = false;                  // a [flume] table was given
    Vec2 w1_p0{0.0, 1.115}, w1_p1{1.4486, 0.3121};          // slope, m
    Vec2 arc_centre{1.4970, 0.3995};       // transition arc, m
    double arc_radius = 0.10;              // m
    double arc_start_deg = 241.0, arc_end_deg = 303.0;      // deg, counter-clockwise from +x
    Vec2 w3_p0{1.5515, 0.3156}, w3_p1{2.4390, 0.8920};      // barrier, m
    Vec2 gate_p0{0.5276, 0.8226}, gate_p1{0.5276, 1.1150};  // W4, m
    Vec2 lid_p0{0.5276, 1.1150}, lid_p1{0.0, 1.1150};       // W5, m
};

// The dam break of the calibration (section 4.3.3; geometry assumed, data/dam_break_geometry.md):
// a column between a back wall at x = 0 and a gate at x = width, on a horizontal floor.
struct DamBreakDef {
    bool enabled = false;                  // a [dam_break] table was given
    double width = 0.20;                   // m, back wall to gate
    double height = 0.40;                  // m, height of the column (the lid while it is generated)
    double floor_length = 1.5;             // m, floor from the back wall
    double sections_start = 0.0;           // m, from the back wall to where section 5 (gamma_5) begins
};

// A terrain profile (setups/setup.h): walls along a polyline read from a CSV file, the ground
// below it; the mass from a release polygon or explicit discs.
struct TerrainDef {
    bool enabled = false;                  // a [terrain] table was given
    std::string profile;                   // CSV file of x,y rows (m), x increasing
    std::string grid;                      // or an ESRI ASCII grid (.asc) sampled along `section`
    std::vector<Vec2> section;             // m, the section line's two ends in the grid's coordinates
    double spacing = 0.0;                  // m, between the section's samples; 0 = the grid's cell size
    std::vector<Vec2> release;             // m, a convex polygon the release mass fills; empty: [[discs]]
    std::vector<Vec2> points;              // m, the profile as read (finish_scenario)
    // m, a barrier (a dam) standing on the profile: a polyline from its foot on the profile,
    // the flow on its left (up the upstream face first); empty: none
    std::vector<Vec2> barrier;
    int barrier_on_segment = -1;           // the profile segment the barrier's foot stands on (finish_scenario)
};

// Cohesive bonds (docs/spec/COHESION.md; dem/bonds/): the bond law, how the bonds are built
// at t = 0 of the run (a Delaunay triangulation of the disc centres, or explicit pairs).
struct CohesionDef {
    bool enabled = false;                  // a [cohesion] table with enabled = true
    bool given = false;                    // a [cohesion] table was given (it is then written back)
    BondDef bond;                          // modulus, max_strain, min_distance, area, break_mode, predict
    BondBuildDef build;                    // filter, max_edge_factor, max_bond_length, max_gap
    std::vector<std::pair<long, long>> bonds;  // explicit [k, l] pairs; when given, no triangulation
};

// Discs on a triangular lattice inside a polygon (COHESION.md section 3), at an angle.
struct LatticeReleaseDef {
    bool enabled = false;                  // a [lattice_release] table was given
    std::vector<Vec2> region;              // m, a simple polygon of >= 3 corners
    std::string top;                       // or a CSV file of the mass's top (x,y rows, x increasing), filled down to the terrain
    std::vector<Vec2> fill;                // m, the polygon filled: region, or between top and the terrain (finish_scenario)
    Vec2 origin{NAN, NAN};                 // m, a lattice node (required)
    double angle_deg = 0.0;                // deg, the rows' direction, ccw from +x
    double spacing = 0.0;                  // m, between neighbours; 0 = 2 r_max
    double r_min = 0.0;                    // m, > 0 (required)
    double r_max = 0.0;                    // m; 0 = r_min (radii uniform in [r_min, r_max] from the seed)
    bool settle = false;                   // settle under gravity before t = 0 (lattice_release.cpp)
    double settle_alpha = 0.7;             // local damping while the lattice settles (with friction)
};

struct ReleaseDef {
    int scale = 4;                         // upscaling factor of the sand (Table 14): radii [0.25, 0.5] mm * scale
    double r_min = 0.0;                    // m; 0 = from the scale
    double r_max = 0.0;                    // m; 0 = from the scale
    double porosity = 0.166;               // 2D porosity of the generated mass (Table 5)
    double radius_reduction = 0.03;        // fraction by which all radii shrink after generation
    std::string variant = "II";            // I: gate deleted at t = 0; II: gate lifted at gate_speed
    double gate_speed = 2.25;              // m/s, Variant II
    double settle_alpha = 0.3;             // local damping while the mass compacts without friction
    double settle_stiffness_factor = 0.25; // the stiffnesses while the mass compacts without friction, as a fraction of theirs
    double settle_friction_alpha = 0.2;    // local damping while the mass settles with friction
    std::string settle_dashpots = "lagged";  // the dashpots while settling: lagged or centred (timestep.dashpots)
    double settle_ratio = 5e-4;            // settled when mean |unbalanced force| / mean |contact force| < this
    bool accept_unsettled = false;         // run a mass that did not reach settle_ratio (else refused, exit 3)
    double settle_max_time = 1.5;          // s of simulated settling at most
    double layer_height = 0.03;            // m, height of the colour bands (layers)
    double grid_cell = 0.05;               // m, size of the colour grid cells
    std::string from_file;                 // a settled mass saved by an earlier run (release.csv)
    std::string space_order = "auto";      // number the discs in space order before settling: on, off,
                                           // auto (on above kSpaceOrderDiscs discs; release.cpp)
    std::string settle_ramp = "auto";      // compaction at a quarter of settle_stiffness_factor, then
                                           // the stiffness raised continuously (smooth) or by fours
                                           // (on); off; auto (smooth above kSettleRampDiscs discs;
                                           // release.cpp)
};

struct StopDef {
    double t_max = 5.0;                    // s after release
    double rest_ke_fraction = 1e-3;        // at rest: kinetic energy below this fraction of its peak ...
    double rest_duration = 0.2;            // s ... for this long
    double max_energy_gain = 1.0;          // -, energy created beyond this multiple of the energy turned over stops the run
    int max_steps = 0;                     // steps at most (0: no limit); stop_reason "max_steps"
};

struct OutputDef {
    double series_interval = 0.005;        // s between rows of the CSV series
    double snapshot_interval = 0.05;       // s between snapshots (VTK)
    std::string snapshot_format = "binary";  // "binary" (appended, zlib) or "ascii"
    std::vector<long> track;               // disc ids whose path is written to track.csv
    double deposit_bin = 0.01;             // m, spacing of deposit.csv (and peaks.csv) along the bed path, of surface.csv in x
    double pressure_bin = 0.01;            // m, bins of barrier_pressure.csv along the barrier
    double load_window = 0.05;             // s, the window of the impulse-filtered loads (summary's *_filtered)
    double approach_length = 0.0;          // m upstream of the barrier where the arriving flow is measured; 0 = 20 r_max
    int force_history_steps = 0;           // steps between rows of force_history.csv; 0 = none
    double front_neighbour_gap = 0.0;      // m, a front disc must have a neighbour within this gap; 0 = r_max
};

// A scenario's world starts from the engine's defaults but takes a stray disc out
// (world.lost_discs): one disc over a barrier's end should not end a run.
inline WorldDef scenario_world() {
    WorldDef d;
    d.lost_discs = LostDiscs::Remove;
    return d;
}

// The 3-D solver's scenario (src/dem3/, docs/debris.md "In three dimensions"): a terrain as a
// TIN, a release of close-packed spheres between it and a top surface (or a thickness) inside a
// box in map view, and the DEBRIS law's parameters (Dem3Def).
struct Dem3Scenario {
    std::string terrain;                   // .asc grid or .xyz points: the bed
    std::string release_top;               // .asc or .xyz: the mass's top before failure ("": release_thickness)
    double release_thickness = 0.0;        // m, above the bed when there is no top surface
    LatticeLayers release_layers = LatticeLayers::Level;  // the lattice's layers level (Mikhailov's) or along the bed
    Vec2 release_lo{0.0, 0.0};             // m, the release's box in map view
    Vec2 release_hi{0.0, 0.0};
    double radius = 10.0;                  // m
    double density = 2000.0;               // kg/m3
    Dem3Def law;                           // E, mu, eta, step, gravity
    double raster_cell = 0.0;              // m, the peak rasters' cell (0: the terrain grid's, or 2 radii)
};

struct Scenario {
    std::string source;                    // file it was read from (for messages)
    std::string name = "unnamed";
    std::string description;
    unsigned long long seed = 1;
    WorldDef world = scenario_world();     // gravity, damping, time step, rotation model, rules
    // m, the domain's box [[x_lo, y_lo], [x_hi, y_hi]] (world.domain): a disc whose centre leaves
    // it is lost; empty: the box of the walls, the discs and the set-up, padded by 0.5 m
    std::vector<Vec2> domain;
    // The materials, resolved by finish_scenario: the friction angles (deg) are the keys'; each
    // becomes its material's coefficient there, once, tan(angle). A world built from the
    // scenario adds scenario_materials(s) in their order, so kDiscMaterial, kWallMaterial and
    // the walls' WallDef::material index it.
    MaterialDef disc;                      // the discs' material (density, kn, ks; friction from disc_friction_deg)
    MaterialDef wall;                      // the set-up's walls' (kn, ks; friction from wall_friction_deg; no density)
    double disc_friction_deg = 15.5;
    double wall_friction_deg = 21.7;
    // [[walls]]: each entry's own material (its kn, ks and friction_deg, tan'd when read),
    // walls[i].material = kFirstWallEntryMaterial + i
    std::vector<MaterialDef> wall_entry_materials;
    std::string solver = "dem";            // "dem" (discs) or "dan" (the continuum model, dan/)
    DanDef dan;                            // the continuum model's parameters ([dan])
    Dem3Scenario dem3;                     // the 3-D solver's ([dem3]; scenario.solver = "dem3")
    bool dem3_given = false;               // a [dem3] table was given
    bool dan_given = false;                // a [dan] table was given (it is then written back)
    FlumeDef flume;
    DamBreakDef dam_break;
    TerrainDef terrain;
    CohesionDef cohesion;
    LatticeReleaseDef lattice_release;
    ReleaseDef release;
    StopDef stop;
    OutputDef output;
    std::vector<WallDef> walls;            // [[walls]]: explicit walls
    std::vector<DiscDef> discs;            // [[discs]]: explicit discs
};

// The materials of a scenario's world, in the order it adds them (World::add_material): the
// discs' first (so the disc-disc tables hold that one only), the set-up's walls', then one of
// each [[walls]] entry.
constexpr int kDiscMaterial = 0, kWallMaterial = 1, kFirstWallEntryMaterial = 2;
inline std::vector<MaterialDef> scenario_materials(const Scenario& s) {
    std::vector<MaterialDef> m{s.disc, s.wall};
    m.insert(m.end(), s.wall_entry_materials.begin(), s.wall_entry_materials.end());
    return m;
}

// Reads a scenario file. Throws InputError "FILE:LINE: key ...: message" on any problem.
Scenario load_scenario(const std::string& path);
// Parses scenario text (path only names it in messages).
Scenario parse_scenario(const std::string& text, const std::string& path);
// Applies a --set override "key=value" (value in TOML syntax; a bare word is taken as a string).
void apply_override(Scenario& s, const std::string& assignment);
// Checks the cross-key constraints (after overrides) and derives dependent values.
void finish_scenario(Scenario& s);
// The resolved scenario as TOML (every key, with its value).
std::string resolved_toml(const Scenario& s);
// The reference page: every key with its unit, default, range and meaning (Markdown).
std::string scenario_reference_markdown();

// A scenario whose discs come from a generated (or saved) release mass.
inline bool has_release(const Scenario& s) {
    return s.flume.enabled || s.dam_break.enabled || (s.terrain.enabled && !s.terrain.release.empty());
}

// Radii of the release mass for a scale factor (Table 14): [0.25, 0.5] mm times the scale.
inline double scale_r_min(int scale) { return 0.00025 * scale; }
inline double scale_r_max(int scale) { return 0.0005 * scale; }

}  // namespace demlab
