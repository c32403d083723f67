#include "run/checkpoint_file.h"

#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/crc32c.h"
#include "core/error.h"
#include "core/fileio.h"
#include "scenario/fingerprint.h"
#include "scenario/scenario.h"

namespace demlab {

namespace {
constexpr char kMagic[8] = {'D', 'E', 'M', 'L', 'A', 'B', 'C', 'K'};
// 2: the file ends with the CRC-32C of all that comes before it; 1 (earlier builds): no checksum
// 3: the barrier outputs' peaks after the solver's state (BarrierOutputs::save)
// 4: the header ends with the scenario's input files and their content hashes
constexpr uint32_t kCheckpointVersion = 4;
constexpr uint32_t kByteOrder = 0x01020304;

}  // namespace

void put_checkpoint_header(BinaryWriter& out, const std::string& scenario_text, const std::vector<ScenarioInput>& inputs,
                           double t, double t_max, long steps, const RunOptions& o) {
    out.put(kMagic);
    out.put(kCheckpointVersion);
    out.put(kByteOrder);
    out.put(uint32_t(sizeof(double)));
    out.put(scenario_text);
    out.put(t);
    out.put(t_max);
    out.put(int64_t(steps));
    out.put(o.checkpoint_every);
    out.put(uint8_t(o.frames));
    out.put(uint8_t(o.plots));
    out.put(uint32_t(inputs.size()));
    for (const ScenarioInput& in : inputs) {
        out.put(in.key);
        out.put(in.path);
        out.put(in.hash);
    }
}

void check_same_inputs(const std::vector<ScenarioInput>& stored, const std::vector<ScenarioInput>& now, const std::string& dir) {
    for (const ScenarioInput& then : stored) {
        const ScenarioInput* cur = nullptr;
        for (const ScenarioInput& n : now)
            if (n.key == then.key) cur = &n;
        if (!cur || cur->path != as_read_then(then.path))
            throw InputError(dir + ": the checkpoint's run read " + then.key + " = \"" + then.path +
                             "\", which the scenario no longer names; a resumed run must read the same files");
        if (cur->hash != then.hash)
            throw InputError(then.path + " (" + then.key + ") has changed since the checkpoint of " + dir +
                             " was written: a resumed run must read the same files. Restore it, or run the scenario again");
    }
    for (const ScenarioInput& n : now) {
        bool known = false;
        for (const ScenarioInput& then : stored) known = known || then.key == n.key;
        if (!known)
            throw InputError(dir + ": the scenario names " + n.key + " = \"" + n.path +
                             "\", which the checkpoint's run did not read; a resumed run must read the same files");
    }
}

CheckpointHeader get_checkpoint_header(BinaryReader& in, const std::string& path) {
    char magic[8];
    in.get(magic);
    if (std::memcmp(magic, kMagic, 8) != 0) throw InputError(path + ": not a demlab checkpoint");
    const uint32_t version = in.get<uint32_t>();
    if (version < 1 || version > kCheckpointVersion) throw InputError(path + ": written by another version of demlab");
    if (in.get<uint32_t>() != kByteOrder || in.get<uint32_t>() != sizeof(double))
        throw InputError(path + ": written on a machine of another architecture (byte order or number size)");
    CheckpointHeader h;
    in.get(h.scenario_text);
    in.get(h.info.time);
    in.get(h.info.t_max);
    h.info.steps = long(in.get<int64_t>());
    in.get(h.info.checkpoint_every);
    h.info.frames = in.get<uint8_t>() != 0;
    h.info.plots = in.get<uint8_t>() != 0;
    h.has_inputs = version >= 4;
    if (h.has_inputs) {
        const uint32_t n = in.get<uint32_t>();
        if (n > 64) throw InputError(path + ": corrupt checkpoint (" + std::to_string(n) + " input files)");
        for (uint32_t k = 0; k < n; ++k) {
            ScenarioInput i;
            in.get(i.key);
            in.get(i.path);
            in.get(i.hash);
            h.inputs.push_back(i);
        }
    }
    return h;
}

std::string seal_checkpoint(const std::string& bytes) {
    std::string out = bytes;
    const uint32_t crc = crc32c(bytes);
    for (int k = 0; k < 4; ++k) out.push_back(char((crc >> (8 * k)) & 0xFFu));
    return out;
}

std::string read_checkpoint_file(const std::string& path) {
    std::string bytes = read_whole(path);
    uint32_t version = 0;
    if (bytes.size() >= 12 && std::memcmp(bytes.data(), kMagic, 8) == 0) std::memcpy(&version, bytes.data() + 8, 4);
    // version 1 had no checksum; another value is not a checkpoint of this build: the header says
    if (version < 2 || version > kCheckpointVersion) return bytes;
    if (bytes.size() < 16) throw InputError(path + ": corrupt checkpoint (truncated)");
    uint32_t stored = 0;
    for (int k = 0; k < 4; ++k) stored |= uint32_t(uint8_t(bytes[bytes.size() - 4 + size_t(k)])) << (8 * k);
    bytes.resize(bytes.size() - 4);
    if (crc32c(bytes) != stored)
        throw InputError(path + ": corrupt checkpoint (its CRC-32C does not match its content): it cannot be resumed; "
                         "run the scenario again");
    return bytes;
}

std::string read_whole(const std::string& path) { return read_input_file(path, kMaxCheckpointBytes, "checkpoint or run file"); }

bool same_scenario(const std::string& stored, const std::string& resolved_now) {
    if (scenario_settings(stored) == scenario_settings(resolved_now)) return true;
    try {
        Scenario then = parse_scenario(stored, "the checkpoint's scenario");
        if (!then.release.from_file.empty()) then.release.from_file = as_read_then(then.release.from_file);
        finish_scenario(then);
        return scenario_settings(resolved_toml(then)) == scenario_settings(resolved_now);
    } catch (const InputError&) {
        return false;  // a key this build no longer reads: not the same scenario
    }
}

std::string as_read_then(const std::string& path) {
    const std::filesystem::path p(path);
    return p.is_relative() ? std::filesystem::absolute(p).lexically_normal().string() : path;
}

Scenario load_run_folder_scenario(const std::string& dir) {
    const std::string file = dir + "/scenario.toml";
    Scenario s = load_scenario(file);
    std::string& from = s.release.from_file;
    if (!from.empty() && std::filesystem::path(from).is_relative()) {
        const std::string then = as_read_then(from);
        if (!std::filesystem::exists(then))
            throw InputError(file + ": release.from_file = \"" + from + "\" is relative: the build that wrote this folder read it "
                             "from the working directory, where " + then + " does not exist; resume from the directory the run "
                             "was started in");
        from = then;
    }
    finish_scenario(s);
    return s;
}

bool checkpoint_continues(const std::string& dir, const Scenario& s) {
    const std::string path = dir + "/" + kCheckpointFile;
    if (!std::filesystem::is_regular_file(path)) return false;
    try {
        BinaryReader in(read_checkpoint_file(path), path);
        const CheckpointHeader header = get_checkpoint_header(in, path);
        if (!header.has_inputs || !same_scenario(header.scenario_text, resolved_toml(s))) return false;
        check_same_inputs(header.inputs, scenario_inputs(s), dir);
        return true;
    } catch (const InputError&) {
        return false;  // damaged, or an input file edited since: the job starts again
    }
    // (anything else, memory for a huge checkpoint say, goes on to the job's error: the folder,
    // checkpoint and all, stays for the next try rather than being emptied)
}

CheckpointInfo read_checkpoint_info(const std::string& run_dir) {
    const std::string path = run_dir + "/" + kCheckpointFile;
    BinaryReader in(read_checkpoint_file(path), path);
    return get_checkpoint_header(in, path).info;
}

}  // namespace demlab
