// DB-9k, the speed workload of docs/spec/BENCHMARK.md: a settled column of 9,140 discs collapsing
// onto a floor, with the flume's material, run with a fixed step. Built here so that the
// benchmark command and the tests use the same set-up.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "dem/world.h"

namespace demlab {

struct XyrDisc {
    long id;
    double x, y, r;
};

// Reads an "id x y r" file (metres; '#' starts a comment). Throws InputError naming the file
// and line on anything malformed.
std::vector<XyrDisc> read_xyr(const std::string& path);

// The DB-9k world: per-contact k_n = k_s = 1e8 N/m (each body 2e8 in series), normal dashpot
// beta 0.5 on m_eff, no shear dashpot, mu 0.2773 disc-disc and 0.3979 disc-wall, rotation free
// without rolling resistance, floor y = 0 (to x = 1.5 m) and left wall x = 0, dt = 5e-6 s.
//
// `copies` > 1 puts that many columns side by side, each kCopySpacing further along +x with
// its own left wall, on one floor (the scaling figure of `bench db9k --copies`: 16 copies are
// 146,240 discs, the flume's mass at the real sand size). The spacing keeps them apart for the
// first second: LAMMPS' column has run out about 1.3 m at 1.5 s (docs/spec/BENCHMARK.md).
constexpr double kCopySpacing = 2.0;  // m
void build_db9k(World& world, const std::vector<XyrDisc>& discs, int copies = 1);
WorldDef db9k_world_def(int copies = 1);

// FNV-1a over the bits of positions, velocities, angles and angular velocities: equal state,
// equal hash.
uint64_t state_hash(const World& world);

// The repository's copy of the initial state.
std::string default_db9k_path();

}  // namespace demlab
