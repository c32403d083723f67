#include "output/plot.h"

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/error.h"
#include "core/fileio.h"

namespace demlab {

// A centred moving average (window in s) of the first `columns` columns of a CSV with a
// header; column 1 (time) is kept.
static std::string moving_average_csv(const std::string& path, int columns, double window) {
    std::ifstream in(path);
    std::string header, line;
    std::getline(in, header);
    std::vector<std::vector<double>> rows;
    while (std::getline(in, line)) {
        std::vector<double> r;
        std::stringstream s(line);
        std::string cell;
        while (std::getline(s, cell, ',') && int(r.size()) < columns) r.push_back(std::stod(cell));
        if (int(r.size()) == columns) rows.push_back(r);
    }
    std::ostringstream out;
    out.precision(8);
    out << header.substr(0, header.find(',', 0)) << ",smoothed\n";
    size_t lo = 0, hi = 0;
    std::vector<double> sum(size_t(columns), 0.0);
    for (size_t k = 0; k < rows.size(); ++k) {
        const double t = rows[k][0];
        while (hi < rows.size() && rows[hi][0] <= t + 0.5 * window) {
            for (int c = 1; c < columns; ++c) sum[size_t(c)] += rows[hi][size_t(c)];
            ++hi;
        }
        while (rows[lo][0] < t - 0.5 * window) {
            for (int c = 1; c < columns; ++c) sum[size_t(c)] -= rows[lo][size_t(c)];
            ++lo;
        }
        out << t;
        for (int c = 1; c < columns; ++c) out << ',' << sum[size_t(c)] / double(hi - lo);
        out << '\n';
    }
    return out.str();
}

bool gnuplot_available() { return std::system("gnuplot --version >/dev/null 2>&1") == 0; }

std::vector<std::string> make_plots(const std::string& run_dir, int width, int height) {
    namespace fs = std::filesystem;
    if (!gnuplot_available())
        throw RunError("gnuplot is not installed, so no plots were made (apt-get install gnuplot-nox, or "
                       "scripts/install-deps.sh)");
    const std::string dir = run_dir + "/plots";
    fs::create_directories(dir);
    std::ostringstream gp;
    gp << "set terminal pngcairo size " << width << "," << height << " font 'DejaVu Sans,11'\n"
       << "set datafile separator ','\nset key autotitle columnhead\nset grid\nset key outside right top\n"
       << "set xlabel 't (s)'\n";
    std::vector<std::string> made;
    const std::string forces = run_dir + "/forces.csv";
    if (fs::exists(forces)) {
        // forces.csv columns: t, fx/fy slope (2,3), arc (4,5), barrier (6,7), total (8,9). The
        // samples are instantaneous (single impacts show); a 50 ms centred moving average is
        // drawn on top of the faint raw curves.
        const std::string smooth = dir + "/forces_smoothed.csv";
        write_file_atomic(smooth, moving_average_csv(forces, 9, 0.05));
        for (const char axis : {'x', 'y'}) {
            const int off = axis == 'x' ? 0 : 1;
            gp << "set output '" << dir << "/forces_" << axis << ".png'\n"
               << "set title 'Force of the mass on the flume, " << axis
               << " (per metre of width; lines: 50 ms moving average, faint: 5 ms samples)'\n"
               << "set ylabel 'F_" << axis << " (N/m)'\n"
               << "plot '" << forces << "' using 1:" << 8 + off << " with lines lc rgb '#d0b0e0' notitle, '' using 1:"
               << 4 + off << " with lines lc rgb '#a0d8c8' notitle, '' using 1:" << 6 + off
               << " with lines lc rgb '#b0d8f0' notitle, '" << smooth << "' using 1:" << 8 + off
               << " with lines lw 2 lc rgb '#8000c0' title 'path (total)', '' using 1:" << 4 + off
               << " with lines lw 2 lc rgb '#009070' title 'arc W2', '' using 1:" << 6 + off
               << " with lines lw 2 lc rgb '#3090d0' title 'barrier W3', '' using 1:" << 2 + off
               << " with lines lw 1 lc rgb '#e0a000' title 'slope W1'\n";
        }
        made.push_back(dir + "/forces_x.png");
        made.push_back(dir + "/forces_y.png");
    }
    const std::string front = run_dir + "/front.csv";
    if (fs::exists(front)) {
        gp << "set output '" << dir << "/front.png'\nset title 'Front of the mass along the flume path'\n"
           << "set ylabel 's (m)'\nplot '" << front << "' using 1:2 with lines lw 2 title 'front s', '' using 1:3 "
              "with lines lw 2 title 'front displacement'\n";
        made.push_back(dir + "/front.png");
    }
    const std::string energy = run_dir + "/energy.csv";
    if (fs::exists(energy)) {
        std::string header;
        std::getline(std::ifstream(energy) >> std::ws, header);
        gp << "set output '" << dir << "/kinetic_energy.png'\nset title 'Kinetic energy (per metre of width)'\n"
           << "set ylabel 'E (J/m)'\n";
        if (header.rfind("t,kinetic,", 0) == 0)  // a DAN run: one kinetic energy
            gp << "plot '" << energy << "' using 1:2 with lines lw 2 title 'kinetic'\n";
        else
            gp << "plot '" << energy << "' using 1:($2+$3) with lines lw 2 title 'total', '' using "
                  "1:2 with lines title 'translation', '' using 1:3 with lines title 'rotation'\n";
        made.push_back(dir + "/kinetic_energy.png");
    }
    if (made.empty()) throw InputError(run_dir + ": no forces.csv, front.csv or energy.csv to plot");
    const std::string script = dir + "/plots.gp";
    write_file_atomic(script, gp.str());
    const std::string cmd = "gnuplot '" + script + "' 2>'" + dir + "/gnuplot.log'";
    if (std::system(cmd.c_str()) != 0)
        throw RunError("gnuplot failed on " + script + " (see " + dir + "/gnuplot.log)");
    return made;
}

}  // namespace demlab
