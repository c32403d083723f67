#include "fileio.h"

#include <cstdio>
#include <filesystem>

#include "error.h"

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

void SeriesFile::open(const std::string& path) {
    path_ = path;
    out_.open(path + ".part", std::ios::trunc);
    if (!out_) throw RunError("cannot write " + path + ".part");
    out_.precision(10);
}

void SeriesFile::close() {
    if (!out_.is_open()) return;
    out_.close();
    std::error_code ec;
    std::filesystem::rename(path_ + ".part", path_, ec);
    if (ec) throw RunError("cannot rename " + path_ + ".part: " + ec.message());
}

}  // namespace demlab
