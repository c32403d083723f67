// Reading the CSV files a run writes, by column name: every series names its unit in its
// columns (`t_s`, `fx_barrier_N_per_m`), and readers find a column by that name, never by its
// place, so a column added later breaks no reader.
#pragma once
#include <string>
#include <utility>
#include <vector>

namespace demlab {

// The cells of one CSV line (no quoting: the run's files have none).
std::vector<std::string> csv_cells(const std::string& line);

// Text read as a number, all of it ("1.5abc" is not 1.5; "nan" and "inf" are numbers): false
// when it is empty or is not.
bool parse_number(const std::string& text, double& x);

// The same, and finite.
bool parse_finite(const std::string& text, double& x);

// A cell read as a number, all of it ("1.5abc" is not 1.5; "nan" and "inf" are numbers); an
// InputError "WHERE: 'CELL' is not a number" otherwise (WHERE names the file and line).
double parse_number_cell(const std::string& cell, const std::string& where);

// A CSV file's header line: its columns and where each one is.
class CsvHeader {
public:
    CsvHeader(const std::string& header_line, std::string file);
    // From the names read_csv_table gave.
    CsvHeader(std::vector<std::string> names, std::string file) : names_(std::move(names)), file_(std::move(file)) {}
    // The index of the column `name`, or of `legacy` (the unitless name of run folders written
    // before the units were named) if given and `name` is absent; an InputError naming the
    // file and the columns it has otherwise.
    size_t column(const std::string& name, const std::string& legacy = "") const;
    bool has(const std::string& name) const;
    const std::vector<std::string>& names() const { return names_; }

private:
    std::vector<std::string> names_;
    std::string file_;
};

// The columns of a CSV file (all rows parsed as numbers), by name: read whole, with an
// InputError naming the file and the row for a cell that is not a number (an empty cell is NaN:
// not measured at that row).
struct CsvTable {
    std::vector<std::string> names;
    std::vector<std::vector<double>> rows;
};
CsvTable read_csv_table(const std::string& path);

}  // namespace demlab
