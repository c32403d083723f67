#include "output/plot.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <tuple>

#include "core/csv.h"
#include "core/error.h"
#include "core/output_dir.h"
#include "core/process.h"
#include "core/fileio.h"
#include "core/interrupt.h"
#include "run/summary_file.h"

namespace demlab {

// A centred moving average (window in s) of columns of a CSV series: a CSV of t_s and the
// smoothed columns in that order, under these names.
static std::string moving_average_csv(const std::string& path, const std::vector<size_t>& columns,
                                      const std::vector<std::string>& names, size_t time_column, double window) {
    const CsvTable table = read_csv_table(path);
    std::vector<std::vector<double>> rows;
    for (const std::vector<double>& r : table.rows) {
        std::vector<double> picked{r.at(time_column)};
        for (size_t c : columns) picked.push_back(r.at(c));
        rows.push_back(std::move(picked));
    }
    const size_t width = columns.size() + 1;
    std::ostringstream out;
    out.precision(8);
    out << "t_s";
    for (const std::string& n : names) out << ',' << n << "_smoothed";
    out << '\n';
    size_t lo = 0, hi = 0;
    std::vector<double> sum(width, 0.0);
    for (size_t k = 0; k < rows.size(); ++k) {
        const double t = rows[k][0];
        while (hi < rows.size() && rows[hi][0] <= t + 0.5 * window) {
            for (size_t c = 1; c < width; ++c) sum[c] += rows[hi][c];
            ++hi;
        }
        while (rows[lo][0] < t - 0.5 * window) {
            for (size_t c = 1; c < width; ++c) sum[c] -= rows[lo][c];
            ++lo;
        }
        out << t;
        for (size_t c = 1; c < width; ++c) out << ',' << sum[c] / double(hi - lo);
        out << '\n';
    }
    return out.str();
}

// The header of a run's CSV series (its first line), once the whole file has been checked: a
// series cut short (a full disk, a killed writer) or with a malformed row is refused, naming
// the file and the row, rather than drawn short.
static CsvHeader header_of(const std::string& path) {
    read_csv_table(path);
    std::string line;
    std::getline(std::ifstream(path) >> std::ws, line);
    return CsvHeader(line, path);
}

namespace {

// The barrier's x-load and the arc's y-load as a designer reads them (forces.csv's every-step
// extremes and filtered columns, summary.json's static loads).
void plot_loads(const std::string& run_dir, const std::string& dir, const CsvHeader& h, size_t ct, std::ostringstream& gp,
                std::vector<std::string>& made) {
    namespace fs = std::filesystem;
    const std::string forces = run_dir + "/forces.csv";
    // the barrier's x-load and the arc's y-load as a designer reads them: the band of every
    // step's extremes between two rows, the 5 ms samples, the impulse-filtered load and the
    // static load at rest (summary.json)
    const SummaryFile summary = fs::exists(run_dir + "/summary.json") ? read_summary_file(run_dir + "/summary.json") : SummaryFile{};
    for (const auto& [part, axis, wall] : {std::tuple<std::string, char, std::string>{"barrier", 'x', "barrier W3"},
                                           std::tuple<std::string, char, std::string>{"arc", 'y', "arc W2"}}) {
        const std::string f = std::string("f") + axis + "_" + part;
        if (!h.has(f + "_max_N_per_m") || !h.has(f + "_filtered_N_per_m")) continue;
        const size_t cmax = h.column(f + "_max_N_per_m") + 1, cmin = h.column(f + "_min_N_per_m") + 1,
                     craw = h.column(f + "_N_per_m") + 1, cfil = h.column(f + "_filtered_N_per_m") + 1;
        const std::string file = "load_" + part + "_" + axis + ".png";
        // the static load's sign: the filtered load's at the end (the summary holds its size)
        double stat = summary.number("static_" + f);
        const CsvTable table = read_csv_table(forces);
        for (size_t r = table.rows.size(); r-- > 0;)
            if (std::isfinite(table.rows[r][cfil - 1])) {
                stat = std::copysign(stat, table.rows[r][cfil - 1]);
                break;
            }
        gp << "set output '" << file << "'\nset key inside left top\n"
           << "set title 'Load on the " << wall << ", " << axis << " (per metre of width)'\n"
           << "set ylabel 'F_" << axis << " (N/m)'\nplot '../forces.csv' using " << ct + 1 << ":" << cmin << ":" << cmax
           << " with filledcurves lc rgb '#c8d8f0' title 'every step (min to max since the previous row)', "
           << "'../forces.csv' using " << ct + 1 << ":" << craw << " with lines lc rgb '#7090c0' title 'samples', "
           << "'../forces.csv' using " << ct + 1 << ":" << cfil << " with lines lw 3 lc rgb '#c03030' title 'filtered: mean force over the window W before t'";
        if (std::isfinite(stat)) gp << ", " << stat << " with lines dt 2 lw 2 lc rgb '#202020' title 'static load at rest'";
        gp << "\nset key outside right top\n";
        made.push_back(dir + "/" + file);
    }
}

// forces_x.png and forces_y.png: each wall group's force, raw and smoothed.
void plot_forces(const std::string& run_dir, const std::string& dir, std::ostringstream& gp, std::vector<std::string>& made) {
    namespace fs = std::filesystem;
    const std::string forces = run_dir + "/forces.csv";
    if (fs::exists(forces)) {
        // forces.csv, by name: the samples are instantaneous (single impacts show); a 50 ms
        // centred moving average is drawn on top of the faint raw curves. The groups are the
        // set-up's (the flume's slope, arc and barrier; a terrain's slope and barrier; the dam
        // break's floor and back wall), read from the header, the total first.
        const CsvHeader h = header_of(forces);
        const size_t ct = h.column("t_s", "t");
        const std::string smooth = dir + "/forces_smoothed.csv";
        std::vector<std::string> parts{"total"};
        for (const std::string& n : h.names()) {
            std::string g;
            if (n.rfind("fx_", 0) == 0 && n.size() > 9 && n.compare(n.size() - 8, 8, "_N_per_m") == 0) g = n.substr(3, n.size() - 11);
            else if (n.rfind("fx_", 0) == 0 && n.find('_', 3) == std::string::npos) g = n.substr(3);  // an earlier build's name
            // (a group's every-step extremes, fx_<g>_max / _min, are not groups)
            auto ends = [&](const std::string& tail) { return g.size() > tail.size() && g.compare(g.size() - tail.size(), tail.size(), tail) == 0; };
            const bool extreme = ends("_max") || ends("_min") || ends("_filtered");
            if (!g.empty() && g != "total" && g != "gate" && !extreme) parts.push_back(g);
        }
        // in one order whatever the file's column order: the flume's roles, then by name
        auto rank = [](const std::string& g) {
            for (int k = 0; const char* known : {"total", "slope", "arc", "barrier", "floor", "back_wall"}) {
                if (g == known) return k;
                ++k;
            }
            return 6;
        };
        std::stable_sort(parts.begin(), parts.end(), [&](const std::string& a, const std::string& b) {
            return rank(a) != rank(b) ? rank(a) < rank(b) : (rank(a) == 6 && a < b);
        });
        // x then y: raw columns of forces.csv, smoothed columns 2.. of forces_smoothed.csv
        std::vector<size_t> cols;
        std::vector<std::string> names;
        for (const char* f : {"fx_", "fy_"})
            for (const std::string& part : parts) {
                names.push_back(std::string(f) + part + "_N_per_m");
                cols.push_back(h.column(names.back(), std::string(f) + part));
            }
        write_file_atomic(smooth, moving_average_csv(forces, cols, names, ct, 0.05));
        auto label = [](const std::string& part) -> std::string {
            if (part == "total") return "all walls (total, dashed)";
            if (part == "slope") return "slope W1";
            if (part == "arc") return "arc W2";
            if (part == "barrier") return "barrier W3";
            if (part == "back_wall") return "back wall";
            return part;
        };
        const char* colour[] = {"#8000c0", "#e0a000", "#009070", "#3090d0", "#c03030", "#606060"};
        const char* faint[] = {"#d0b0e0", "#f0d8a0", "#a0d8c8", "#b0d8f0", "#f0b0b0", "#c0c0c0"};
        const size_t n_parts = parts.size();
        for (const char axis : {'x', 'y'}) {
            const size_t o = axis == 'x' ? 0 : n_parts;
            gp << "set output 'forces_" << axis << ".png'\n"
               << "set title 'Force of the mass on the walls, " << axis
               << " (per metre of width; lines: 50 ms moving average, faint: 5 ms samples)'\n"
               << "set ylabel 'F_" << axis << " (N/m)'\nplot ";
            for (size_t k = 0; k < n_parts; ++k)
                gp << (k ? ", " : "") << "'../forces.csv' using " << ct + 1 << ":" << cols[o + k] + 1 << " with lines lc rgb '"
                   << faint[std::min<size_t>(k, 5)] << "' notitle";
            for (size_t k = 0; k < n_parts; ++k)
                gp << ", 'forces_smoothed.csv' using 1:" << o + k + 2 << " with lines lw " << (k == 0 ? 3 : 2)
                   << (k == 0 ? " dt 2" : "") << " lc rgb '" << colour[std::min<size_t>(k, 5)] << "' title " << gnuplot_quote(label(parts[k]));
            gp << "\n";
        }
        made.push_back(dir + "/forces_x.png");
        made.push_back(dir + "/forces_y.png");
        plot_loads(run_dir, dir, h, ct, gp, made);
    }
}

// front.png: the front along the path.
void plot_front(const std::string& run_dir, const std::string& dir, std::ostringstream& gp, std::vector<std::string>& made) {
    namespace fs = std::filesystem;
    const std::string front = run_dir + "/front.csv";
    if (fs::exists(front)) {
        const CsvHeader h = header_of(front);
        const size_t ct = h.column("t_s", "t") + 1, cs = h.column("s_front_m", "s_front") + 1,
                     cd = h.column("displacement_m", "displacement") + 1;
        gp << "set output 'front.png'\nset title 'Front of the mass along the flume path'\n"
           << "set ylabel 's (m)'\nplot '../front.csv' using " << ct << ":" << cs << " with lines lw 2 title 'front s', '' using "
           << ct << ":" << cd << " with lines lw 2 title 'front displacement'\n";
        made.push_back(dir + "/front.png");
    }
}

// kinetic_energy.png.
void plot_energy(const std::string& run_dir, const std::string& dir, std::ostringstream& gp, std::vector<std::string>& made) {
    namespace fs = std::filesystem;
    const std::string energy = run_dir + "/energy.csv";
    if (fs::exists(energy)) {
        const CsvHeader h = header_of(energy);
        const size_t ct = h.column("t_s", "t") + 1;
        gp << "set output 'kinetic_energy.png'\nset title 'Kinetic energy (per metre of width)'\n"
           << "set ylabel 'E (J/m)'\n";
        if (h.has("kinetic_J_per_m") || h.has("kinetic")) {  // a DAN run: one kinetic energy
            gp << "plot '../energy.csv' using " << ct << ":" << h.column("kinetic_J_per_m", "kinetic") + 1
               << " with lines lw 2 title 'kinetic'\n";
        } else {
            const size_t tr = h.column("kinetic_translation_J_per_m", "kinetic_translation") + 1,
                         ro = h.column("kinetic_rotation_J_per_m", "kinetic_rotation") + 1;
            gp << "plot '../energy.csv' using " << ct << ":($" << tr << "+$" << ro << ") with lines lw 2 title 'total', '' using "
               << ct << ":" << tr << " with lines title 'translation', '' using " << ct << ":" << ro << " with lines title 'rotation'\n";
        }
        made.push_back(dir + "/kinetic_energy.png");
    }
}

// barrier_pressure_peak.png and barrier_pressure_map.png.
void plot_pressure(const std::string& run_dir, const std::string& dir, std::ostringstream& gp, std::vector<std::string>& made) {
    namespace fs = std::filesystem;
    const std::string pressure = run_dir + "/barrier_pressure.csv";
    if (fs::exists(pressure)) {
        // the pressure along the barrier at the instant of its largest bin, and all instants
        // as a map (gnuplot's nonuniform matrix: s along the first row, t down the first column)
        const CsvTable p = read_csv_table(pressure);
        std::vector<double> s;
        for (size_t c = 1; c < p.names.size(); ++c) {
            const std::string& n = p.names[c];  // p_at_S_m_Pa
            s.push_back(std::atof(n.substr(5, n.size() - 10).c_str()));
        }
        size_t peak_row = 0;
        double peak = -INFINITY;
        for (size_t r = 0; r < p.rows.size(); ++r)
            for (size_t c = 1; c < p.rows[r].size(); ++c)
                if (p.rows[r][c] > peak) {
                    peak = p.rows[r][c];
                    peak_row = r;
                }
        if (!p.rows.empty() && !s.empty()) {
            std::ostringstream at, map;
            at.precision(10);
            map.precision(10);
            for (size_t c = 0; c < s.size(); ++c) at << s[c] << ',' << p.rows[peak_row][c + 1] << '\n';
            map << s.size();
            for (double x : s) map << ' ' << x;
            map << '\n';
            for (const std::vector<double>& row : p.rows) {
                map << row[0];
                for (size_t c = 1; c < row.size(); ++c) map << ' ' << row[c] / 1000.0;
                map << '\n';
            }
            write_file_atomic(dir + "/barrier_pressure_peak.csv", "s_m,p_Pa\n" + at.str());
            write_file_atomic(dir + "/barrier_pressure_map.dat", map.str());
            // The colour range: up to the 99th percentile of the loaded bins, so the field shows
            // (one impact's bin would otherwise set the scale and leave the rest near zero); the
            // peak, above it, is marked and named.
            std::vector<double> loaded;
            for (const std::vector<double>& row : p.rows)
                for (size_t c = 1; c < row.size(); ++c)
                    if (row[c] > 0.0) loaded.push_back(row[c]);
            double top = peak;
            if (!loaded.empty()) {
                const size_t q = std::min(loaded.size() - 1, size_t(0.99 * double(loaded.size())));
                std::nth_element(loaded.begin(), loaded.begin() + long(q), loaded.end());
                top = loaded[q];
            }
            size_t peak_col = 1;
            for (size_t c = 1; c < p.rows[peak_row].size(); ++c)
                if (p.rows[peak_row][c] == peak) peak_col = c;
            gp << "set output 'barrier_pressure_peak.png'\nset title 'Normal pressure on the barrier at t = "
               << p.rows[peak_row][0] << " s (its largest bin)'\nset xlabel 's along the barrier from its foot (m)'\n"
               << "set ylabel 'p (Pa)'\nplot 'barrier_pressure_peak.csv' using 1:2 with steps lw 2 title 'pressure'\n"
               << "set output 'barrier_pressure_map.png'\nset title 'Normal pressure on the barrier (kPa)'\n"
               << "set xlabel 's along the barrier from its foot (m)'\nset ylabel 't (s)'\nset datafile separator whitespace\n"
               << "set palette rgbformulae 33,13,10\nset cblabel 'p (kPa), to the 99th percentile of the loaded bins'\n"
               << "set autoscale fix\nset format x '%.2f'\nset cbrange [0:" << std::max(top, 1e-9) / 1000.0 << "]\n"
               << "set label 1 sprintf('peak %.1f kPa', " << peak / 1000.0 << ") at " << s[peak_col - 1] << ','
               << p.rows[peak_row][0] << " point pt 6 ps 2 lc rgb 'black' offset 1,1 front\n"
               << "plot 'barrier_pressure_map.dat' nonuniform matrix using 1:2:3 with image notitle\n"
               << "unset label 1\nset format x '% h'\nset datafile separator ','\nunset cblabel\nset cbrange [*:*]\nset autoscale\nset xlabel 't (s)'\n";
            made.push_back(dir + "/barrier_pressure_peak.png");
            made.push_back(dir + "/barrier_pressure_map.png");
        }
    }
}

// peaks.png: the largest flow height and speed along the path.
void plot_peaks(const std::string& run_dir, const std::string& dir, std::ostringstream& gp, std::vector<std::string>& made) {
    namespace fs = std::filesystem;
    const std::string peaks = run_dir + "/peaks.csv";
    if (fs::exists(peaks)) {
        read_csv_table(peaks);  // whole (as header_of checks the others)
        gp << "set output 'peaks.png'\nset title 'Largest flow height and mean speed along the path over the run'\n"
           << "set xlabel 's along the path (m)'\nset ylabel 'flow height normal to the bed (m)'\nset y2label 'mean speed (m/s)'\n"
           << "set y2tics\nplot '../peaks.csv' using 1:2 with lines lw 2 title 'height' axes x1y1, '' using 1:3 with lines lw 2 "
           << "title 'speed' axes x1y2\nunset y2tics\nunset y2label\nset xlabel 't (s)'\n";
        made.push_back(dir + "/peaks.png");
    }
}

// deposit_section.png: the deposit at the end over x (surface.csv), filled between the bed and
// its surface, to scale (one metre in x as long as one in y), as a designer draws the section.
void plot_surface(const std::string& run_dir, const std::string& dir, std::ostringstream& gp, std::vector<std::string>& made) {
    namespace fs = std::filesystem;
    const std::string surface = run_dir + "/surface.csv";
    if (!fs::exists(surface)) return;
    const CsvHeader h = header_of(surface);
    const size_t cx = h.column("x_m") + 1, cb = h.column("bed_m") + 1, cs = h.column("surface_m") + 1;
    gp << "set output 'deposit_section.png'\nset title 'The deposit at the end of the run'\n"
       << "set xlabel 'x (m)'\nset ylabel 'y (m)'\nset size ratio -1\n"
       << "plot '../surface.csv' using " << cx << ":" << cb << ":" << cs
       << " with filledcurves lc rgb '#c8a060' title 'deposit', '' using " << cx << ":" << cb
       << " with lines lw 2 lc rgb '#303030' title 'bed'\nset size noratio\nset xlabel 't (s)'\n";
    made.push_back(dir + "/deposit_section.png");
}

// motion.png and bonds.png of a 3-D run (series.csv of dem3/dem3_run.cpp): the fastest sphere
// and the largest travel, and the intact bonds when there are any.
void plot_spheres(const std::string& run_dir, const std::string& dir, std::ostringstream& gp, std::vector<std::string>& made) {
    const std::string path = run_dir + "/series.csv";
    std::ifstream in(path);
    std::string header_line, first;
    if (!std::getline(in, header_line) || header_line.find("moving_spheres") == std::string::npos) return;
    read_csv_table(path);  // whole (as header_of checks the others)
    const CsvHeader header(header_line, path);
    auto col = [&](const char* name) { return std::to_string(header.column(name) + 1); };  // gnuplot counts from 1
    gp << "set output 'motion.png'\nset title 'The fastest sphere and the largest travel in map view'\n"
       << "set ylabel 'speed (m/s)'\nset y2label 'travel (m)'\nset y2tics\n"
       << "plot '../series.csv' using 1:" << col("max_speed_m_per_s") << " with lines lw 2 title 'fastest sphere' axes x1y1, '' using 1:"
       << col("max_travel_m") << " with lines lw 2 title 'largest travel' axes x1y2\nunset y2tics\nunset y2label\n";
    made.push_back(dir + "/motion.png");
    // the t = 0 row: the bonds there are the bonds made
    if (!header.has("intact_bonds") || !std::getline(in, first)) return;
    const std::vector<std::string> cells = csv_cells(first);
    const size_t bonds = header.column("intact_bonds");
    if (bonds >= cells.size() || std::strtod(cells[bonds].c_str(), nullptr) <= 0.0) return;
    gp << "set output 'bonds.png'\nset title 'Intact bonds'\nset ylabel 'bonds'\n"
       << "plot '../series.csv' using 1:" << col("intact_bonds") << " with lines lw 2 title 'intact'\n";
    made.push_back(dir + "/bonds.png");
}

}  // namespace

bool gnuplot_available() { return program_available("gnuplot"); }

namespace {
// Whether the file is a whole PNG: the signature first and the IEND chunk last (a write cut
// by a full disk or a size limit loses the end).
bool png_is_whole(const std::string& path) {
    static const unsigned char kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    static const unsigned char kEnd[12] = {0, 0, 0, 0, 'I', 'E', 'N', 'D', 0xae, 0x42, 0x60, 0x82};
    std::ifstream in(path, std::ios::binary);
    unsigned char head[8], tail[12];
    if (!in.read(reinterpret_cast<char*>(head), 8) || !std::equal(head, head + 8, kSignature)) return false;
    in.seekg(-12, std::ios::end);
    return bool(in.read(reinterpret_cast<char*>(tail), 12)) && std::equal(tail, tail + 12, kEnd);
}
}  // namespace

void run_gnuplot(const std::string& dir, const std::string& script, const std::vector<std::string>& pngs) {
    ProcessDef gnuplot;
    gnuplot.argv = {"gnuplot", script};
    gnuplot.cwd = dir;
    gnuplot.stderr_file = dir + "/gnuplot.log";
    const int status = run_process(gnuplot);
    // Ctrl-C reaches gnuplot too (one process group), which may end with any status: the work
    // drawn from is complete (the caller holds an InterruptScope, so demlab records the signal)
    if (pending_interrupt() != 0)
        throw Interrupted("interrupted while gnuplot drew " + dir + "; what it draws from is complete: `demlab plot` "
                          "(or `demlab compare` again) draws it");
    if (status != 0) throw RunError("gnuplot failed on " + dir + "/" + script + " (see " + dir + "/gnuplot.log)");
    std::string cut;
    for (const std::string& png : pngs)
        if (!png_is_whole(png)) {
            std::error_code ec;
            std::filesystem::remove(png, ec);
            if (cut.empty()) cut = png;
        }
    if (!cut.empty())
        throw WriteError(cut + ": gnuplot could not write the whole plot (a full disk or a file size limit?); "
                               "no cut plot was left");
}

std::vector<std::string> make_plots(const std::string& run_dir, int width, int height) {
    namespace fs = std::filesystem;
    if (!gnuplot_available())
        throw RunError("gnuplot is not installed, so no plots were made (apt-get install gnuplot-nox, or "
                       "scripts/install-deps.sh)");
    const std::string dir = run_dir + "/plots";
    // a plots/ folder the user made, or files the user put into demlab's: refused before any
    // is overwritten or recorded as demlab's (which a later --force would delete). A folder
    // without the marker that holds only the files this function writes is one made by a
    // build before the marker (its plots.gp among them): it is demlab's.
    if (fs::is_directory(dir) && !fs::is_symlink(dir) && !is_demlab_output(dir) && fs::is_regular_file(dir + "/plots.gp")) {
        bool only_plots = true;
        for (const auto& e : fs::directory_iterator(dir)) {
            const std::string name = e.path().filename().string(), ext = e.path().extension().string();
            only_plots = only_plots && !e.is_symlink() && e.is_regular_file() &&
                         (ext == ".png" || name == "plots.gp" || name == "gnuplot.log" || name == "forces_smoothed.csv" ||
                          name == "barrier_pressure_peak.csv" || name == "barrier_pressure_map.dat");
        }
        if (only_plots) mark_output_dir(dir);
    }
    check_regenerated_output_dir(dir);
    fs::create_directories(dir);
    mark_output_dir(dir);
    // Ctrl-C reaches gnuplot as well as demlab: recorded here (run_gnuplot reports it as an
    // interruption), not the end of demlab by the signal
    InterruptScope interrupts;
    std::ostringstream gp;
    gp << "set terminal pngcairo size " << width << "," << height << " font 'DejaVu Sans,11'\n"
       << "set datafile separator ','\nset key autotitle columnhead\nset grid\nset key outside right top\n"
       << "set xlabel 't (s)'\n";
    std::vector<std::string> made;
    plot_forces(run_dir, dir, gp, made);
    plot_front(run_dir, dir, gp, made);
    plot_energy(run_dir, dir, gp, made);
    plot_pressure(run_dir, dir, gp, made);
    plot_peaks(run_dir, dir, gp, made);
    plot_surface(run_dir, dir, gp, made);
    plot_spheres(run_dir, dir, gp, made);
    if (made.empty()) throw InputError(run_dir + ": no forces.csv, front.csv, energy.csv or series.csv to plot");
    const std::string script = dir + "/plots.gp";
    write_file_atomic(script, gp.str());
    // no shell, and the script names its files relative to the plots folder, where gnuplot
    // runs: no path or name a user chose ever reaches a command line or the script
    run_gnuplot(dir, "plots.gp", made);
    record_output_files(dir);  // (so a --force on the run keeps off what the user adds here)
    return made;
}

}  // namespace demlab
