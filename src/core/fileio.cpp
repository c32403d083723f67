#include "core/fileio.h"

#include <cmath>
#include <sstream>

#include <cstdio>
#include <filesystem>

#include "core/error.h"

namespace demlab {

void write_file_atomic(const std::string& path, const std::string& content) {
    const std::string tmp = path + ".tmp";
    {
        std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
        if (!out) throw RunError("cannot write " + tmp);
        out << content;
        out.flush();
        if (!out) throw RunError("cannot write " + tmp + " (disk full?)");
    }
    std::error_code ec;
    std::filesystem::rename(tmp, path, ec);
    if (ec) throw RunError("cannot rename " + tmp + " to " + path + ": " + ec.message());
}

std::string read_input_file(const std::string& path, uint64_t max_bytes, const std::string& what) {
    namespace fs = std::filesystem;
    std::error_code ec;
    const fs::file_status st = fs::status(path, ec);
    if (ec || !fs::exists(st)) throw InputError(path + ": cannot open the " + what + " (no such file)");
    if (!fs::is_regular_file(st)) throw InputError(path + ": the " + what + " is not a regular file");
    const uint64_t size = fs::file_size(path, ec);
    if (ec) throw InputError(path + ": cannot read the " + what + " (" + ec.message() + ")");
    if (size > max_bytes)
        throw InputError(path + ": the " + what + " has " + std::to_string(size) + " bytes, more than the " +
                         std::to_string(max_bytes >> 20) + " MiB such a file may have");
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError(path + ": cannot open the " + what);
    std::string text(size_t(size), '\0');
    in.read(text.data(), std::streamsize(size));
    if (uint64_t(in.gcount()) != size) throw InputError(path + ": cannot read the " + what + " whole");
    strip_utf8_bom(text);
    return text;
}

void strip_utf8_bom(std::string& text) {
    if (text.size() >= 3 && text.compare(0, 3, "\xEF\xBB\xBF") == 0) text.erase(0, 3);
}

void SeriesFile::open(const std::string& path) {
    path_ = path;
    out_.open(path + ".part", std::ios::trunc);
    if (!out_) throw RunError("cannot write " + path + ".part");
    out_.precision(10);
}

void SeriesFile::reopen(const std::string& path, uint64_t size) {
    namespace fs = std::filesystem;
    path_ = path;
    const std::string part = path + ".part";
    std::error_code ec;
    const auto have = fs::file_size(part, ec);
    if (ec || have < size)
        throw InputError("cannot resume: " + part + " is missing or shorter than at the checkpoint (" +
                       std::to_string(size) + " bytes)");
    fs::resize_file(part, size, ec);
    if (ec) throw RunError("cannot resume: cannot cut " + part + " back: " + ec.message());
    // not ios::app: its position reads 0 until the first write, and flush() reports it
    out_.open(part, std::ios::in | std::ios::out);
    out_.seekp(0, std::ios::end);
    if (!out_) throw RunError("cannot write " + part);
    out_.precision(10);
}

uint64_t SeriesFile::flush() {
    if (!out_.is_open()) return 0;
    out_.flush();
    if (!out_) throw RunError("cannot write " + path_ + ".part (disk full?)");
    return uint64_t(out_.tellp());
}

void SeriesFile::close() {
    if (!out_.is_open()) return;
    out_.close();
    std::error_code ec;
    std::filesystem::rename(path_ + ".part", path_, ec);
    if (ec) throw RunError("cannot rename " + path_ + ".part: " + ec.message());
}

std::string json_number(double v) {
    if (!std::isfinite(v)) return "null";
    std::ostringstream o;
    o.precision(10);
    o << v;
    return o.str();
}

std::string json_string(const std::string& text) {
    std::string o = "\"";
    for (const char ch : text) {
        const unsigned char u = static_cast<unsigned char>(ch);
        if (ch == '"' || ch == '\\') {
            o += '\\';
            o += ch;
        } else if (u < 0x20) {
            char b[8];
            std::snprintf(b, sizeof b, "\\u%04x", unsigned(u));
            o += b;
        } else {
            o += ch;
        }
    }
    return o + "\"";
}

}  // namespace demlab
