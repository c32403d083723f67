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

}  // namespace demlab::test
