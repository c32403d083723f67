// libFuzzer target that builds and runs small random scenarios: explicit discs (up to 16) on a
// floor with random walls, either contact law (linear: any rotation model, dashpot mode,
// damping, friction rule; DEBRIS: any modulus, friction, area, direction and ceiling), any
// time step (automatic or fixed, stable or not), lost-disc policy and, at times, cohesive bonds, for
// at most a few hundred steps (stop.max_steps), with every output written. Each run must end
// normally, or with an InputError or RunError (a refusal or a diagnosed blow-up); and the
// series and the summary of a run that ended must hold finite numbers only. Anything else (an
// uncaught exception, a crash, a hang, a sanitizer report, a NaN written) is a defect.
// One input in three is a terrain scenario instead (draw_terrain: a profile of any shape or a
// grid's section, a release polygon, lattice region or top anywhere, at times bonds or a
// domain box); an accepted one must also start with every disc above the ground and inside
// the domain (check_start).
// Run: scripts/fuzz.sh [RUNS] (both targets).
#include <fuzzer/FuzzedDataProvider.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "core/csv.h"
#include "core/error.h"
#include "dem/world.h"
#include "run/run.h"
#include "run/summary_file.h"
#include "scenario/scenario.h"

namespace {

std::string number(double v) {
    std::ostringstream o;
    o.precision(17);
    o << v;
    return o.str();
}

// The scenario's TOML text, drawn from the fuzzer's bytes (parsed like a user's file, so the
// validation runs as it does for them).
std::string draw_scenario(FuzzedDataProvider& in) {
    std::ostringstream t;
    const int steps = in.ConsumeIntegralInRange(1, 400);
    t << "[scenario]\nname = \"fuzz\"\n";
    const double t_max = in.ConsumeFloatingPointInRange(1e-4, 2.0);
    t << "[stop]\nt_max = " << number(t_max) << "\nrest_duration = " << number(0.5 * t_max) << "\nmax_steps = " << steps
      << "\nmax_energy_gain = " << number(in.ConsumeFloatingPointInRange(0.01, 10.0)) << "\n";
    t << "[output]\nseries_interval = " << number(in.ConsumeFloatingPointInRange(1e-5, 0.01))
      << "\nsnapshot_interval = " << (in.ConsumeBool() ? number(in.ConsumeFloatingPointInRange(1e-4, 0.01)) : "0") << "\n";
    const int discs = in.ConsumeIntegralInRange(1, 16);
    if (in.ConsumeBool()) t << "track = [" << in.ConsumeIntegralInRange(0, discs - 1) << "]\n";
    t << "[timestep]\nautomatic = " << (in.ConsumeBool() ? "true" : "false") << "\nsafety = "
      << number(in.ConsumeFloatingPointInRange(0.05, 1.0)) << "\nfixed = " << number(std::pow(10.0, in.ConsumeFloatingPointInRange(-7.0, -2.0)))
      << "\ndamping_correction = " << (in.ConsumeBool() ? "true" : "false") << "\n";
    t << "[world]\ngravity = [" << number(in.ConsumeFloatingPointInRange(-20.0, 20.0)) << ", "
      << number(in.ConsumeFloatingPointInRange(-20.0, 5.0)) << "]\nlost_discs = \"" << (in.ConsumeBool() ? "remove" : "stop")
      << "\"\nmax_overlap_ratio = " << number(in.ConsumeFloatingPointInRange(0.05, 2.0)) << "\n";
    // one run in four with the DEBRIS law (no rotation, none of the linear law's keys)
    const bool debris = in.ConsumeIntegralInRange(0, 3) == 0;
    if (debris) {
        t << "[contact]\nlaw = \"debris\"\n[rotation]\nmodel = 1\n[debris]\nyoungs_modulus = "
          << number(std::pow(10.0, in.ConsumeFloatingPointInRange(5.0, 11.0))) << "\nmu = " << number(in.ConsumeFloatingPointInRange(0.0, 1.0))
          << "\neta = " << number(in.ConsumeBool() ? 0.0 : std::pow(10.0, in.ConsumeFloatingPointInRange(0.0, 5.0)))
          << "\ncontact_area = \"" << (in.ConsumeBool() ? "chord" : "diameter") << "\"\nfriction_normal = \""
          << (in.ConsumeBool() ? "resultant" : "sum") << "\"\nfriction_direction = \"" << (in.ConsumeBool() ? "trial" : "previous")
          << "\"\ndt_max = " << number(std::pow(10.0, in.ConsumeFloatingPointInRange(-5.0, -1.0))) << "\n";
        t << "[material]\ndensity = " << number(std::pow(10.0, in.ConsumeFloatingPointInRange(1.0, 4.5))) << "\n";
    } else {
        t << "[rotation]\nmodel = " << in.ConsumeIntegralInRange(1, 3) << "\nmu_br = " << number(in.ConsumeFloatingPointInRange(0.01, 1.0))
          << "\nrolling_form = \"" << (in.ConsumeBool() ? "literal" : "normal_force") << "\"\ndamping_per = \""
          << (in.ConsumeBool() ? "disc" : "contact") << "\"\nu_rr = " << number(in.ConsumeFloatingPointInRange(0.0, 0.002)) << "\n";
        t << "[damping]\nbeta_n = " << number(in.ConsumeFloatingPointInRange(0.0, 0.99)) << "\nbeta_s = "
          << number(in.ConsumeFloatingPointInRange(0.0, 0.99)) << "\ndp_mode = \"" << in.ConsumeIntegralInRange(0, 3) << "\"\n";
        t << "[material]\ndensity = " << number(std::pow(10.0, in.ConsumeFloatingPointInRange(1.0, 4.5)))
          << "\nkn = " << number(std::pow(10.0, in.ConsumeFloatingPointInRange(3.0, 9.0)))
          << "\nks = " << number(std::pow(10.0, in.ConsumeFloatingPointInRange(3.0, 9.0)))
          << "\nwall_kn = " << number(std::pow(10.0, in.ConsumeFloatingPointInRange(3.0, 9.0)))
          << "\nfriction_disc_deg = " << number(in.ConsumeFloatingPointInRange(0.0, 60.0))
          << "\nfriction_wall_deg = " << number(in.ConsumeFloatingPointInRange(0.0, 60.0))
          << "\nfriction_rule_disc_disc = \"" << (in.ConsumeBool() ? "min" : "max") << "\"\n";
    }
    if (in.ConsumeIntegralInRange(0, 3) == 0)
        t << "[cohesion]\nenabled = true\nmodulus = " << number(std::pow(10.0, in.ConsumeFloatingPointInRange(3.0, 7.0)))
          << "\nmax_strain = " << number(in.ConsumeFloatingPointInRange(0.01, 0.5)) << "\nbreak_mode = \""
          << (in.ConsumeBool() ? "both" : "tension") << "\"\npredict = " << (in.ConsumeBool() ? "true" : "false")
          << "\nfilter = \"none\"\n";
    // the discs on a grid of 0.1 m cells (4 a row), each inside its cell: they start apart
    for (int i = 0; i < discs; ++i) {
        const double r = in.ConsumeFloatingPointInRange(0.004, 0.045);
        const double x = 0.1 * (i % 4) + 0.05 + in.ConsumeFloatingPointInRange(-1.0, 1.0) * (0.049 - r);
        const double y = 0.1 * (i / 4) + 0.06 + in.ConsumeFloatingPointInRange(-1.0, 1.0) * (0.049 - r);
        t << "[[discs]]\nposition = [" << number(x) << ", " << number(y) << "]\nradius = " << number(r) << "\nvelocity = ["
          << number(in.ConsumeFloatingPointInRange(-5.0, 5.0)) << ", " << number(in.ConsumeFloatingPointInRange(-5.0, 5.0))
          << "]\nomega = " << number(in.ConsumeFloatingPointInRange(-50.0, 50.0)) << "\n";
    }
    // a floor under them, then up to three walls anywhere around them
    t << "[[walls]]\nstart = [-0.5, 0]\nend = [1.0, 0]\n";
    const int walls = in.ConsumeIntegralInRange(0, 3);
    for (int w = 0; w < walls; ++w) {
        auto coord = [&] { return number(in.ConsumeFloatingPointInRange(-0.5, 1.0)); };
        const std::string x0 = coord(), y0 = coord(), x1 = coord(), y1 = coord();
        t << "[[walls]]\nstart = [" << x0 << ", " << y0 << "]\nend = [" << x1 << ", " << y1 << "]\n";
    }
    return t.str();
}

// A terrain scenario (one input in three): a profile of any shape (2 to 8 points, x
// increasing, heights anywhere) from a CSV file, or an elevation grid sampled along a section
// anywhere; a release anywhere: a generated polygon (terrain.release), a lattice region or a
// lattice top (filled down to the ground), at times cohesive, at times with a domain box
// (world.domain). The files are written beside the run folder; `files` lists them for removal.
std::string draw_terrain(FuzzedDataProvider& in, const std::string& stem, std::vector<std::string>& files) {
    std::ostringstream t;
    t << "[scenario]\nname = \"fuzz\"\n";
    const double t_max = in.ConsumeFloatingPointInRange(1e-4, 1.0);
    t << "[stop]\nt_max = " << number(t_max) << "\nmax_steps = " << in.ConsumeIntegralInRange(1, 300) << "\n";
    t << "[output]\nseries_interval = " << number(in.ConsumeFloatingPointInRange(1e-4, 0.01)) << "\nsnapshot_interval = 0\n";
    t << "[timestep]\nautomatic = " << (in.ConsumeIntegralInRange(0, 3) != 0 ? "true" : "false")
      << "\nfixed = " << number(std::pow(10.0, in.ConsumeFloatingPointInRange(-6.0, -3.0))) << "\n";
    t << "[material]\nkn = " << number(std::pow(10.0, in.ConsumeFloatingPointInRange(3.0, 7.0)))
      << "\nks = " << number(std::pow(10.0, in.ConsumeFloatingPointInRange(3.0, 7.0))) << "\n";
    t << "[rotation]\nmodel = " << in.ConsumeIntegralInRange(1, 3) << "\nu_rr = 0\n";
    if (in.ConsumeBool()) {
        const double x0 = in.ConsumeFloatingPointInRange(-3.0, 3.0), y0 = in.ConsumeFloatingPointInRange(-3.0, 3.0);
        t << "[world]\ndomain = [[" << number(x0) << ", " << number(y0) << "], [" << number(x0 + in.ConsumeFloatingPointInRange(0.0, 6.0))
          << ", " << number(y0 + in.ConsumeFloatingPointInRange(0.0, 6.0)) << "]]\n";
    }
    t << "[terrain]\n";
    double xa = 0.0, xb = 0.0;  // the ground's x range (of the section: its length)
    if (in.ConsumeIntegralInRange(0, 3) != 0) {
        // a profile: x increasing by 0.05 to 1 m, y anywhere in [-0.5, 1.5] m
        std::ostringstream p;
        p << "x_m,y_m\n";
        double x = in.ConsumeFloatingPointInRange(-1.0, 1.0);
        xa = x;
        for (int k = 0, n = in.ConsumeIntegralInRange(2, 8); k < n; ++k) {
            p << number(x) << ',' << number(in.ConsumeFloatingPointInRange(-0.5, 1.5)) << '\n';
            xb = x;
            x += in.ConsumeFloatingPointInRange(0.05, 1.0);
        }
        files.push_back(stem + "-profile.csv");
        std::ofstream(files.back()) << p.str();
        t << "profile = \"" << files.back() << "\"\n";
    } else {
        // a grid of 2-6 x 2-4 cells of 0.2-0.5 m, heights anywhere; a section anywhere near it
        const int nc = in.ConsumeIntegralInRange(2, 6), nr = in.ConsumeIntegralInRange(2, 4);
        const double cell = in.ConsumeFloatingPointInRange(0.2, 0.5);
        std::ostringstream g;
        g << "ncols " << nc << "\nnrows " << nr << "\nxllcorner 0\nyllcorner 0\ncellsize " << number(cell) << "\n";
        for (int r = 0; r < nr; ++r) {
            for (int c = 0; c < nc; ++c) g << (c ? " " : "") << number(in.ConsumeFloatingPointInRange(-0.5, 1.5));
            g << '\n';
        }
        files.push_back(stem + "-grid.asc");
        std::ofstream(files.back()) << g.str();
        auto coord = [&](int n) { return number(in.ConsumeFloatingPointInRange(0.0, (n + 0.5) * cell)); };
        const std::string ax = coord(nc), ay = coord(nr), bx = coord(nc), by = coord(nr);
        xb = std::hypot(std::stod(bx) - std::stod(ax), std::stod(by) - std::stod(ay));
        t << "grid = \"" << files.back() << "\"\nsection = [[" << ax << ", " << ay << "], [" << bx << ", " << by << "]]\n"
          << "spacing = " << number(in.ConsumeFloatingPointInRange(0.05, 0.5)) << "\n";
    }
    // the release, anywhere: over the ground's x range three times in four, else x in [-2, 6] m;
    // y in [-1, 3] m (the ground lies in [-0.5, 1.5] m)
    const int kind = in.ConsumeIntegralInRange(0, 2);
    const double cx = in.ConsumeIntegralInRange(0, 3) != 0 ? in.ConsumeFloatingPointInRange(xa, std::max(xa, xb))
                                                           : in.ConsumeFloatingPointInRange(-2.0, 6.0);
    const double cy = in.ConsumeFloatingPointInRange(-1.0, 3.0);
    const double size = in.ConsumeFloatingPointInRange(0.1, 1.0);
    if (kind == 0) {
        // a box or a triangle of a few dozen discs, settled briefly (accepted unsettled)
        const double w = size, h = size * in.ConsumeFloatingPointInRange(0.5, 2.0);
        t << "release = [[" << number(cx) << ", " << number(cy) << "], [" << number(cx + w) << ", " << number(cy) << "], ";
        if (in.ConsumeBool()) t << "[" << number(cx + w) << ", " << number(cy + h) << "], ";
        t << "[" << number(cx) << ", " << number(cy + h) << "]]\n";
        const double r_max = std::min(w, h) / 8.0 * in.ConsumeFloatingPointInRange(0.7, 1.0);
        t << "[release]\nr_max = " << number(r_max) << "\nr_min = " << number(r_max * in.ConsumeFloatingPointInRange(0.5, 1.0))
          << "\nsettle_max_time = " << number(in.ConsumeFloatingPointInRange(0.001, 0.02)) << "\naccept_unsettled = true\n";
    } else {
        t << "[lattice_release]\n";
        if (kind == 1) {
            // a star-shaped polygon of 3-6 corners around (cx, cy): simple
            t << "region = [";
            const int n = in.ConsumeIntegralInRange(3, 6);
            for (int k = 0; k < n; ++k) {
                const double a = 2.0 * demlab::kPi * (k + in.ConsumeFloatingPointInRange(0.0, 0.9)) / n;
                const double rho = size * in.ConsumeFloatingPointInRange(0.3, 1.0);
                t << (k ? ", " : "") << "[" << number(cx + rho * std::cos(a)) << ", " << number(cy + rho * std::sin(a)) << "]";
            }
            t << "]\n";
        } else {
            // a top surface of 2-4 points, x increasing, heights anywhere
            std::ostringstream p;
            p << "x_m,y_m\n";
            double x = cx;
            for (int k = 0, n = in.ConsumeIntegralInRange(2, 4); k < n; ++k) {
                p << number(x) << ',' << number(in.ConsumeFloatingPointInRange(-0.5, 2.0)) << '\n';
                x += in.ConsumeFloatingPointInRange(0.05, 1.0);
            }
            files.push_back(stem + "-top.csv");
            std::ofstream(files.back()) << p.str();
            t << "top = \"" << files.back() << "\"\n";
        }
        const double r = size * in.ConsumeFloatingPointInRange(0.03, 0.2);
        t << "origin = [" << number(cx) << ", " << number(cy) << "]\nr_min = " << number(r) << "\nangle_deg = "
          << number(in.ConsumeFloatingPointInRange(0.0, 60.0)) << "\nsettle = " << (in.ConsumeIntegralInRange(0, 7) == 0 ? "true" : "false")
          << "\n[release]\nsettle_max_time = " << number(in.ConsumeFloatingPointInRange(0.001, 0.05)) << "\n";
    }
    if (in.ConsumeIntegralInRange(0, 2) == 0)
        t << "[cohesion]\nenabled = true\nmodulus = " << number(std::pow(10.0, in.ConsumeFloatingPointInRange(3.0, 7.0)))
          << "\nmax_strain = " << number(in.ConsumeFloatingPointInRange(0.01, 0.5)) << "\nfilter = \""
          << (in.ConsumeBool() ? "triangular" : "none") << "\"\n";
    return t.str();
}

// The invariant of an accepted terrain scenario: it starts with every disc's centre above the
// ground (within the profile's x range, on or above the polyline) and inside the domain.
void check_start(const demlab::Scenario& s, const demlab::World& w, const std::string& text) {
    const std::vector<demlab::Vec2>& g = s.terrain.points;
    const demlab::Vec2 lo = w.def().domain_lo, hi = w.def().domain_hi;
    for (size_t i = 0; i < w.disc_count(); ++i) {
        const demlab::Vec2 p = w.positions()[i];
        const char* fault = nullptr;
        if (p.x() < lo.x() || p.x() > hi.x() || p.y() < lo.y() || p.y() > hi.y()) fault = "outside the domain";
        else if (p.x() < g.front().x() || p.x() > g.back().x()) fault = "over no ground (beyond the profile's x range)";
        else {
            size_t k = 0;
            while (k + 2 < g.size() && g[k + 1].x() < p.x()) ++k;
            const double y = g[k].y() + (g[k + 1].y() - g[k].y()) * (p.x() - g[k].x()) / (g[k + 1].x() - g[k].x());
            if (p.y() < y - 1e-9 * (1.0 + std::abs(y))) fault = "under the ground";
        }
        if (fault) {
            std::fprintf(stderr, "fuzz_run: an accepted scenario starts with disc %zu at (%g, %g) %s:\n%s\n", i, p.x(), p.y(), fault,
                         text.c_str());
            std::abort();
        }
    }
}

// The numbers of a run's series and summary are finite (a summary's null is a figure that
// does not apply, e.g. a release figure of explicit discs).
void check_outputs(const std::filesystem::path& dir) {
    for (const char* f : {"forces.csv", "energy.csv", "track.csv", "lost.csv", "bonds_broken.csv"}) {
        if (!std::filesystem::exists(dir / f)) continue;
        const demlab::CsvTable table = demlab::read_csv_table((dir / f).string());
        for (const auto& row : table.rows)
            for (size_t c = 0; c < row.size(); ++c)
                if (!std::isfinite(row[c])) {
                    std::fprintf(stderr, "fuzz_run: %s: column %s holds %g\n", f, table.names[c].c_str(), row[c]);
                    std::abort();
                }
    }
    const demlab::SummaryFile s = demlab::read_summary_file((dir / "summary.json").string());
    for (const char* key : {"t_end", "dt", "dt_min", "dt_max", "energy_balance_error", "total_mass", "steps"})
        if (!std::isfinite(s.number(key))) {
            std::fprintf(stderr, "fuzz_run: summary.json: %s = %g\n", key, s.number(key));
            std::abort();
        }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    FuzzedDataProvider in(data, size);
    static const std::filesystem::path dir =
        std::filesystem::temp_directory_path() / ("demlab-fuzz-run-" + std::to_string(::getpid()));
    std::vector<std::string> files;
    const bool terrain = in.ConsumeIntegralInRange(0, 2) == 0;
    const std::string text = terrain ? draw_terrain(in, dir.string(), files) : draw_scenario(in);
    std::filesystem::remove_all(dir);
    try {
        demlab::Scenario s = demlab::parse_scenario(text, "fuzz.toml");
        demlab::finish_scenario(s);
        if (terrain) check_start(s, demlab::world_of_scenario(s), text);
        demlab::RunOptions o;
        o.out_dir = dir.string();
        o.plots = false;
        demlab::run_scenario(s, o);
        check_outputs(dir);
        if (std::getenv("DEMLAB_FUZZ_VERBOSE")) std::fprintf(stderr, "fuzz_run: ran%s\n", terrain ? " (terrain)" : "");
    } catch (const demlab::InputError& e) {
        // a clear refusal
        if (std::getenv("DEMLAB_FUZZ_VERBOSE")) std::fprintf(stderr, "fuzz_run: refused: %s\n", e.what());
    } catch (const demlab::RunError& e) {
        // a diagnosed blow-up or lost disc ("stop")
        if (std::getenv("DEMLAB_FUZZ_VERBOSE")) std::fprintf(stderr, "fuzz_run: stopped: %s\n", e.what());
    }
    std::filesystem::remove_all(dir);
    for (const std::string& f : files) std::filesystem::remove(f);
    return 0;
}
