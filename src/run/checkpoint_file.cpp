#include "run/checkpoint_file.h"

#include <cstring>
#include <fstream>
#include <sstream>

#include "core/crc32c.h"
#include "core/error.h"
#include "core/fileio.h"
#include "scenario/scenario.h"

namespace demlab {

namespace {
constexpr char kMagic[8] = {'D', 'E', 'M', 'L', 'A', 'B', 'C', 'K'};
// 2: the file ends with the CRC-32C of all that comes before it; 1 (earlier builds): no checksum
// 3: the barrier outputs' peaks after the solver's state (BarrierOutputs::save)
constexpr uint32_t kCheckpointVersion = 3;
constexpr uint32_t kByteOrder = 0x01020304;

// The scenario's settings: its text without the comment lines (the header names the file the
// scenario was read from, which is the run folder's copy when resuming).
std::string without_comments(const std::string& text) {
    std::istringstream in(text);
    std::string line, out;
    while (std::getline(in, line))
        if (line.empty() || line[0] != '#') out += line + '\n';
    return out;
}
}  // namespace

void put_checkpoint_header(BinaryWriter& out, const std::string& scenario_text, double t, double t_max, long steps,
                           const RunOptions& o) {
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
}

CheckpointHeader get_checkpoint_header(BinaryReader& in, const std::string& path) {
    char magic[8];
    in.get(magic);
    if (std::memcmp(magic, kMagic, 8) != 0) throw InputError(path + ": not a demlab checkpoint");
    const uint32_t version = in.get<uint32_t>();
    if (version != kCheckpointVersion && version != 1 && version != 2) throw InputError(path + ": written by another version of demlab");
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
    if (without_comments(stored) == without_comments(resolved_now)) return true;
    try {
        Scenario then = parse_scenario(stored, "the checkpoint's scenario");
        finish_scenario(then);
        return without_comments(resolved_toml(then)) == without_comments(resolved_now);
    } catch (const InputError&) {
        return false;  // a key this build no longer reads: not the same scenario
    }
}

CheckpointInfo read_checkpoint_info(const std::string& run_dir) {
    const std::string path = run_dir + "/" + kCheckpointFile;
    BinaryReader in(read_checkpoint_file(path), path);
    return get_checkpoint_header(in, path).info;
}

}  // namespace demlab
