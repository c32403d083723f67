// The runs of a sweep (the calibration's, `demlab sweep`'s) spread over the MPI ranks and, on
// each, over threads: rank r takes every size-th job from the r-th. A job whose folder holds a
// summary.json is reused, an unfinished folder is emptied and run again, so a sweep resumes with any number of ranks. Each finished job prints a
// line with the count of finished jobs in the folder (all ranks') and an ETA from this rank's
// pace. Once every rank is done, a failure on any rank is thrown on all of them.
#pragma once
#include <cstddef>
#include <functional>
#include <string>

namespace demlab {

struct RankJobsDef {
    size_t count = 0;       // jobs in the sweep
    int threads = 1;        // at once on this rank
    std::string what;       // "calibration", "sweep": names the failure
    std::function<std::string(size_t)> folder;    // job k's run folder (finished: its summary.json)
    std::function<void(size_t)> run;              // runs job k into its folder (emptied first)
    // job k's line once finished ("phi15.00 seed 1: objective 4.50 deg"); may also write the
    // job's own figures into its folder
    std::function<std::string(size_t)> describe;
};

struct RankJobsCount {
    int ran = 0, reused = 0;  // this rank's
};

RankJobsCount run_rank_jobs(const RankJobsDef& def);

}  // namespace demlab
