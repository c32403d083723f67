// File helpers shared by the tests that run scenarios and compare their outputs.
#pragma once
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "core/csv.h"

namespace demlab::test {

// One column of a run's CSV series, by its name (the files name each column's unit).
inline std::vector<double> csv_column(const std::filesystem::path& p, const std::string& name) {
    const CsvTable t = read_csv_table(p.string());
    std::string header;
    for (const std::string& n : t.names) header += (header.empty() ? "" : ",") + n;
    const size_t c = CsvHeader(header, p.string()).column(name);
    std::vector<double> out;
    for (const std::vector<double>& r : t.rows) out.push_back(r.at(c));
    return out;
}

// The whole file, byte for byte ("" if it cannot be read).
inline std::string read_file(const std::filesystem::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::stringstream b;
    b << in.rdbuf();
    return b.str();
}

// The first line of a file ("" if it cannot be read).
inline std::string read_file_header(const std::filesystem::path& p) {
    std::ifstream in(p);
    std::string line;
    std::getline(in, line);
    return line;
}

// A fresh, absent folder in the temporary directory, unique to this process.
inline std::filesystem::path temp_dir(const std::string& name) {
    const auto p = std::filesystem::temp_directory_path() / ("demlab-test-" + name + "-" + std::to_string(::getpid()));
    std::filesystem::remove_all(p);
    return p;
}

// A file written in the temporary directory under a name unique to this process
// ("demlab-test-PID-NAME": the name's extension stays last), removed when the object goes out
// of scope: a test leaves nothing behind however it ends (a failed assertion returns early).
// Not copyable: one owner.
class TempFile {
public:
    TempFile(const std::string& name, const std::string& text)
        : path_((std::filesystem::temp_directory_path() / ("demlab-test-" + std::to_string(::getpid()) + "-" + name)).string()) {
        std::ofstream(path_, std::ios::binary) << text;
    }
    ~TempFile() {
        std::error_code ec;
        std::filesystem::remove(path_, ec);
    }
    TempFile(const TempFile&) = delete;
    TempFile& operator=(const TempFile&) = delete;
    const std::string& path() const { return path_; }

private:
    std::string path_;
};

// What this process left in the temporary directory: the entries named "demlab-...-PID..."
// (the names temp_dir, TempFile and the tests' own give).
inline std::vector<std::string> temp_leftovers() {
    std::vector<std::string> out;
    const std::string pid = std::to_string(::getpid());
    std::error_code ec;
    for (const auto& e : std::filesystem::directory_iterator(std::filesystem::temp_directory_path(), ec)) {
        const std::string name = e.path().filename().string();
        if (name.rfind("demlab-", 0) != 0) continue;
        for (size_t at = name.find("-" + pid); at != std::string::npos; at = name.find("-" + pid, at + 1)) {
            const size_t end = at + 1 + pid.size();
            if (end == name.size() || name[end] == '-' || name[end] == '.') {
                out.push_back(name);
                break;
            }
        }
    }
    return out;
}

}  // namespace demlab::test
