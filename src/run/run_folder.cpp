#include "run/run_folder.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <filesystem>

#include "core/error.h"
#include "core/fileio.h"
#include "core/output_dir.h"
#include "run/checkpoint_file.h"

namespace demlab {

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
    // a write the kill interrupted left its temporary file (the target is intact)
    for (const auto& e : std::filesystem::recursive_directory_iterator(dir))
        if (e.is_regular_file() && e.path().extension() == ".tmp") std::filesystem::remove(e.path());
    return restore;
}

}  // namespace demlab
