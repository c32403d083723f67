#include "app/bench_bonds.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <vector>

#include "app/commands.h"
#include "core/error.h"
#include "core/machine.h"
#include "core/progress.h"
#include "run/run.h"
#include "scenario/scenario.h"
#include "setups/db9k.h"

namespace demlab {

namespace {
struct BondRun {
    double seconds = 0;
    size_t discs = 0, bonds = 0;
    uint64_t hash = 0;
};

BondRun timed(const Scenario& base, bool bonds, const BondBenchOptions& o) {
    Scenario s = base;
    s.cohesion.enabled = bonds;
    s.world.threads = o.threads;
    s.world.simd = !o.scalar;
    s.world.avx512 = !o.no_avx512;
    World w = world_of_scenario(s);
    BondRun r;
    r.discs = w.disc_count();
    r.bonds = w.bonds().size();
    Progress progress(double(o.steps), bonds ? "steps, bonds on" : "steps, bonds off");
    const auto t0 = std::chrono::steady_clock::now();
    for (long k = 0; k < o.steps; ++k) {
        w.step();
        if ((k & 255) == 0) progress.update(double(k), k);
    }
    r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    progress.finish();
    r.hash = state_hash(w);
    return r;
}

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    const size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}
}  // namespace

int bench_bonds(const BondBenchOptions& o) {
    if (o.steps < 1) throw InputError("bench bonds --steps = " + std::to_string(o.steps) + ": must be >= 1");
    const std::string path = o.scenario.empty() ? std::string(DEMLAB_SOURCE_DIR) + "/scenarios/snow-slide-2d.toml" : o.scenario;
    Scenario s = load_scenario(path);
    finish_scenario(s);
    if (!s.cohesion.enabled) throw InputError(path + ": bench bonds needs a scenario with cohesion.enabled = true");
    std::printf("bonds on against off: %s, %ld steps, %d thread(s), %d interleaved pair(s)\n", path.c_str(), o.steps,
                o.threads, o.rounds);
    std::printf("  machine: %s\n", machine_summary(machine_info()).c_str());
    std::vector<double> on_ns, off_ns, ratios;
    BondRun on, off;
    for (int k = 0; k < o.rounds; ++k) {
        on = timed(s, true, o);
        off = timed(s, false, o);
        const double a = 1e9 * on.seconds / (double(on.discs) * double(o.steps));
        const double b = 1e9 * off.seconds / (double(off.discs) * double(o.steps));
        on_ns.push_back(a);
        off_ns.push_back(b);
        ratios.push_back(a / b);
        std::printf("  pair %d: bonds on %.1f ns, off %.1f ns per particle-step: %+.1f %%\n", k + 1, a, b, 100.0 * (a / b - 1.0));
    }
    const double cost = median(ratios) - 1.0;
    std::printf("  %zu discs, %zu bonds (%.2f a disc): on %.1f ns, off %.1f ns per particle-step (medians); the bonds "
                "add %+.1f %% (the pairs' range %+.1f to %+.1f %%); target at most +30 %%: %s\n",
                on.discs, on.bonds, double(on.bonds) / double(on.discs), median(on_ns), median(off_ns), 100.0 * cost,
                100.0 * (*std::min_element(ratios.begin(), ratios.end()) - 1.0),
                100.0 * (*std::max_element(ratios.begin(), ratios.end()) - 1.0), cost <= 0.30 ? "met" : "not met");
    std::printf("  final-state checksums: on %016llx, off %016llx\n", static_cast<unsigned long long>(on.hash),
                static_cast<unsigned long long>(off.hash));
    return kExitOk;
}

}  // namespace demlab
