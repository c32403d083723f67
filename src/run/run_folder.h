// The run folder of `demlab run` (DEM or DAN): created new (refused when it exists, unless
// forced) with the resolved scenario, or opened to resume from its checkpoint, and locked
// while the run lives (flock on RUN_DIR/.demlab.lock), so a second process resuming or
// forcing the same folder is refused instead of writing over the first.
#pragma once
#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <memory>
#include <string>
#include <string_view>
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
    explicit RunFolderLock(const std::string& dir) : path_(dir + "/" + kRunLockName) {
        // Another process may remove the file between our open and our flock (it ends its run):
        // the lock we got is then on a file no other process can find, so take the new one.
        for (int attempt = 0; attempt < 8; ++attempt) {
            fd_ = ::open(path_.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
            if (fd_ < 0) throw InputError(path_ + ": cannot create the run folder's lock");
            if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
                ::close(fd_);
                fd_ = -1;
                throw InputError(dir + ": another demlab process is running in this folder (it holds " + path_ +
                                 "); wait for it to finish, or choose another --out");
            }
            struct stat held {}, named {};
            if (::fstat(fd_, &held) == 0 && ::stat(path_.c_str(), &named) == 0 && held.st_dev == named.st_dev &&
                held.st_ino == named.st_ino)
                return;
            ::close(fd_);
            fd_ = -1;
        }
        throw InputError(path_ + ": the run folder's lock keeps being replaced by another process");
    }
    ~RunFolderLock() { release_and_remove(); }
    RunFolderLock(const RunFolderLock&) = delete;
    RunFolderLock& operator=(const RunFolderLock&) = delete;
    // Removed while still held, so that no other process can lock the file that is going away.
    // A forced run's old folder is moved aside with its lock inside: the file is removed where
    // it now is (the kernel's name for the descriptor), never a new folder's lock at the old path.
    void release_and_remove() noexcept {
        if (fd_ < 0) return;
        char where[4096];
        const std::string link = "/proc/self/fd/" + std::to_string(fd_);
        const ssize_t len = ::readlink(link.c_str(), where, sizeof(where) - 1);
        if (len > 0) {
            where[len] = 0;
            if (std::string_view(where, size_t(len)).find(" (deleted)") == std::string_view::npos) ::unlink(where);
        }
        ::close(fd_);
        fd_ = -1;
    }

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
