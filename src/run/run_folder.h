// The run folder of `demlab run` (DEM or DAN): created new (refused when it exists, unless
// forced) with the resolved scenario, or opened to resume from its checkpoint, and locked
// while the run lives (flock on RUN_DIR/.demlab.lock), so a second process resuming or
// forcing the same folder is refused instead of writing over the first.
#pragma once

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "core/binary_io.h"
#include "core/error.h"
#include "core/output_dir.h"
#include "run/run.h"
#include "scenario/fingerprint.h"

namespace demlab {

// The kernel drops the lock when the process ends, however it ends. The file goes with the
// lock whenever the process leaves the run's scope (finished, refused, failed, interrupted), so
// only a killed process leaves it behind, and a left file is harmless: nothing holds its lock.
class RunFolderLock {
public:
    // Refused (InputError) when another process holds the folder's lock.
    explicit RunFolderLock(const std::string& dir);
    ~RunFolderLock() { release_and_remove(); }
    RunFolderLock(const RunFolderLock&) = delete;
    RunFolderLock& operator=(const RunFolderLock&) = delete;
    // Removed while still held, so that no other process can lock the file that is going away.
    // A forced run's old folder is moved aside with its lock inside: the file is removed where
    // it now is (the kernel's name for the descriptor), never a new folder's lock at the old path.
    void release_and_remove() noexcept;

private:
    std::string path_;
    int fd_ = -1;
};

// The files a run reads, which its folder must not hold: the scenario file (unless the run is
// done again in place from the folder's own scenario.toml: RunOptions::rerun) and `inputs`.
std::vector<std::string> run_inputs(const Scenario& s, const RunOptions& o, const std::vector<ScenarioInput>& inputs);

// The run folder: a new one (refused if it exists, unless forced) with the resolved scenario,
// or the checkpoint of the one to resume, checked against it (the scenario, and the content
// of every file it reads: `inputs`); locked either way. `held`: the
// files a forced folder must not hold (output_dir.h).
std::unique_ptr<BinaryReader> open_run_folder(const RunOptions& o, const std::string& scenario_text,
                                              const std::vector<ScenarioInput>& inputs, std::unique_ptr<RunFolderLock>& lock,
                                              const std::vector<std::string>& held);

}  // namespace demlab
