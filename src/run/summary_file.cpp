#include "run/summary_file.h"

#include <cctype>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>

#include "core/csv.h"
#include "core/error.h"
#include "core/fileio.h"

namespace demlab {

void SummaryJson::number(const std::string& key, double v, const std::string& unit) {
    entries_.emplace_back(key, json_number(v));
    units_.emplace_back(key, unit);
}

void SummaryJson::integer(const std::string& key, long v, const std::string& unit) {
    entries_.emplace_back(key, std::to_string(v));
    units_.emplace_back(key, unit);
}

void SummaryJson::text(const std::string& key, const std::string& v) { entries_.emplace_back(key, json_string(v)); }

std::vector<std::string> SummaryJson::number_keys() const {
    std::vector<std::string> keys;
    for (const auto& [k, v] : entries_)
        if (v.empty() || v[0] != '"') keys.push_back(k);
    return keys;
}

void SummaryJson::boolean(const std::string& key, bool v) { entries_.emplace_back(key, v ? "true" : "false"); }

void SummaryJson::reasons(const std::string& key, const std::vector<std::pair<std::string, std::string>>& texts) {
    reasons_key_ = key;
    reasons_ = texts;
}

std::string SummaryJson::str() const {
    std::string o = "{\n";
    for (const auto& [key, value] : entries_) o += "  " + json_string(key) + ": " + value + ",\n";
    if (!reasons_key_.empty()) {
        o += "  " + json_string(reasons_key_) + ": {\n";
        for (size_t k = 0; k < reasons_.size(); ++k)
            o += "    " + json_string(reasons_[k].first) + ": " + json_string(reasons_[k].second) + (k + 1 < reasons_.size() ? ",\n" : "\n");
        o += "  },\n";
    }
    o += "  \"units\": {\n";
    for (size_t k = 0; k < units_.size(); ++k)
        o += "    " + json_string(units_[k].first) + ": " + json_string(units_[k].second) + (k + 1 < units_.size() ? ",\n" : "\n");
    o += "  }\n}\n";
    return o;
}

std::string SummaryFile::unit(const std::string& key) const {
    const auto it = units.find(key);
    return it == units.end() ? std::string() : it->second;
}

double SummaryFile::number(const std::string& key) const {
    const auto it = numbers.find(key);
    return it == numbers.end() ? NAN : it->second;
}

std::string SummaryFile::text(const std::string& key) const {
    const auto it = strings.find(key);
    return it == strings.end() ? std::string() : it->second;
}

// Whether a summary's text is whole: one object whose braces close (outside strings). A file cut
// short (a full disk, a killed writer) or emptied would otherwise read as a run that measured
// nothing.
static bool whole_object(const std::string& text) {
    int depth = 0;
    bool in_string = false, escaped = false, opened = false;
    for (const char c : text) {
        if (in_string) {
            if (escaped) escaped = false;
            else if (c == '\\') escaped = true;
            else if (c == '"') in_string = false;
        } else if (c == '"') {
            in_string = true;
        } else if (c == '{') {
            ++depth;
            opened = true;
        } else if (c == '}') {
            if (--depth < 0) return false;
        }
    }
    return opened && depth == 0 && !in_string;
}

SummaryFile read_summary_file(const std::string& path) {
    const std::string text = read_input_file(path, kMaxScenarioBytes, "run summary");
    if (!whole_object(text))
        throw InputError(path + ": not a whole summary (empty, or cut short: its braces do not close); "
                         "the run folder is damaged: run it again");
    std::istringstream in(text);
    SummaryFile out;
    std::string line;
    // the nested objects: "units" (key: unit) and "not_measured" (key: reason), one entry a line
    std::map<std::string, std::string>* block = nullptr;
    while (std::getline(in, line)) {
        const size_t text_start = line.find_first_not_of(" \t");
        if (block && text_start != std::string::npos && line[text_start] == '}') {
            block = nullptr;
            continue;
        }
        if (line.find("\"units\": {") != std::string::npos) {
            block = &out.units;
            continue;
        }
        if (line.find("\"not_measured\": {") != std::string::npos) {
            block = &out.not_measured;
            continue;
        }
        const size_t q1 = line.find('"'), q2 = line.find('"', q1 + 1), colon = line.find(':', q2);
        if (q1 == std::string::npos || q2 == std::string::npos || colon == std::string::npos) continue;
        const std::string key = line.substr(q1 + 1, q2 - q1 - 1);
        std::string value = line.substr(colon + 1);
        const size_t v1 = value.find('"');
        if (block) {
            const size_t v2 = value.rfind('"');
            if (v1 != std::string::npos && v2 > v1) (*block)[key] = value.substr(v1 + 1, v2 - v1 - 1);
            continue;
        }
        if (v1 != std::string::npos) {
            const size_t v2 = value.rfind('"');
            out.strings[key] = v2 > v1 ? value.substr(v1 + 1, v2 - v1 - 1) : std::string();
            continue;
        }
        // the value without its blanks and the comma after it: null, true, false or a number,
        // all of it ("1.5x" is no number)
        std::string bare = value;
        while (!bare.empty() && (bare.back() == ',' || std::isspace(static_cast<unsigned char>(bare.back())))) bare.pop_back();
        const size_t first = bare.find_first_not_of(" \t");
        bare = first == std::string::npos ? std::string() : bare.substr(first);
        double x = 0.0;
        if (bare == "null") out.numbers[key] = NAN;
        else if (bare == "true") out.numbers[key] = 1.0;
        else if (bare == "false") out.numbers[key] = 0.0;
        else if (parse_number(bare, x)) out.numbers[key] = x;
    }
    return out;
}

}  // namespace demlab
