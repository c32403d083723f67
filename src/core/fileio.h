// Files written whole and atomically: to a temporary name beside the target, then renamed,
// so a run killed mid-write leaves either the old file or the complete new one.
#pragma once
#include <cstdint>
#include <fstream>
#include <string>

namespace demlab {

// Every byte is checked: a failed write (a full disk, a size limit) throws WriteError naming
// the file, and the temporary file is removed.
void write_file_atomic(const std::string& path, const std::string& content);

// An input file read whole: refused (InputError, exit 2, naming the file and `what` it is)
// when it is missing, not a regular file (a directory, /dev/zero, a pipe) or larger than
// max_bytes, before a byte of it is read. A UTF-8 byte-order mark at its start (what
// spreadsheet programs write for "CSV UTF-8") is dropped: the text is the same file without it.
// Every input file (scenario, profile, grid, release mass, top, table, checkpoint) is read here.
std::string read_input_file(const std::string& path, uint64_t max_bytes, const std::string& what);
// Drops a UTF-8 byte-order mark (EF BB BF) from the start of `text`, if it has one.
void strip_utf8_bom(std::string& text);
// The limits, in bytes
inline constexpr uint64_t kMaxScenarioBytes = uint64_t(16) << 20;     // scenario, calibration: 16 MiB
inline constexpr uint64_t kMaxTableBytes = uint64_t(1) << 30;         // release mass, terrain profile: 1 GiB
inline constexpr uint64_t kMaxCheckpointBytes = uint64_t(64) << 30;   // checkpoint: 64 GiB

// `text` as a JSON string literal, in quotes: quotes, backslashes and control characters
// escaped (summary.json's free text, such as the machine's name).
std::string json_string(const std::string& text);
// A number for summary.json with 10 significant digits; null when not finite.
std::string json_number(double v);

// A file written over time (a CSV series): it is written as PATH.part and renamed to PATH
// by close(), so an unfinished series is never mistaken for a complete one. A write that
// failed throws WriteError at the next check(), flush() or close(), and the file keeps its
// .part name.
class SeriesFile {
public:
    SeriesFile() = default;
    void open(const std::string& path);
    // Continues PATH.part from a checkpoint: cuts it back to `size` bytes (what it held when the
    // checkpoint was written) and appends from there.
    void reopen(const std::string& path, uint64_t size);
    // Flushes and returns the bytes written so far (for a checkpoint).
    uint64_t flush();
    std::ofstream& out() { return out_; }
    // Throws WriteError if a write since the last check failed (cheap: the stream's state).
    void check();
    void close();
    bool is_open() const { return out_.is_open(); }

private:
    std::string path_;
    std::ofstream out_;
};

}  // namespace demlab
