#include "calibration/rank_jobs.h"

#include "core/output_dir.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <mutex>
#include <thread>
#include <vector>

#include "calibration/ranks.h"
#include "core/error.h"
#include "core/interrupt.h"
#include "core/validate.h"
#include "run/run_folder.h"
#include "run/summary_file.h"

namespace demlab {

bool finished_run_of(const std::string& dir, const std::string& fingerprint) {
    const std::string summary = dir + "/summary.json";
    if (!std::filesystem::exists(summary)) return false;
    try {
        return read_summary_file(summary).text("scenario_fingerprint") == fingerprint;
    } catch (const std::exception&) {
        return false;  // unreadable: not a finished run of ours
    }
}

void open_folder_on_root(const std::string& out, const std::function<void()>& open) {
    const Ranks& ranks = Ranks::world();
    enum Kind { kOpened = 0, kRefused = 1, kWriteFailed = 2 };
    int kind = kOpened;
    std::string error;
    if (ranks.root()) {
        try {
            open();
        } catch (const WriteError& e) {
            kind = kWriteFailed;
            error = e.what();
        } catch (const std::exception& e) {
            kind = kRefused;
            error = e.what();
        }
    }
    const int worst = ranks.max_over_ranks(kind);
    const std::string said = error.empty() ? "output folder '" + out + "' was refused by rank 0 (its output says why)" : error;
    if (worst == kWriteFailed) throw WriteError(said);
    if (worst == kRefused) throw InputError(said);
}

RankJobsCount run_rank_jobs(const RankJobsDef& def) {
    const Ranks& ranks = Ranks::world();
    std::vector<size_t> mine;
    for (size_t k = 0; k < def.count; ++k)
        if (int(k % size_t(ranks.size())) == ranks.rank()) mine.push_back(k);
    RankJobsCount count;
    // which runs an earlier invocation finished: decided on every rank before any rank starts
    // one (the collective call below), so that rank 0's table says the same as the runs did
    count.reused_jobs.assign(def.count, false);
    for (size_t k = 0; k < def.count; ++k) count.reused_jobs[k] = def.finished(k);
    (void)ranks.any_failed(false);
    // Ctrl-C, SIGTERM or SIGHUP: every run in progress writes its checkpoint and stops, no new
    // one starts, and the command ends as interrupted (exit 4); run again, it reuses the finished
    // runs, resumes those with a checkpoint and starts the others afresh
    InterruptScope interrupts;
    bool interrupted = false;
    std::mutex mu;
    size_t next = 0;
    std::string error;
    // How the command ends, the same on every rank and for any number of jobs at once: bad input
    // wins (exit 2: the user has something to fix), then a failed write (5), then a failed run
    // (3); a signal (4) only when nothing failed otherwise. Within a rank the most telling error
    // is kept (two jobs failing at once: which came first is timing); across the ranks they are
    // compared once all are done (below).
    enum Outcome { kDone = 0, kInterrupted = 1, kRunFailed = 2, kWriteFailed = 3, kBadInput = 4 };
    int failure = kDone;  // this rank's worst error (kRunFailed and up), with its message
    const auto keep_error = [&](int kind, const std::string& message) {
        if (kind > failure) {
            failure = kind;
            error = message;
        }
    };
    const auto t0 = std::chrono::steady_clock::now();
    const auto worker = [&] {
        while (true) {
            size_t k;
            {
                std::lock_guard<std::mutex> lock(mu);
                if (next >= mine.size() || !error.empty() || interrupted) return;
                if (pending_interrupt() != 0) {
                    interrupted = true;
                    return;
                }
                k = mine[next++];
            }
            const std::string dir = def.folder(k);
            try {
                const bool reused = count.reused_jobs[k];
                bool resumed = false;
                if (!reused) {
                    if (std::filesystem::exists(dir)) {
                        if (!is_demlab_output(dir) && !std::filesystem::exists(dir + "/scenario.toml"))
                            throw InputError(dir + ": a folder demlab did not make stands where this run goes; move it");
                        // a run an interrupted invocation left with its checkpoint continues
                        // from it (the same bytes as a run without the stop); any other
                        // unfinished run, or one of another scenario or other input files, is
                        // removed (a folder demlab made, never someone else's)
                        resumed = def.resumable && def.resumable(k);
                        if (!resumed) {
                            // a run another process is making there now (a second sweep into the
                            // same folder) holds its lock: refused, not deleted under it; the
                            // lock is held while the folder goes, so none can take it meanwhile
                            RunFolderLock in_use(dir);
                            std::filesystem::remove_all(dir);
                        }
                    }
                    def.run(k, resumed);
                }
                const std::string line = def.describe(k);
                std::lock_guard<std::mutex> lock(mu);
                (reused ? count.reused : count.ran) += 1;
                long finished = 0;
                for (size_t j = 0; j < def.count; ++j) finished += def.finished(j) ? 1 : 0;
                const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
                const double eta = count.ran > 0 ? secs / count.ran * double(def.count - size_t(finished)) / ranks.size() : 0.0;
                std::printf("  %s%s; %ld / %zu runs done%s\n", line.c_str(),
                            reused ? " (reused)" : resumed ? " (resumed from its checkpoint)" : "", finished, def.count,
                            count.ran > 0 && size_t(finished) < def.count ? (", ETA " + format_number(std::round(eta)) + " s").c_str() : "");
                std::fflush(stdout);
            } catch (const Interrupted&) {
                std::lock_guard<std::mutex> lock(mu);
                interrupted = true;
            } catch (const InputError& e) {
                // input a run found wrong only once its mass was made (a tracer id beyond its
                // discs): the row named, and exit 2, as `demlab run` gives for the same input
                std::string tag = dir;
                try {
                    tag = def.describe(k);  // (a calibration's reads the run's figures: it may fail here)
                } catch (const std::exception&) {
                }
                std::lock_guard<std::mutex> lock(mu);
                keep_error(kBadInput, tag + ": " + e.what());
            } catch (const WriteError& e) {  // a full disk, a file size limit: exit 5, as `demlab run`
                std::lock_guard<std::mutex> lock(mu);
                keep_error(kWriteFailed, dir + ": " + e.what());
            } catch (const std::exception& e) {
                std::lock_guard<std::mutex> lock(mu);
                keep_error(kRunFailed, dir + ": " + e.what());
            }
        }
    };
    std::vector<std::thread> pool;
    for (int t = 0; t < std::min<int>(def.threads, int(mine.size())); ++t) pool.emplace_back(worker);
    for (auto& th : pool) th.join();
    // every rank stops with the same exit code (mpirun reports the code of whichever rank
    // stops first); the rank that met the deciding error names it, the others point to its
    // output and name their own
    const int this_rank = failure != kDone ? failure : interrupted ? kInterrupted : kDone;
    const int outcome = ranks.max_over_ranks(this_rank);
    if (outcome != kDone) {
        const std::string said = outcome == this_rank ? error
                                 : "on another rank (its output says which)" + (error.empty() ? "" : "; on this rank: " + error);
        if (outcome == kBadInput) throw InputError(def.what + " stopped: " + said);
        if (outcome == kWriteFailed) throw WriteError(def.what + " stopped: " + said);
        if (outcome == kRunFailed) throw RunError(def.what + " run failed: " + said);
        long finished = 0;
        for (size_t j = 0; j < def.count; ++j) finished += def.finished(j) ? 1 : 0;
        throw Interrupted(def.what + " stopped by a signal: " + std::to_string(finished) + " of " + std::to_string(def.count) +
                          " runs finished; the same command continues it (the runs stopped now resume from their "
                          "checkpoints)");
    }
    return count;
}

}  // namespace demlab
