// Reading a run folder's summary.json back (our own flat layout: one "key": value a line):
// the numbers (null as NaN) and the strings, for the calibration's table and `demlab compare`.
#pragma once
#include <map>
#include <string>

namespace demlab {

struct SummaryFile {
    std::map<std::string, double> numbers;
    std::map<std::string, std::string> strings;
    double number(const std::string& key) const;  // NaN when absent
    std::string text(const std::string& key) const;  // "" when absent
};

SummaryFile read_summary_file(const std::string& path);

}  // namespace demlab
