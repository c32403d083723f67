#include "geometry/profile.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include "core/error.h"
#include "core/fileio.h"
#include "core/validate.h"

namespace demlab {

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
        std::replace(line.begin(), line.end(), ',', ' ');
        std::istringstream row(line);
        double x = 0.0, y = 0.0;
        std::string rest;
        if (!(row >> x >> y)) {
            if (header_allowed) {  // a header line ("x,y", "x_m,y_m")
                header_allowed = false;
                continue;
            }
            throw InputError(where + ": expected a row 'x,y' of two numbers in m");
        }
        header_allowed = false;
        if (row >> rest) throw InputError(where + ": expected two columns x,y (m), found more");
        if (!std::isfinite(x) || !std::isfinite(y)) throw InputError(where + ": x and y must be finite (m)");
        if (!pts.empty() && !(x > pts.back().x()))
            throw InputError(where + ": x = " + format_number(x) + " m must exceed the previous row's x = " +
                             format_number(pts.back().x()) + " m (a profile runs left to right)");
        pts.emplace_back(x, y);
    }
    if (pts.size() < 2) throw InputError(path + ": a " + what + " needs at least 2 points (x,y rows in m)");
    return pts;
}

}  // namespace demlab
