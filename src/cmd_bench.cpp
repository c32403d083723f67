// demlab bench db9k: the speed workload (docs/BENCHMARK.md), and optionally the peer (LAMMPS)
// on the same work in the same invocation.
#include <array>
#include <chrono>
#include <cstdio>
#include <latch>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "commands.h"
#include "db9k.h"
#include "error.h"
#include "progress.h"

namespace demlab {

namespace {
struct BenchOptions {
    std::string workload = "db9k";
    long steps = 20000;
    std::string file;
    bool peer = false;
    int threads = 1;
    bool scalar = false;
    bool no_avx512 = false;
    bool ceiling = false;
};

// One DB-9k run on `threads` threads, timed from its first step; `start`, when given, holds
// every run back until all are built (runs side by side).
struct TimedRun {
    double seconds = 0;
    uint64_t hash = 0;
};
TimedRun timed_db9k(const std::vector<XyrDisc>& discs, const BenchOptions& o, int threads, std::latch* start) {
    WorldDef def = db9k_world_def();
    def.threads = threads;
    def.simd = !o.scalar;
    def.avx512 = !o.no_avx512;
    World world(def);
    build_db9k(world, discs);
    world.finalize();
    if (start) start->arrive_and_wait();
    const auto t0 = std::chrono::steady_clock::now();
    world.run(o.steps);
    TimedRun r;
    r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    r.hash = state_hash(world);
    return r;
}

// What the machine's cores give together: `copies` independent 1-thread runs side by side
// (one thread each, nothing shared) against one 1-thread run alone. Two cores of a virtual
// machine need not give twice one core: they share the last-level cache and memory, and the
// host may run other work on them. Measured here (session 12), two runs side by side each ran
// from 8 % faster to 27 % slower than one alone, so the 2-thread figure is best read against
// this ceiling.
void print_ceiling(const std::vector<XyrDisc>& discs, const BenchOptions& o, double rate_shared) {
    const double n = double(discs.size()) * double(o.steps);
    const TimedRun alone = timed_db9k(discs, o, 1, nullptr);
    const int copies = o.threads;
    std::vector<TimedRun> side(static_cast<size_t>(copies));
    {
        std::latch start(copies);
        std::vector<std::thread> runs;
        for (int k = 0; k < copies; ++k)
            runs.emplace_back([&, k] { side[size_t(k)] = timed_db9k(discs, o, 1, &start); });
        for (std::thread& t : runs) t.join();
    }
    const double rate_alone = n / alone.seconds;
    double rate_sum = 0.0;
    bool same_bits = true;
    std::printf("ceiling: one 1-thread run alone %.3e particle-steps/s (%.1f ns); %d side by side:", rate_alone,
                1e9 * alone.seconds / n, copies);
    for (const TimedRun& r : side) {
        rate_sum += n / r.seconds;
        same_bits = same_bits && r.hash == alone.hash;
        std::printf(" %.1f", 1e9 * r.seconds / n);
    }
    std::printf(" ns\n");
    std::printf("  the %d cores give %.2fx one core; demlab on %d threads gave %.2fx one 1-thread run, %.0f %% of "
                "the ceiling%s\n",
                copies, rate_sum / rate_alone, o.threads, rate_shared / rate_alone, 100.0 * rate_shared / rate_sum,
                same_bits ? "" : " (the runs' checksums differ: a bug)");
}

// Runs the LAMMPS script and returns its particle-steps/s (0 if it could not run).
double run_peer(long steps, int ranks) {
    const std::string script = std::string(DEMLAB_SOURCE_DIR) + "/bench/db9k/lammps/run.sh";
    const std::string cmd = "bash '" + script + "' " + std::to_string(steps) + " " + std::to_string(ranks) + " 2>&1";
    std::unique_ptr<FILE, int (*)(FILE*)> pipe(popen(cmd.c_str(), "r"), pclose);
    if (!pipe) return 0.0;
    std::array<char, 512> buf{};
    double rate = 0.0;
    while (fgets(buf.data(), int(buf.size()), pipe.get())) {
        std::string line(buf.data());
        std::fputs(("  [lammps] " + line).c_str(), stdout);
        const auto pos = line.find("particle-steps/s  max ");
        if (pos != std::string::npos) rate = std::stod(line.substr(pos + 22));
    }
    return rate;
}

int bench(const BenchOptions& o) {
    if (o.workload != "db9k") throw InputError("bench: unknown workload '" + o.workload + "'; accepted: db9k");
    if (o.steps < 1) throw InputError("bench --steps = " + std::to_string(o.steps) + ": must be >= 1");
    if (o.ceiling && o.threads < 2)
        throw InputError("bench --ceiling with --threads = " + std::to_string(o.threads) +
                         ": needs --threads 2 or more (it runs that many 1-thread copies side by side)");
    const std::string path = o.file.empty() ? default_db9k_path() : o.file;
    const auto discs = read_xyr(path);
    WorldDef def = db9k_world_def();
    def.threads = o.threads;
    def.simd = !o.scalar;
    def.avx512 = !o.no_avx512;
    World world(def);
    build_db9k(world, discs);
    world.finalize();

    Progress progress(double(o.steps), "steps");
    const auto t0 = std::chrono::steady_clock::now();
    for (long s = 0; s < o.steps; ++s) {
        world.step();
        if ((s & 255) == 0) progress.update(double(s), s);
    }
    const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    progress.finish();
    const double rate = double(world.disc_count()) * double(o.steps) / secs;
    const auto& bs = world.broad_phase_stats();
    std::printf("DB-9k: N=%zu steps=%ld dt=%g s threads=%d, %s pair kernel\n", world.disc_count(), o.steps, world.dt(),
                o.threads, world.avx512_kernel() ? "AVX-512" : world.simd_kernel() ? "AVX2" : "scalar");
    std::printf("  wall time %.3f s, %.3e particle-steps/s, %.1f ns per particle-step\n", secs, rate,
                1e9 * secs / (double(world.disc_count()) * double(o.steps)));
    std::printf("  broad phase: margin %.3g m, %ld updates (%.3f s, %.1f %% of the wall time), %ld re-insertions, %ld "
                "queries in %ld tree walks; contacts now %ld disc-disc, %ld disc-wall\n",
                world.broad_phase_margin(), bs.updates, world.list_update_seconds(),
                100.0 * world.list_update_seconds() / secs, bs.disc_reinserts, bs.queries, bs.tree_walks,
                world.touching_disc_pairs(), world.touching_wall_pairs());
    std::printf("  force pass: %d disc range(s), %zu of %zu candidate pairs cross ranges; %.1f %% of the candidates "
                "skipped as clear\n",
                world.force_pass_ranges(), world.cross_contacts(), world.disc_contacts().size(),
                world.candidate_passes() > 0 ? 100.0 * double(world.pairs_skipped()) / double(world.candidate_passes()) : 0.0);
    if (world.force_pass_ranges() > 1) {
        std::printf("  force-pass shares after %ld re-cut(s) to balance the ranges' times:", world.force_pass_rebalances());
        for (double s : world.force_pass_shares()) std::printf(" %.3f", s);
        std::printf("\n");
    }
    if (world.force_pass_shared_seconds() > 0.0)
        std::printf("  shared force passes: %.3f s wall (%.1f %% of the wall time); the ranges worked %.1f %% of the "
                    "threads' time in them, waited %.1f %% (at the join for the slower range, for cross contacts, "
                    "for the hand-over)\n",
                    world.force_pass_shared_seconds(), 100.0 * world.force_pass_shared_seconds() / secs,
                    100.0 * world.force_pass_busy_share(), 100.0 * (1.0 - world.force_pass_busy_share()));
    if (world.force_pass_busy_fallbacks() > 0)
        std::printf("  the machine was busy: the pass fell back to one range %ld time(s), for %ld of the %ld steps "
                    "(a core taken by another process; give --threads no more than the free cores)\n",
                    world.force_pass_busy_fallbacks(), world.force_pass_one_range_steps(), o.steps);
    std::printf("  final-state checksum %016llx\n", static_cast<unsigned long long>(state_hash(world)));
    if (o.ceiling) print_ceiling(discs, o, rate);
    if (o.peer) {
        const int ranks = o.threads > 1 ? 2 : 1;
        std::printf("peer: LAMMPS, %ld steps, %d rank(s)\n", o.steps, ranks);
        const double peer = run_peer(o.steps, ranks);
        if (peer > 0)
            std::printf("  demlab %.3e vs LAMMPS %.3e particle-steps/s: ratio %.2f\n", rate, peer, rate / peer);
        else
            std::printf("  LAMMPS did not run (install it with scripts/install-deps.sh --peer)\n");
    }
    return kExitOk;
}
}  // namespace

Command add_bench_command(CLI::App& app) {
    auto opts = std::make_shared<BenchOptions>();
    CLI::App* sub = app.add_subcommand("bench", "Speed benchmark: prints particle-steps per second and a state checksum");
    sub->add_option("workload", opts->workload, "Workload to run (db9k)")->capture_default_str();
    sub->add_option("--steps", opts->steps, "Number of time steps (20000: the quick figure; 100000: the reference)")
        ->capture_default_str();
    sub->add_option("--file", opts->file, "Initial state 'id x y r' (default: the repository's bench/db9k/db9k_initial.xyr)");
    sub->add_option("--threads", opts->threads, "Worker threads (the final state is the same bits for any count)")
        ->capture_default_str()->check(CLI::Range(1, 64));
    sub->add_flag("--scalar", opts->scalar, "Use the scalar loops (pair forces, integration) even if the CPU has AVX2 (the same bits; for comparison)");
    sub->add_flag("--no-avx512", opts->no_avx512, "Run the pair law four pairs at a time (AVX2) even if the CPU has AVX-512 (the same bits; for comparison)");
    sub->add_flag("--ceiling", opts->ceiling,
                  "With --threads T >= 2: also run one 1-thread copy alone and T side by side, and print what the "
                  "cores give together (the ceiling of the T-thread figure on this machine)");
    sub->add_flag("--peer", opts->peer, "Also run LAMMPS (bench/db9k/lammps/run.sh) on the same work and print the ratio");
    return [opts] { return bench(*opts); };
}

}  // namespace demlab
