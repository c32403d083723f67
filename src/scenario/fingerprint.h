// A content hash of a resolved scenario and of every file it reads. Reuse (a sweep's, the
// calibration's) and resume decide with it: a finished run is taken again only when its
// fingerprint is this one, and a checkpoint holds each input file's hash so that `resume`
// refuses a file edited since.
#pragma once
#include <string>
#include <vector>

#include "scenario/scenario.h"

namespace demlab {

// The keys whose value names a file the run reads (a relative path is resolved by
// finish_scenario, except release.from_file: the working folder's).
const std::vector<std::string>& scenario_file_keys();

struct ScenarioInput {
    std::string key;   // "terrain.profile"
    std::string path;  // as the resolved scenario names it
    std::string hash;  // content_hash of its bytes
};

// The files a finished scenario names, in the order of scenario_file_keys, each read and
// hashed (InputError naming the key and the file when one cannot be read).
std::vector<ScenarioInput> scenario_inputs(const Scenario& s);

// A resolved scenario's settings: its text without the comment lines (which name the file it
// was read from: a resumed run's is the run folder's copy).
std::string scenario_settings(const std::string& text);

// 32 hex digits: 128-bit FNV-1a of the bytes (stable across builds and machines).
std::string content_hash(const std::string& bytes);

// The hash of the resolved scenario's settings (resolved_toml without its comment lines, so
// not the file it was read from) and of each input, tagged with its key and path.
std::string scenario_fingerprint(const Scenario& s, const std::vector<ScenarioInput>& inputs);
std::string scenario_fingerprint(const Scenario& s);

}  // namespace demlab
