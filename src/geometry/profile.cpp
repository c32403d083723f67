#include "geometry/profile.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <sstream>

#include "core/csv.h"
#include "core/error.h"
#include "core/fileio.h"
#include "core/validate.h"

namespace demlab {

namespace {
// A row's cells: split at commas, or at blanks where the row has no comma; each trimmed.
std::vector<std::string> profile_cells(const std::string& line) {
    std::vector<std::string> cells;
    if (line.find(',') != std::string::npos) {
        std::istringstream in(line);
        std::string cell;
        while (std::getline(in, cell, ',')) {
            const size_t a = cell.find_first_not_of(" \t"), b = cell.find_last_not_of(" \t");
            cells.push_back(a == std::string::npos ? std::string() : cell.substr(a, b - a + 1));
        }
        if (line.back() == ',') cells.emplace_back();
    } else {
        std::istringstream in(line);
        std::string cell;
        while (in >> cell) cells.push_back(cell);
    }
    return cells;
}
}  // namespace

std::vector<Vec2> read_profile_csv(const std::string& path, const std::string& what) {
    std::istringstream in(read_input_file(path, kMaxTableBytes, what));
    std::vector<Vec2> pts;
    std::string line;
    int no = 0;
    bool header_allowed = true;
    while (std::getline(in, line)) {
        ++no;
        if (!line.empty() && line.back() == '\r') line.pop_back();
        if (line.empty() || line[0] == '#') continue;
        const std::string where = path + ":" + std::to_string(no);
        std::vector<std::string> cells = profile_cells(line);
        while (!cells.empty() && cells.back().empty()) cells.pop_back();  // a spreadsheet's trailing commas
        if (cells.empty()) continue;
        double v[2] = {0.0, 0.0};
        int numbers = 0;
        for (size_t k = 0; k < cells.size() && k < 2; ++k) numbers += parse_number(cells[k], v[k]) ? 1 : 0;
        // a header names its columns ("x,y", "x_m,y_m"): no cell of it is a number; a row with
        // a cell that only starts like one ("1.5x", "O.45") is a damaged row, not a header
        bool header = header_allowed;
        for (const std::string& c : cells) {
            double probe = 0.0;
            header = header && !parse_number(c, probe) && !c.empty() && !(std::isdigit(static_cast<unsigned char>(c[0])) ||
                                                                          c[0] == '-' || c[0] == '+' || c[0] == '.');
        }
        header_allowed = false;
        if (header) continue;
        if (cells.size() != 2 || numbers != 2)
            throw InputError(where + ": expected a row 'x,y' of two numbers in m, found '" + line + "'");
        // beyond these is no ground (and squares would overflow): x a map coordinate within
        // 1e9 m, y an elevation within 10,000 km
        const double bound[2] = {1e9, 1e7};
        for (int k = 0; k < 2; ++k)
            if (!(std::abs(v[k]) <= bound[k]))
                throw InputError(where + ": " + (k == 0 ? "x" : "y") + " = " + cells[size_t(k)] + " must be a finite number in [-" +
                                 (k == 0 ? "1e9, 1e9" : "1e7, 1e7") + "] m");
        const double x = v[0], y = v[1];
        if (!pts.empty() && !(x > pts.back().x()))
            throw InputError(where + ": x = " + format_number(x) + " m must exceed the previous row's x = " +
                             format_number(pts.back().x()) + " m (a profile runs left to right)");
        pts.emplace_back(x, y);
    }
    if (pts.size() < 2) throw InputError(path + ": a " + what + " needs at least 2 points (x,y rows in m)");
    return pts;
}

}  // namespace demlab
