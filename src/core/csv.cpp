#include "core/csv.h"

#include <cstdlib>
#include <fstream>
#include <cmath>
#include <sstream>

#include "core/error.h"
#include "core/fileio.h"

namespace demlab {

bool parse_number(const std::string& c, double& x) {
    if (c.empty()) return false;
    char* end = nullptr;
    x = std::strtod(c.c_str(), &end);
    return end == c.c_str() + c.size();
}

bool parse_finite(const std::string& text, double& x) { return parse_number(text, x) && std::isfinite(x); }

double parse_number_cell(const std::string& cell, const std::string& where) {
    double x = 0.0;
    if (!parse_number(cell, x)) throw InputError(where + ": '" + cell + "' is not a number");
    return x;
}

std::vector<std::string> csv_cells(const std::string& line) {
    std::vector<std::string> out;
    std::string cell;
    std::istringstream in(line);
    while (std::getline(in, cell, ',')) {
        if (!cell.empty() && cell.back() == '\r') cell.pop_back();
        out.push_back(cell);
    }
    if (!line.empty() && line.back() == ',') out.emplace_back();
    return out;
}

namespace {
// a header line read by a reader of its own (a file's first line): without a byte-order mark
std::string without_bom(std::string line) {
    strip_utf8_bom(line);
    return line;
}
}  // namespace

CsvHeader::CsvHeader(const std::string& header_line, std::string file)
    : names_(csv_cells(without_bom(header_line))), file_(std::move(file)) {}

bool CsvHeader::has(const std::string& name) const {
    for (const std::string& n : names_)
        if (n == name) return true;
    return false;
}

size_t CsvHeader::column(const std::string& name, const std::string& legacy) const {
    // a name given twice: which column is meant cannot be told
    auto only = [&](const std::string& n, size_t k) {
        for (size_t j = k + 1; j < names_.size(); ++j)
            if (names_[j] == n) throw InputError(file_ + ": the column '" + n + "' is named twice in its header");
        return k;
    };
    for (size_t k = 0; k < names_.size(); ++k)
        if (names_[k] == name) return only(name, k);
    if (!legacy.empty())
        for (size_t k = 0; k < names_.size(); ++k)
            if (names_[k] == legacy) return only(legacy, k);
    std::string have;
    for (const std::string& n : names_) have += (have.empty() ? "" : ", ") + n;
    throw InputError(file_ + ": no column '" + name + "' (its columns: " + have + ")");
}

CsvTable read_csv_table(const std::string& path) {
    std::istringstream in(read_input_file(path, kMaxTableBytes, "CSV table"));
    CsvTable t;
    std::string line;
    if (!std::getline(in, line)) throw InputError(path + ": empty (no header line)");
    t.names = csv_cells(line);
    long row = 1;
    while (std::getline(in, line)) {
        ++row;
        if (line.empty()) continue;
        // a run writes whole lines: a last line without its line end, or a row with fewer or
        // more cells than the header, is a file cut short (a full disk, a killed writer)
        if (in.eof())
            throw InputError(path + ":" + std::to_string(row) + ": the last line has no line end: the file is cut short");
        const std::vector<std::string> cells = csv_cells(line);
        if (cells.size() != t.names.size())
            throw InputError(path + ":" + std::to_string(row) + ": " + std::to_string(cells.size()) + " cells, the header has " +
                             std::to_string(t.names.size()) + ": the row is cut short or malformed");
        std::vector<double> v;
        v.reserve(cells.size());
        for (const std::string& c : cells) {
            double x = 0.0;
            if (c.empty()) x = NAN;  // a value not measured at this row (forces.csv's filtered loads before a whole window)
            else x = parse_number_cell(c, path + ":" + std::to_string(row));
            v.push_back(x);
        }
        t.rows.push_back(std::move(v));
    }
    return t;
}

}  // namespace demlab
