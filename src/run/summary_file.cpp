#include "run/summary_file.h"

#include <cmath>
#include <fstream>

namespace demlab {

double SummaryFile::number(const std::string& key) const {
    const auto it = numbers.find(key);
    return it == numbers.end() ? NAN : it->second;
}

std::string SummaryFile::text(const std::string& key) const {
    const auto it = strings.find(key);
    return it == strings.end() ? std::string() : it->second;
}

SummaryFile read_summary_file(const std::string& path) {
    std::ifstream in(path);
    SummaryFile out;
    std::string line;
    while (std::getline(in, line)) {
        const size_t q1 = line.find('"'), q2 = line.find('"', q1 + 1), colon = line.find(':', q2);
        if (q1 == std::string::npos || q2 == std::string::npos || colon == std::string::npos) continue;
        const std::string key = line.substr(q1 + 1, q2 - q1 - 1);
        std::string value = line.substr(colon + 1);
        const size_t v1 = value.find('"');
        if (v1 != std::string::npos) {
            const size_t v2 = value.rfind('"');
            out.strings[key] = v2 > v1 ? value.substr(v1 + 1, v2 - v1 - 1) : std::string();
            continue;
        }
        try {
            out.numbers[key] = value.find("null") != std::string::npos ? NAN : std::stod(value);
        } catch (...) {
            if (value.find("true") != std::string::npos) out.numbers[key] = 1.0;
            else if (value.find("false") != std::string::npos) out.numbers[key] = 0.0;
        }
    }
    return out;
}

}  // namespace demlab
