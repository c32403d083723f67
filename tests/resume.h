// Resuming a run folder from its checkpoint as `demlab resume` does, for the tests that
// compare a resumed run with one never stopped.
#pragma once
#include <filesystem>

#include "run/checkpoint_file.h"
#include "run/run.h"
#include "scenario/scenario.h"

namespace demlab::test {

// The folder's own resolved scenario, on `threads` threads (the thread count is not part of
// the result: a resume on another count must give the same bytes).
inline RunSummary resume_run(const std::filesystem::path& dir, int threads) {
    Scenario s = load_run_folder_scenario(dir.string());
    s.world.threads = threads;
    RunOptions options{dir.string(), false, {}};
    options.resume = true;
    return run_scenario(s, options);
}

}  // namespace demlab::test
