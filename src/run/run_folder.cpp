#include "run/run_folder.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <string_view>

#include "core/error.h"
#include "core/fileio.h"
#include "core/output_dir.h"
#include "run/checkpoint_file.h"

namespace demlab {

// Whether `path` names the file open on `fd` (the same device and inode).
static bool names_open_file(int fd, const std::string& path) {
    struct stat held {}, named {};
    return ::fstat(fd, &held) == 0 && ::stat(path.c_str(), &named) == 0 && held.st_dev == named.st_dev &&
           held.st_ino == named.st_ino;
}

RunFolderLock::RunFolderLock(const std::string& dir) : path_(dir + "/" + kRunLockName) {
    // Another process may remove the file between our open and our flock (it ends its run): the
    // lock we got is then on a file no other process can find, so take the new one.
    for (int attempt = 0; attempt < 8; ++attempt) {
        fd_ = ::open(path_.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
        if (fd_ < 0) throw InputError(path_ + ": cannot create the run folder's lock");
        if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
            ::close(fd_);
            fd_ = -1;
            throw InputError(dir + ": another demlab process is running in this folder (it holds " + path_ +
                             "); wait for it to finish, or choose another --out");
        }
        if (names_open_file(fd_, path_)) return;
        ::close(fd_);
        fd_ = -1;
    }
    throw InputError(path_ + ": the run folder's lock keeps being replaced by another process");
}

void RunFolderLock::release_and_remove() noexcept {
    if (fd_ < 0) return;
    char link[64], where[4096];
    std::snprintf(link, sizeof(link), "/proc/self/fd/%d", fd_);
    const ssize_t len = ::readlink(link, where, sizeof(where) - 1);
    if (len > 0) {
        where[len] = 0;
        if (std::string_view(where, size_t(len)).find(" (deleted)") == std::string_view::npos) ::unlink(where);
    } else if (names_open_file(fd_, path_)) {  // no /proc: the path, if it still names the file
        ::unlink(path_.c_str());
    }
    ::close(fd_);
    fd_ = -1;
}

std::vector<std::string> run_inputs(const Scenario& s, const RunOptions& o, const std::vector<ScenarioInput>& inputs) {
    std::vector<std::string> files;
    if (!o.rerun && !s.source.empty()) files.push_back(s.source);
    for (const ScenarioInput& in : inputs) files.push_back(in.path);
    return files;
}

// The run folder: a new one (refused if it exists, unless forced) with the resolved scenario,
// or the checkpoint of the one to resume, checked against it; locked either way.
std::unique_ptr<BinaryReader> open_run_folder(const RunOptions& o, const std::string& scenario_text,
                                              const std::vector<ScenarioInput>& inputs, std::unique_ptr<RunFolderLock>& lock,
                                              const std::vector<std::string>& held) {
    const std::string& dir = o.out_dir;
    const std::string checkpoint_path = dir + "/" + kCheckpointFile;
    if (!o.resume) {
        // refused (a user's folder, an input inside it) before anything is written into it
        check_output_dir(dir, o.force, held);
        // a folder that exists is locked before it is touched (a forced run over a running one)
        if (o.force && std::filesystem::is_directory(dir)) lock = std::make_unique<RunFolderLock>(dir);
        prepare_output_dir(o.out_dir, o.force, held);  // (forced: the old folder, with its lock, moved aside)
        lock = std::make_unique<RunFolderLock>(dir);
        std::filesystem::remove(checkpoint_path);  // a stale one of a replaced run
        write_file_atomic(dir + "/scenario.toml", scenario_text);
        return nullptr;
    }
    if (!std::filesystem::is_directory(dir)) throw InputError(dir + ": no such run folder to resume");
    lock = std::make_unique<RunFolderLock>(dir);
    auto restore = std::make_unique<BinaryReader>(read_checkpoint_file(checkpoint_path), checkpoint_path);
    const CheckpointHeader header = get_checkpoint_header(*restore, checkpoint_path);
    if (!same_scenario(header.scenario_text, scenario_text))
        throw InputError(dir + "/scenario.toml differs from the scenario the checkpoint was written with "
                         "(was it edited?); a resumed run must continue the same scenario");
    // a terrain profile (or any file the scenario reads) edited since: refused, naming it
    if (header.has_inputs) check_same_inputs(header.inputs, inputs, dir);
    restore->expect_tag("RUN ");
    // a write the kill interrupted left its temporary file (the target is intact): only the
    // names demlab's writers give them (NAME.EXT.tmp, core/fileio.cpp, output/image.cpp) in the
    // folders a run writes, never a user's own .tmp file in a folder of theirs
    namespace fs = std::filesystem;
    for (const char* sub : {"", "snapshots", "frames", "plots"}) {
        const fs::path folder = fs::path(dir) / sub;
        std::error_code ec;
        if (!fs::is_directory(folder, ec) || fs::is_symlink(fs::symlink_status(folder, ec))) continue;
        for (const auto& e : fs::directory_iterator(folder, ec)) {
            const fs::path name = e.path().filename();
            if (!e.is_regular_file() || name.extension() != ".tmp") continue;
            const std::string inner = name.stem().extension().string();
            bool writers = name.stem() == kOutputMarker;  // the marker's own
            for (const char* ext : {".csv", ".part", ".json", ".toml", ".vtp", ".pvd", ".png", ".bin", ".asc", ".dat", ".gp"})
                writers = writers || inner == ext;
            if (writers) fs::remove(e.path(), ec);
        }
    }
    return restore;
}

}  // namespace demlab
