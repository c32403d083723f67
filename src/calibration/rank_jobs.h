// The runs of a sweep (the calibration's, `demlab sweep`'s) spread over the MPI ranks and, on
// each, over threads: rank r takes every size-th job from the r-th. A job whose folder holds
// a finished run of the same scenario (`finished`: its summary.json with this job's
// scenario_fingerprint) is reused; one holding a checkpoint of the job's scenario and input
// files (an interrupted invocation's: `resumable`) is resumed from it; any other folder
// (unfinished, or of another scenario or other input files) is emptied and run again, so a
// sweep continues with any number of ranks.
// Every rank decides which jobs are reused before any rank runs one. Each finished job prints a
// line with the count of finished jobs in the folder (all ranks') and an ETA from this rank's
// pace. Once every rank is done, a failure on any rank is thrown on all of them.
#pragma once
#include <cstddef>
#include <functional>
#include <string>
#include <vector>

namespace demlab {

struct RankJobsDef {
    size_t count = 0;       // jobs in the sweep
    int threads = 1;        // at once on this rank
    std::string what;       // "calibration", "sweep": names the failure
    std::function<std::string(size_t)> folder;    // job k's run folder
    std::function<bool(size_t)> finished;         // whether job k's folder holds its finished run
    std::function<bool(size_t)> resumable;        // whether job k's folder holds a checkpoint of its run
    // runs job k into its folder (emptied first), or with resume true continues it from its
    // checkpoint
    std::function<void(size_t, bool resume)> run;
    // job k's line once finished ("phi15.00 seed 1: objective 4.50 deg"); may also write the
    // job's own figures into its folder
    std::function<std::string(size_t)> describe;
};

struct RankJobsCount {
    int ran = 0, reused = 0;  // this rank's
    std::vector<bool> reused_jobs;  // every job (all ranks'): taken from an earlier invocation
};

// Whether DIR holds a finished run (summary.json) of the scenario with this fingerprint.
bool finished_run_of(const std::string& dir, const std::string& fingerprint);

RankJobsCount run_rank_jobs(const RankJobsDef& def);

// Rank 0 opens the sweep's output folder OUT with OPEN (checks, makes, marks it); the other ranks
// wait for it. A failure reaches every rank as the same class: a failed write (WriteError, exit 5)
// or a refused folder (InputError, exit 2, for anything else), so that no rank waits for ever and
// mpirun ends with one code.
void open_folder_on_root(const std::string& out, const std::function<void()>& open);

}  // namespace demlab
