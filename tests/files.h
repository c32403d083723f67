// File helpers shared by the tests that run scenarios and compare their outputs.
#pragma once
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace demlab::test {

// The whole file, byte for byte ("" if it cannot be read).
inline std::string read_file(const std::filesystem::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::stringstream b;
    b << in.rdbuf();
    return b.str();
}

// A fresh, absent folder in the temporary directory, unique to this process.
inline std::filesystem::path temp_dir(const std::string& name) {
    const auto p = std::filesystem::temp_directory_path() / ("demlab-test-" + name + "-" + std::to_string(::getpid()));
    std::filesystem::remove_all(p);
    return p;
}

}  // namespace demlab::test
