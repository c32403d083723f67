#include "core/fileio.h"

#include <cmath>
#include <sstream>

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "core/error.h"

namespace demlab {

namespace {

// Why the last write failed, for a message ("No space left on device", "File too large").
std::string last_error() { return std::strerror(errno); }

}  // namespace

void write_file_atomic(const std::string& path, const std::string& content) {
    // every byte checked: the write, the close (a network or full file system reports there),
    // then the rename; a temporary file that failed is removed, never given the final name
    const std::string tmp = path + ".tmp";
    const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd < 0) throw WriteError("cannot write " + path + " (" + last_error() + ")");
    const char* p = content.data();
    size_t left = content.size();
    std::string failed;
    while (left > 0) {
        const ssize_t put = ::write(fd, p, left);
        if (put < 0 && errno == EINTR) continue;
        if (put <= 0) {
            failed = put < 0 ? last_error() : "nothing written";
            break;
        }
        p += put;
        left -= size_t(put);
    }
    if (::close(fd) != 0 && failed.empty()) failed = last_error();
    if (!failed.empty()) {
        ::unlink(tmp.c_str());
        throw WriteError("cannot write " + path + " (" + failed + ")");
    }
    std::error_code ec;
    std::filesystem::rename(tmp, path, ec);
    if (ec) {
        ::unlink(tmp.c_str());
        throw WriteError("cannot rename " + tmp + " to " + path + ": " + ec.message());
    }
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
    if (!out_) throw WriteError("cannot write " + path + ".part (" + last_error() + ")");
    out_.precision(10);
}

void SeriesFile::reopen(const std::string& path, uint64_t size) {
    namespace fs = std::filesystem;
    path_ = path;
    const std::string part = path + ".part";
    std::error_code ec;
    // a link put in its place would have the run write into the file it points at
    if (fs::is_symlink(fs::symlink_status(part, ec)))
        throw InputError("cannot resume: " + part + " is a symbolic link, not the file the run wrote; demlab writes only its own files");
    const auto have = fs::file_size(part, ec);
    if (ec || have < size)
        throw InputError("cannot resume: " + part + " is missing or shorter than at the checkpoint (" +
                       std::to_string(size) + " bytes)");
    fs::resize_file(part, size, ec);
    if (ec) throw RunError("cannot resume: cannot cut " + part + " back: " + ec.message());
    // not ios::app: its position reads 0 until the first write, and flush() reports it
    out_.open(part, std::ios::in | std::ios::out);
    out_.seekp(0, std::ios::end);
    if (!out_) throw WriteError("cannot write " + part + " (" + last_error() + ")");
    out_.precision(10);
}

uint64_t SeriesFile::flush() {
    if (!out_.is_open()) return 0;
    out_.flush();
    check();
    return uint64_t(out_.tellp());
}

void SeriesFile::check() {
    // the stream fails when a buffer it hands on is refused (a full disk, a size limit)
    if (out_.is_open() && !out_)
        throw WriteError("cannot write " + path_ + " (" + (errno ? last_error() : std::string("the write failed")) +
                         "): the run stops; the file stays " + path_ + ".part");
}

void SeriesFile::close() {
    if (!out_.is_open()) return;
    out_.flush();
    check();
    out_.close();
    if (out_.fail()) throw WriteError("cannot write " + path_ + " (" + last_error() + "): the file stays " + path_ + ".part");
    std::error_code ec;
    std::filesystem::rename(path_ + ".part", path_, ec);
    if (ec) throw WriteError("cannot rename " + path_ + ".part: " + ec.message());
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
