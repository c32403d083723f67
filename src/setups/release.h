// The release mass (thesis section 4.2): discs of radii uniform in [r_min, r_max] fill the
// triangle between W1, the gate and the lid at a target porosity, all radii shrink by 3 %,
// and the mass settles under gravity (release.cpp: compaction, restiffening, friction). The
// count follows PFC's radius-expansion rule, N = A (1 - n) / (pi R_mean^2), which gives the
// thesis' 9,099 (scale 4), 36,403 (2) and 364 (20).
#pragma once
#include <array>
#include <string>
#include <vector>

#include "scenario/scenario.h"
#include "setups/flume.h"

namespace demlab {

struct ReleaseMass {
    std::vector<Vec2> pos;
    std::vector<double> radius;
    std::vector<int> layer;        // horizontal colour band, 0 at the bottom
    std::vector<int> grid;         // colour grid cell
    double box_area = 0;           // m2, the release triangle
    double porosity_target = 0;
    double porosity_generated = 0; // before the radius reduction
    double porosity_settled = 0;   // after reduction and settling, over the triangle
    double settle_time = 0;        // s simulated
    long settle_steps = 0;
    double settle_ratio = 0;       // final unbalanced-force ratio
    bool settled = false;
    double lid_load_fraction = 0;  // load on the lid / weight at the end of the compaction
    std::vector<std::array<Vec2, 2>> box_walls;  // W1, gate, lid the mass settled against
    double wall_seconds = 0;
};

// Number of discs for a box area, porosity and radius range (PFC's rule, see above).
long release_count(double area, double porosity, double r_min, double r_max);
// The most discs a generated release mass may have (generate_release refuses more before
// allocating them: an input error naming the radii's keys).
constexpr double kMaxReleaseDiscs = 2e7;

// Generates and settles the mass (deterministic for a seed). Progress on a terminal.
ReleaseMass generate_release(const Scenario& s);

// release.space_order = auto numbers the discs in space order before they settle above this
// many discs (generate_release).
constexpr long kSpaceOrderDiscs = 1000;

// release.settle_ramp = auto raises the settling's stiffness smoothly above this many discs: the
// masses that take minutes to settle (geometry A at scale 2 and 1), while the smaller ones,
// seconds to settle, keep the releases (and the regression references) of the single
// restiffening.
constexpr long kSettleRampDiscs = 20000;

// Renumbers the discs in space order (dem/space_order.h): strips across x, `strip` metres
// wide, from left to right, and up each strip. Deterministic: ties keep the old order.
void order_in_space(ReleaseMass& m, double strip);

// release.csv: id, x, y, r, layer, grid and the generation figures as comments.
void save_release(const ReleaseMass& m, const std::string& path);
// Refused (InputError naming the file and line): a header value that is not a finite number,
// layer or grid tags that are not whole numbers from 0, fewer or more disc rows than '# n'.
ReleaseMass load_release(const std::string& path);
// An InputError naming the file and the first disc (by its row, 0-based) whose centre lies
// more than its radius beyond an edge of the box (release_box), or beyond its lid by two of the
// largest diameters more (a settled mass heaves a little once the lid is gone).
void refuse_loaded_mass_outside_box(const ReleaseBox& box, const ReleaseMass& m, const std::string& path);
// An InputError naming the file and the first two discs (by their row, 0-based) that overlap
// by more than `ratio` of the smaller radius (world.max_overlap_ratio).
void refuse_overlapping_discs(const ReleaseMass& m, double ratio, const std::string& path);

}  // namespace demlab
