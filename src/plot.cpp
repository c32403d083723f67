#include "plot.h"

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "error.h"
#include "fileio.h"

namespace demlab {

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
        // forces.csv columns: t, fx/fy slope (2,3), arc (4,5), barrier (6,7), total (8,9)
        gp << "set output '" << dir << "/forces_x.png'\n"
           << "set title 'Force of the mass on the flume, x (per metre of width)'\nset ylabel 'F_x (N/m)'\n"
           << "plot '" << forces << "' using 1:8 with lines lw 2 title 'path (total)', '' using 1:4 with lines lw 2 "
              "title 'arc W2', '' using 1:6 with lines lw 2 title 'barrier W3', '' using 1:2 with lines title 'slope W1'\n"
           << "set output '" << dir << "/forces_y.png'\n"
           << "set title 'Force of the mass on the flume, y (per metre of width)'\nset ylabel 'F_y (N/m)'\n"
           << "plot '" << forces << "' using 1:9 with lines lw 2 title 'path (total)', '' using 1:5 with lines lw 2 "
              "title 'arc W2', '' using 1:7 with lines lw 2 title 'barrier W3', '' using 1:3 with lines title 'slope W1'\n";
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
        gp << "set output '" << dir << "/kinetic_energy.png'\nset title 'Kinetic energy (per metre of width)'\n"
           << "set ylabel 'E (J/m)'\nplot '" << energy << "' using 1:($2+$3) with lines lw 2 title 'total', '' using "
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
