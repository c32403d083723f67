// Output folders: one policy for every command that writes one (run, render, compare, plot,
// demo, sweep, calibrate).
//
// - A new folder is made with a marker file (kOutputMarker) that says demlab made it.
// - An existing folder is refused unless the user said --force, and even then it is replaced
//   only when it carries the marker, is not (and does not hold) one of the command's inputs,
//   and does not hold the working directory: --force never deletes a user's own files. A
//   completed output lists its files in the marker, and a --force is refused while the folder
//   holds anything else (a user's notes or analysis put beside the results).
// - A forced folder is moved aside (FOLDER.replaced) and a new one made, so nothing of the old
//   output stays beside the new files; the old one is removed only when the new output is
//   complete (remove_replaced_output), so a failed command loses nothing.
// check_output_dir does every check without touching the disk, so a command can refuse before
// it writes (or locks) anything.
#pragma once
#include <string>
#include <vector>

namespace demlab {

// The file demlab writes into every output folder it makes.
inline constexpr const char* kOutputMarker = ".demlab-output";
// The file a run folder's lock is held on (run/run_folder.h), kept after the run.
inline constexpr const char* kRunLockName = ".demlab.lock";

// The name alone: not empty, and no `..` after a folder that does not exist (the system would
// find no folder there, and making the folders would then write into an existing one).
void check_output_path(const std::string& dir);
// Throws InputError unless `dir` may become a new output folder: a non-empty name that does
// not exist, or (force) an output folder demlab made that neither is, nor holds, any of
// `inputs` (files or folders the command reads) nor the working directory.
void check_output_dir(const std::string& dir, bool force, const std::vector<std::string>& inputs = {});

// check_output_dir, then makes dir (and parents) with its marker; a forced old folder is
// moved aside first.
void prepare_output_dir(const std::string& dir, bool force, const std::vector<std::string>& inputs = {});

// Throws InputError unless dir may be written again by a later command (demlab plot's plots/,
// demlab render's frames/): it does not exist, or it is a folder demlab made that holds only
// the files demlab recorded there.
void check_regenerated_output_dir(const std::string& dir);

// Makes the folder `path` and its parents (a sweep's OUT/runs); InputError naming `dir` (the
// output folder) when they cannot be made: a symbolic link to nowhere, a file on the way.
void create_output_tree(const std::string& dir, const std::string& path);

// Writes the marker into a folder demlab made by other means (a run's frames/, plots/).
void mark_output_dir(const std::string& dir);

// Whether dir carries the marker.
bool is_demlab_output(const std::string& dir);

// The folder a forced prepare_output_dir moved the old one to.
std::string replaced_output_dir(const std::string& dir);

// The output in dir is complete: its files are listed in its marker, and in those of the
// marked folders inside it (a later --force deletes nothing else).
void record_output_files(const std::string& dir);

// record_output_files, and the old folder a forced prepare_output_dir moved aside is removed.
void remove_replaced_output(const std::string& dir);

// A command that failed after prepare_output_dir: its new folder is removed and the old one
// (forced) put back, as if the command had not run.
void abandon_output(const std::string& dir);

// Whether `path` is `base` or lies inside it (both resolved: symbolic links, `..`, relative).
bool path_within(const std::string& path, const std::string& base);

}  // namespace demlab
