// A run's checkpoint file (RUN_DIR/checkpoint.bin): its header, which `demlab resume` reads
// first (the resolved scenario and the options to resume with); the run's own state ("RUN ")
// and the solver's (World::save_state) follow it (run.cpp).
#pragma once
#include <string>

#include "core/binary_io.h"
#include "run/run.h"
#include "scenario/fingerprint.h"
#include "scenario/scenario.h"

namespace demlab {

struct CheckpointHeader {
    std::string scenario_text;
    CheckpointInfo info;
    // the files the scenario reads, with their content hashes (format 4; empty before)
    std::vector<ScenarioInput> inputs;
    bool has_inputs = false;  // format 4 or later (an earlier build's checkpoint is not checked)
};

void put_checkpoint_header(BinaryWriter& out, const std::string& scenario_text, const std::vector<ScenarioInput>& inputs,
                           double t, double t_max, long steps, const RunOptions& o);
// InputError naming the first input file whose content (or path) is not the one the
// checkpoint was written with.
void check_same_inputs(const std::vector<ScenarioInput>& stored, const std::vector<ScenarioInput>& now, const std::string& dir);
CheckpointHeader get_checkpoint_header(BinaryReader& in, const std::string& path);

// The file's bytes with the CRC-32C of all of them appended (written last), and a checkpoint
// file read back without it: InputError (exit 2) naming the file when the sum does not match.
// A checkpoint of an earlier build, without a sum, is read as it is.
std::string seal_checkpoint(const std::string& bytes);
std::string read_checkpoint_file(const std::string& path);

// A run folder's scenario (DIR/scenario.toml), parsed and finished as a resume reads it. A
// relative release.from_file there was written by a build that read it from the working
// directory (before the key was taken from the scenario's folder; or a scenario given as text):
// it is read from the working directory still, and its absence says to resume from the folder
// the run was started in.
Scenario load_run_folder_scenario(const std::string& dir);
// A path the checkpoint's scenario or inputs hold: a relative one (see above) made absolute
// against the working directory, as those builds read it; others as they are.
std::string as_read_then(const std::string& path);

// Whether DIR holds a checkpoint that resuming with scenario s continues: written with s's
// resolved scenario and with the same content of every file s reads. False for none, a
// damaged one, another scenario's or an earlier build's without the files' hashes (a sweep
// then runs its job again from the start rather than resume what it cannot check).
bool checkpoint_continues(const std::string& dir, const Scenario& s);

// A whole file's bytes (InputError naming it when it cannot be read).
std::string read_whole(const std::string& path);

}  // namespace demlab
