// demlab bench db9k: the speed workload (docs/BENCHMARK.md), and optionally the peer (LAMMPS)
// on the same work in the same invocation; demlab bench jitter: the machine's interruptions.
#include <algorithm>
#include <array>
#include <chrono>
#include <cstdarg>
#include <cstdio>
#include <latch>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "app/bench_bonds.h"
#include "app/commands.h"
#include "core/process.h"
#include "setups/db9k.h"
#include "core/error.h"
#include "core/jitter.h"
#include "core/machine.h"
#include "core/progress.h"

namespace demlab {

namespace {
struct BenchOptions {
    std::string workload = "db9k";
    long steps = 20000;
    int copies = 1;  // columns side by side (build_db9k)
    std::string prefetch = "auto";  // WorldDef::prefetch: auto, on, off
    std::string file;
    bool peer = false;
    int threads = 1;
    bool scalar = false;
    bool no_avx512 = false;
    bool ceiling = false;
    bool targets = false;
    int rounds = 0;              // 0: not given (--targets: 5)
    bool threads_given = false;  // --threads on the command line
    bool steps_given = false;    // --steps on the command line
    double seconds = 10.0;       // s, jitter: how long the probes run
    bool seconds_given = false;
};

// One DB-9k run on `threads` threads, timed from its first step; `start`, when given, holds
// every run back until all are built (runs side by side).
struct TimedRun {
    double seconds = 0;
    uint64_t hash = 0;
    double busy_share = 1.0;  // of the threads' time in the shared force passes, the share they worked
    long fallbacks = 0;       // times the pass fell back to one range (a busy machine)
};
// DB-9k's world on `threads` threads with the options' kernels, ready to step
std::unique_ptr<World> db9k_world(const std::vector<XyrDisc>& discs, const BenchOptions& o, int threads) {
    WorldDef def = db9k_world_def(o.copies);
    def.threads = threads;
    def.simd = !o.scalar;
    def.avx512 = !o.no_avx512;
    def.prefetch = o.prefetch == "on" ? Prefetch::On : o.prefetch == "off" ? Prefetch::Off : Prefetch::Auto;
    auto world = std::make_unique<World>(def);
    build_db9k(*world, discs, o.copies);
    world->finalize();
    return world;
}

TimedRun timed_db9k(const std::vector<XyrDisc>& discs, const BenchOptions& o, int threads, std::latch* start) {
    const std::unique_ptr<World> w = db9k_world(discs, o, threads);
    World& world = *w;
    if (start) start->arrive_and_wait();
    const auto t0 = std::chrono::steady_clock::now();
    world.run(o.steps);
    TimedRun r;
    r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    r.hash = state_hash(world);
    if (world.force_pass_shared_seconds() > 0.0) r.busy_share = world.force_pass_busy_share();
    r.fallbacks = world.force_pass_busy_fallbacks();
    return r;
}

// What the machine's cores give together: `copies` independent 1-thread runs side by side
// (one thread each, nothing shared) against one 1-thread run alone. Two cores of a virtual
// machine need not give twice one core: they share the last-level cache and memory, and the
// host may run other work on them. Measured on the 2-core machine: two runs side by side each ran
// from 8 % faster to 27 % slower than one alone, so the 2-thread figure is best read against
// this ceiling.
struct Ceiling {
    TimedRun alone;
    std::vector<TimedRun> side;
    double cores_give = 0.0;  // the copies' rates summed, in units of the run alone
    bool same_bits = true;    // every copy ended in the run alone's state
};
Ceiling measure_ceiling(const std::vector<XyrDisc>& discs, const BenchOptions& o, int copies) {
    Ceiling c;
    c.alone = timed_db9k(discs, o, 1, nullptr);
    c.side.resize(static_cast<size_t>(copies));
    {
        std::latch start(copies);
        std::vector<std::thread> runs;
        for (int k = 0; k < copies; ++k)
            runs.emplace_back([&, k] { c.side[size_t(k)] = timed_db9k(discs, o, 1, &start); });
        for (std::thread& t : runs) t.join();
    }
    double rate_sum = 0.0;  // in units of 1/s: the same work in every run
    for (const TimedRun& r : c.side) {
        rate_sum += 1.0 / r.seconds;
        c.same_bits = c.same_bits && r.hash == c.alone.hash;
    }
    c.cores_give = rate_sum * c.alone.seconds;
    return c;
}

void print_ceiling(const std::vector<XyrDisc>& discs, const BenchOptions& o, double rate_shared) {
    const double n = double(discs.size()) * double(o.copies) * double(o.steps);
    const Ceiling c = measure_ceiling(discs, o, o.threads);
    const double rate_alone = n / c.alone.seconds;
    std::printf("ceiling: one 1-thread run alone %.3e particle-steps/s (%.1f ns); %d side by side:", rate_alone,
                1e9 * c.alone.seconds / n, o.threads);
    for (const TimedRun& r : c.side) std::printf(" %.1f", 1e9 * r.seconds / n);
    std::printf(" ns\n");
    std::printf("  the %d cores give %.2fx one core; demlab on %d threads gave %.2fx one 1-thread run, %.0f %% of "
                "the ceiling%s\n",
                o.threads, c.cores_give, o.threads, rate_shared / rate_alone, 100.0 * rate_shared / (c.cores_give * rate_alone),
                c.same_bits ? "" : " (the runs' checksums differ: a bug)");
}

// The peer's two styles of the same contact law on the same work: LAMMPS' general
// `pair_style granular` (Hooke, linear history) and its faster `gran/hooke/history` with
// `fix wall/gran hooke/history` (bench/db9k/lammps; ../docs/performance.md).
enum class PeerStyle { Granular, HookeHistory };
const char* peer_style_name(PeerStyle st) { return st == PeerStyle::Granular ? "granular" : "gran/hooke/history"; }

// Runs the LAMMPS script in one style and returns its particle-steps/s (0 if it could not
// run); `echo` passes its lines on.
double run_peer(long steps, int ranks, PeerStyle style, bool echo = true) {
    const std::string script = std::string(DEMLAB_SOURCE_DIR) + "/bench/db9k/lammps/run.sh";
    double rate = 0.0;
    ProcessDef peer;  // no shell
    peer.argv = {"bash", script, std::to_string(steps), std::to_string(ranks),
                 style == PeerStyle::Granular ? "bench.in" : "bench_hooke_history.in"};
    peer.on_line = [&](const std::string& line) {
        if (echo) std::fputs(("  [lammps " + std::string(peer_style_name(style)) + "] " + line).c_str(), stdout);
        const auto pos = line.find("particle-steps/s  max ");
        if (pos != std::string::npos) rate = std::atof(line.c_str() + pos + 22);
    };
    if (run_process(peer) < 0) return 0.0;
    return rate;
}

// printf into a string
[[gnu::format(printf, 1, 2)]] std::string strf(const char* fmt, ...) {
    char b[160];
    va_list args;
    va_start(args, fmt);
    std::vsnprintf(b, sizeof b, fmt, args);
    va_end(args);
    return b;
}

double median_of(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    const size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// "lo-hi" of v, each figure printed with `fmt` (scaled by `scale`); "-" for no figures
std::string range_of(const std::vector<double>& v, const char* fmt, double scale = 1.0) {
    if (v.empty()) return "-";
    const auto [lo, hi] = std::minmax_element(v.begin(), v.end());
    return strf(fmt, scale * *lo, scale * *hi);
}

// "met in every round", "met in the median" or "not met", and in how many rounds
std::string verdict(const std::vector<double>& v, double target) {
    const long k = long(std::count_if(v.begin(), v.end(), [target](double x) { return x >= target; }));
    const char* met = median_of(v) < target ? "not met" : k == long(v.size()) ? "met in every round" : "met in the median";
    return strf("%s (%ld of %zu rounds)", met, k, v.size());
}

// The figures in one invocation (docs/performance.md): rounds of demlab on 1 thread,
// LAMMPS on 1 rank, demlab on 2 threads, LAMMPS on 2 ranks and the two cores' ceiling, one
// after the other, so that the machine's drift (its speed wanders by 10-30 % over minutes
// here) touches every figure of a round alike. Prints each round as it ends, then a table of
// the rounds with their medians and ranges, then each target against the medians and round by
// round. A final state that differs between runs is a determinism bug: exit code 3.
int targets(const BenchOptions& o, const std::vector<XyrDisc>& discs) {
    const double n = double(discs.size()) * double(o.steps);  // particle-steps of one run
    const int rounds = o.rounds > 0 ? o.rounds : 5;
    std::printf("DB-9k targets: %d round(s) of %ld steps; each round demlab on 1 thread%s, demlab on 2 threads%s, "
                "then two 1-thread copies side by side against one alone\n",
                rounds, o.steps, o.peer ? ", LAMMPS on 1 rank (granular, then gran/hooke/history)" : "",
                o.peer ? ", LAMMPS on 2 ranks (both styles)" : "");
    if (o.peer) std::printf("ratios: demlab against LAMMPS' faster style, gran/hooke/history (against granular in brackets)\n");
    std::printf("machine: %s\n", machine_summary(machine_info()).c_str());
    // per round
    // peer1, peer2: gran/hooke/history (the faster style, the one the ratios are taken to);
    // gpeer1, gpeer2: pair_style granular
    std::vector<double> ns1, ns2, peer1, peer2, gpeer1, gpeer2, ratio1, ratio2, gratio1, gratio2, speedup, busy, cores,
        of_ceiling;
    bool peer = o.peer, same_bits = true;
    uint64_t hash = 0;
    long fallbacks = 0, runs = 0;
    for (int r = 0; r < rounds; ++r) {
        const TimedRun one = timed_db9k(discs, o, 1, nullptr);
        const double g1 = peer ? run_peer(o.steps, 1, PeerStyle::Granular, false) : 0.0;
        const double p1 = peer ? run_peer(o.steps, 1, PeerStyle::HookeHistory, false) : 0.0;
        const TimedRun two = timed_db9k(discs, o, 2, nullptr);
        const double g2 = peer ? run_peer(o.steps, 2, PeerStyle::Granular, false) : 0.0;
        const double p2 = peer ? run_peer(o.steps, 2, PeerStyle::HookeHistory, false) : 0.0;
        const Ceiling c = measure_ceiling(discs, o, 2);
        if (r == 0) hash = one.hash;
        same_bits = same_bits && one.hash == hash && two.hash == hash && c.alone.hash == hash && c.same_bits;
        runs += 5;
        fallbacks += two.fallbacks;
        const double rate1 = n / one.seconds, rate2 = n / two.seconds;
        ns1.push_back(1e9 / rate1);
        ns2.push_back(1e9 / rate2);
        speedup.push_back(rate2 / rate1);
        busy.push_back(two.busy_share);
        cores.push_back(c.cores_give);
        of_ceiling.push_back(rate2 / (c.cores_give * n / c.alone.seconds));
        std::printf("  round %d: 1 thread %.1f ns, 2 threads %.1f ns (%.2fx), the two cores give %.2fx", r + 1, ns1.back(),
                    ns2.back(), speedup.back(), c.cores_give);
        if (peer && (p1 <= 0.0 || p2 <= 0.0 || g1 <= 0.0 || g2 <= 0.0)) {
            peer = false;
            std::printf("; LAMMPS did not run (install it with scripts/install-deps.sh --peer)");
        } else if (peer) {
            peer1.push_back(p1);
            peer2.push_back(p2);
            gpeer1.push_back(g1);
            gpeer2.push_back(g2);
            ratio1.push_back(rate1 / p1);
            ratio2.push_back(rate2 / p2);
            gratio1.push_back(rate1 / g1);
            gratio2.push_back(rate2 / g2);
            std::printf("; demlab vs LAMMPS gran/hooke/history %.2f (1 thread vs 1 rank), %.2f (2 threads vs 2 ranks); "
                        "vs granular %.2f, %.2f",
                        ratio1.back(), ratio2.back(), gratio1.back(), gratio2.back());
        }
        std::printf("\n");
        std::fflush(stdout);
    }

    // the rounds as a table (figures as particle-steps/s, with ns per particle-step)
    auto rate_cell = [](double ns) { return strf("%.3e (%.1f)", 1e9 / ns, ns); };
    auto peer_cell = [&](const std::vector<double>& v, size_t r, const char* fmt) { return peer ? strf(fmt, v[r]) : "-"; };
    // (LAMMPS columns: particle-steps/s of granular, then of gran/hooke/history; the ratio is
    // demlab's to the faster style, gran/hooke/history)
    std::printf("\n| round | 1 thread: demlab (ns) | LAMMPS 1 rank: granular | gran/hooke/history | ratio to the faster "
                "| 2 threads: demlab (ns) | LAMMPS 2 ranks: granular | gran/hooke/history | ratio to the faster "
                "| 2 threads / 1 | busy share | the two cores give | 2 threads, of the ceiling |\n"
                "|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    for (size_t r = 0; r < ns1.size(); ++r)
        std::printf("| %zu | %s | %s | %s | %s | %s | %s | %s | %s | %.2f | %.1f %% | %.2fx | %.0f %% |\n", r + 1,
                    rate_cell(ns1[r]).c_str(), peer_cell(gpeer1, r, "%.3e").c_str(), peer_cell(peer1, r, "%.3e").c_str(),
                    peer_cell(ratio1, r, "%.2f").c_str(), rate_cell(ns2[r]).c_str(), peer_cell(gpeer2, r, "%.3e").c_str(),
                    peer_cell(peer2, r, "%.3e").c_str(), peer_cell(ratio2, r, "%.2f").c_str(), speedup[r], 100.0 * busy[r],
                    cores[r], 100.0 * of_ceiling[r]);
    auto med = [&](const std::vector<double>& v, const char* fmt) { return peer ? strf(fmt, median_of(v)) : std::string("-"); };
    std::printf("| median | %s | %s | %s | %s | %s | %s | %s | %s | %.2f (%.2f from the medians) | %.1f %% | %.2fx | %.0f %% |\n",
                rate_cell(median_of(ns1)).c_str(), med(gpeer1, "%.3e").c_str(), med(peer1, "%.3e").c_str(),
                med(ratio1, "%.2f").c_str(), rate_cell(median_of(ns2)).c_str(), med(gpeer2, "%.3e").c_str(),
                med(peer2, "%.3e").c_str(), med(ratio2, "%.2f").c_str(), median_of(speedup), median_of(ns1) / median_of(ns2),
                100.0 * median_of(busy), median_of(cores), 100.0 * median_of(of_ceiling));
    std::printf("| range | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |\n", range_of(ns1, "%.1f-%.1f ns").c_str(),
                range_of(gpeer1, "%.3e-%.3e").c_str(), range_of(peer1, "%.3e-%.3e").c_str(), range_of(ratio1, "%.2f-%.2f").c_str(),
                range_of(ns2, "%.1f-%.1f ns").c_str(), range_of(gpeer2, "%.3e-%.3e").c_str(), range_of(peer2, "%.3e-%.3e").c_str(),
                range_of(ratio2, "%.2f-%.2f").c_str(), range_of(speedup, "%.2f-%.2f").c_str(),
                range_of(busy, "%.1f-%.1f %%", 100.0).c_str(), range_of(cores, "%.2f-%.2fx").c_str(),
                range_of(of_ceiling, "%.0f-%.0f %%", 100.0).c_str());
    if (peer)
        std::printf("\nAgainst the slower style, granular: %.2fx on 1 thread vs 1 rank (%s), %.2fx on 2 threads vs 2 ranks (%s).\n",
                    median_of(gratio1), range_of(gratio1, "%.2f-%.2f").c_str(), median_of(gratio2),
                    range_of(gratio2, "%.2f-%.2f").c_str());
    if (fallbacks > 0)
        std::printf("\nThe 2-thread runs fell back to one range %ld time(s): another process took a core, and their "
                    "figures are not the machine's.\n",
                    fallbacks);

    // the targets (issue #6), against the medians, and in how many rounds
    std::printf("\n| target | required | measured | verdict |\n|---|---|---|---|\n");
    if (peer) {
        std::printf("| 1 thread vs LAMMPS gran/hooke/history 1 rank | 5x | %.2fx (median; %s) | %s |\n", median_of(ratio1),
                    range_of(ratio1, "%.2f-%.2f").c_str(), verdict(ratio1, 5.0).c_str());
        std::printf("| 2 threads vs LAMMPS gran/hooke/history 2 ranks | 5x | %.2fx (median; %s) | %s |\n", median_of(ratio2),
                    range_of(ratio2, "%.2f-%.2f").c_str(), verdict(ratio2, 5.0).c_str());
    } else {
        std::printf("| 1 and 2 threads vs LAMMPS' faster style on 1 and 2 ranks | 5x | - | not measured (give --peer; LAMMPS "
                    "from scripts/install-deps.sh --peer) |\n");
    }
    std::printf("| 2 threads vs demlab's 1 thread | 1.8x | %.2fx (median pair by pair; %s; two independent copies got "
                "%.2fx) | %s |\n",
                median_of(speedup), range_of(speedup, "%.2f-%.2f").c_str(), median_of(cores), verdict(speedup, 1.8).c_str());
    if (same_bits)
        std::printf("| final state, 1 vs 2 threads | identical | checksum %016llx in all %ld runs | met |\n",
                    static_cast<unsigned long long>(hash), runs);
    else
        std::printf("| final state, 1 vs 2 threads | identical | the checksums differ | NOT MET |\n");
    if (!same_bits) {
        std::fprintf(stderr, "demlab bench: runs of the same work ended in different states (a determinism bug)\n");
        return kExitRun;
    }
    return kExitOk;
}

// demlab bench jitter: the machine's interruptions on each core (jitter.h), and what they
// cost a run whose threads join every step.
int jitter(const BenchOptions& o) {
    const int cores = o.threads_given ? o.threads : std::max(1, int(std::thread::hardware_concurrency()));
    std::printf("jitter: a probe on each of %d core(s) reads the clock for %.1f s; a gap is two readings more than 10 us "
                "apart\n",
                cores, o.seconds);
    double lost_share = 0.0;
    for (const CoreGaps& g : measure_gaps(cores, o.seconds)) {
        const double share = g.seconds > 0.0 ? g.lost / g.seconds : 0.0;
        lost_share += share;
        std::printf("  core %s: %ld gaps (%.0f a second), %.3f s lost (%.2f %%), mean %.0f us, longest %.0f us\n",
                    g.core >= 0 ? std::to_string(g.core).c_str() : "(not pinned)", g.gaps,
                    g.seconds > 0.0 ? double(g.gaps) / g.seconds : 0.0, g.lost, 100.0 * share,
                    g.gaps > 0 ? 1e6 * g.lost / double(g.gaps) : 0.0, 1e6 * g.longest);
    }
    if (cores > 1)
        std::printf("  a run whose %d threads join every step waits for every core's gaps: about %.1f %% of its time; "
                    "independent runs lose only their own core's\n",
                    cores, 100.0 * lost_share);
    return kExitOk;
}

int bench(const BenchOptions& o) {
    if (o.workload == "jitter") {
        if (o.peer || o.targets || o.ceiling || o.rounds > 0 || o.steps_given || o.scalar || o.no_avx512 || !o.file.empty() ||
            o.copies != 1 || o.prefetch != "auto")
            throw InputError("bench jitter: takes only --seconds and --threads (the cores to probe); the other options are "
                             "DB-9k's");
        return jitter(o);
    }
    if (o.seconds_given) throw InputError("bench --seconds: only with the jitter workload (bench jitter --seconds S)");
    if (o.workload == "bonds") {
        if (o.peer || o.targets || o.ceiling || o.copies != 1 || o.prefetch != "auto")
            throw InputError("bench bonds: takes --steps, --threads, --rounds, --file (a scenario with bonds), --scalar and "
                             "--no-avx512; the other options are DB-9k's");
        BondBenchOptions b;
        b.scenario = o.file;
        if (o.steps_given) b.steps = o.steps;
        b.threads = o.threads;
        if (o.rounds > 0) b.rounds = o.rounds;
        b.scalar = o.scalar;
        b.no_avx512 = o.no_avx512;
        return bench_bonds(b);
    }
    if (o.workload != "db9k") throw InputError("bench: unknown workload '" + o.workload + "'; accepted: db9k, bonds, jitter");
    if (o.steps < 1) throw InputError("bench --steps = " + std::to_string(o.steps) + ": must be >= 1");
    if (o.ceiling && o.threads < 2)
        throw InputError("bench --ceiling with --threads = " + std::to_string(o.threads) +
                         ": needs --threads 2 or more (it runs that many 1-thread copies side by side)");
    if (o.copies != 1 && (o.peer || o.targets))
        throw InputError("bench --copies = " + std::to_string(o.copies) + " with " + (o.peer ? "--peer" : "--targets") +
                         ": the peer's script runs one column; compare with LAMMPS on --copies 1");
    if (o.rounds > 0 && !o.targets) throw InputError("bench --rounds: only with --targets or the bonds workload");
    if (o.targets && (o.threads_given || o.ceiling))
        throw InputError(std::string("bench --targets with ") + (o.ceiling ? "--ceiling" : "--threads") +
                         ": --targets runs 1 and 2 threads and the two cores' ceiling itself; leave it out");
    const std::string path = o.file.empty() ? default_db9k_path() : o.file;
    const auto discs = read_xyr(path);
    if (o.targets) return targets(o, discs);
    const std::unique_ptr<World> w = db9k_world(discs, o, o.threads);
    World& world = *w;

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
    std::printf("DB-9k%s: N=%zu steps=%ld dt=%g s threads=%d, %s pair kernel\n",
                o.copies > 1 ? strf(" (%d columns side by side)", o.copies).c_str() : "", world.disc_count(), o.steps, world.dt(),
                o.threads, world.avx512_kernel() ? "AVX-512" : world.simd_kernel() ? "AVX2" : "scalar");
    std::printf("  machine: %s\n", machine_summary(machine_info()).c_str());
    std::printf("  wall time %.3f s, %.3e particle-steps/s, %.1f ns per particle-step\n", secs, rate,
                1e9 * secs / (double(world.disc_count()) * double(o.steps)));
    std::printf("  broad phase: margin %.3g m, %ld updates (%.3f s, %.1f %% of the wall time), %ld re-insertions, %ld "
                "queries in %ld tree walks; contacts now %ld disc-disc, %ld disc-wall\n",
                world.broad_phase_margin(), bs.updates, world.list_update_seconds(),
                100.0 * world.list_update_seconds() / secs, bs.disc_reinserts, bs.queries, bs.tree_walks,
                world.touching_disc_pairs(), world.touching_wall_pairs());
    std::printf("  software prefetch: %s (the step streams %.1f MB; auto: on above %.1f MB, half the last-level cache)\n",
                world.prefetching() ? "on" : "off", double(world.step_bytes()) / (1 << 20),
                double(prefetch_threshold_bytes()) / (1 << 20));
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
        for (const PeerStyle style : {PeerStyle::Granular, PeerStyle::HookeHistory}) {
            std::printf("peer: LAMMPS %s, %ld steps, %d rank(s)\n", peer_style_name(style), o.steps, ranks);
            const double peer = run_peer(o.steps, ranks, style);
            if (peer > 0)
                std::printf("  demlab %.3e vs LAMMPS %s %.3e particle-steps/s: ratio %.2f%s\n", rate, peer_style_name(style),
                            peer, rate / peer, style == PeerStyle::HookeHistory ? " (the faster style: the ratio that counts)" : "");
            else
                std::printf("  LAMMPS did not run (install it with scripts/install-deps.sh --peer)\n");
        }
    }
    return kExitOk;
}
}  // namespace

Command add_bench_command(CLI::App& app) {
    auto opts = std::make_shared<BenchOptions>();
    CLI::App* sub = app.add_subcommand("bench", "Speed benchmark: prints particle-steps per second and a state checksum");
    sub->add_option("workload", opts->workload,
                    "Workload to run: db9k (the speed workload), bonds (what cohesive bonds cost: a bonded scenario, "
                    "default the snow slab, bonds on against off), jitter (the machine's interruptions on each core)")
        ->capture_default_str();
    CLI::Option* steps = sub->add_option("--steps", opts->steps, "Number of time steps (20000: the quick figure; 100000: the reference)")
        ->capture_default_str();
    sub->add_option("--copies", opts->copies,
                    "Columns side by side, each 2 m further along x with its own left wall: the speed at a larger "
                    "N (16 copies: 146,240 discs, the flume's mass at the real sand size)")
        ->capture_default_str()->check(CLI::Range(1, 64));
    sub->add_option("--prefetch", opts->prefetch,
                    "Software prefetch in the force and centre passes: auto (on when the step streams more than half the last-level "
                    "cache), on, off (the same bits; for comparison)")
        ->capture_default_str()->check(CLI::IsMember({"auto", "on", "off"}));
    sub->add_option("--file", opts->file, "db9k: initial state 'id x y r' (default: the repository's bench/db9k/db9k_initial.xyr); "
                    "bonds: a scenario with bonds (default scenarios/snow-slide-2d.toml)");
    CLI::Option* threads = sub->add_option("--threads", opts->threads, "Worker threads (the final state is the same bits for any count); jitter: the cores to probe (default: all)")
        ->capture_default_str()->check(CLI::Range(1, 64));
    sub->add_flag("--scalar", opts->scalar, "Use the scalar loops (pair forces, integration) even if the CPU has AVX2 (the same bits; for comparison)");
    sub->add_flag("--no-avx512", opts->no_avx512, "Run the pair law four pairs and the integration four discs at a time (AVX2) even if the CPU has AVX-512 (the same bits; for comparison)");
    sub->add_flag("--ceiling", opts->ceiling,
                  "With --threads T >= 2: also run one 1-thread copy alone and T side by side, and print what the "
                  "cores give together (the ceiling of the T-thread figure on this machine)");
    sub->add_flag("--peer", opts->peer,
                  "Also run LAMMPS (bench/db9k/lammps/run.sh) on the same work in both its styles, pair_style granular and the "
                  "faster gran/hooke/history, and print the ratios (the one to the faster counts)");
    sub->add_flag("--targets", opts->targets,
                  "The issue's side-by-side figures: rounds of 1 thread, 2 threads and the two cores' ceiling (with "
                  "--peer, LAMMPS on 1 and 2 ranks too); prints a table with medians and ranges, and each target met or not");
    sub->add_option("--rounds", opts->rounds, "With --targets: how many rounds (default 5; about a minute each with --peer); "
                    "bonds: pairs of runs (default 3)")
        ->check(CLI::Range(1, 100));
    CLI::Option* seconds = sub->add_option("--seconds", opts->seconds, "jitter: how long the probes run, s")
        ->capture_default_str()->check(CLI::Range(0.01, 600.0));
    return [opts, threads, steps, seconds] {
        opts->threads_given = threads->count() > 0;
        opts->steps_given = steps->count() > 0;
        opts->seconds_given = seconds->count() > 0;
        return bench(*opts);
    };
}

}  // namespace demlab
