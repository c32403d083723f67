// demlab bench bonds: what cohesive bonds cost, bonds on against bonds off on the same discs
// and the same number of steps (the snow slab of scenarios/snow-slide-2d.toml by default).
#pragma once
#include <string>

namespace demlab {

struct BondBenchOptions {
    std::string scenario;  // default: the repository's scenarios/snow-slide-2d.toml
    long steps = 6000;     // the slab's slide down the slope to the toe (about 3.3 s)
    int threads = 1;
    int rounds = 3;        // pairs of runs, on and off interleaved
    bool scalar = false, no_avx512 = false;
};

int bench_bonds(const BondBenchOptions& o);

}  // namespace demlab
