// A run folder's summary.json: our own flat layout, one "key": value a line, then a "units"
// object that names the unit of every number ("-" for counts and ratios; the keys keep their
// names, so `runout_s` is a length in m: s is the path coordinate). Written by SummaryJson,
// read back (the numbers, null as NaN, the strings and the units) for the calibration's table
// and `demlab compare`.
#pragma once
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace demlab {

class SummaryJson {
public:
    void number(const std::string& key, double v, const std::string& unit);  // NaN and inf as null
    void integer(const std::string& key, long v, const std::string& unit = "-");
    void text(const std::string& key, const std::string& v);
    void boolean(const std::string& key, bool v);
    // an object of texts, {key: text, ...} (summary.json's "not_measured"), written after the
    // numbers; read back into SummaryFile::reasons
    void reasons(const std::string& key, const std::vector<std::pair<std::string, std::string>>& texts);
    std::string str() const;
    // the keys whose value is a number (true and false count: the reader takes them as 1, 0)
    std::vector<std::string> number_keys() const;

private:
    std::vector<std::pair<std::string, std::string>> entries_, units_;  // key, its JSON value / unit
    std::string reasons_key_;
    std::vector<std::pair<std::string, std::string>> reasons_;
};

struct SummaryFile {
    std::map<std::string, double> numbers;
    std::map<std::string, std::string> strings;
    std::map<std::string, std::string> units;
    std::map<std::string, std::string> not_measured;  // key: why it is null
    std::string unit(const std::string& key) const;  // "" when absent
    double number(const std::string& key) const;  // NaN when absent
    std::string text(const std::string& key) const;  // "" when absent
};

SummaryFile read_summary_file(const std::string& path);

}  // namespace demlab
