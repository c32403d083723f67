// libFuzzer target that builds and runs small random scenarios: explicit discs (up to 16) on a
// floor with random walls, either contact law (linear: any rotation model, dashpot mode,
// damping, friction rule; DEBRIS: any modulus, friction, area, direction and ceiling), any
// time step (automatic or fixed, stable or not), lost-disc policy and, at times, cohesive bonds, for
// at most a few hundred steps (stop.max_steps), with every output written. Each run must end
// normally, or with an InputError or RunError (a refusal or a diagnosed blow-up); and the
// series and the summary of a run that ended must hold finite numbers only. Anything else (an
// uncaught exception, a crash, a hang, a sanitizer report, a NaN written) is a defect.
// Run: scripts/fuzz.sh [RUNS] (both targets).
#include <fuzzer/FuzzedDataProvider.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <string>

#include "core/csv.h"
#include "core/error.h"
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
    const std::string text = draw_scenario(in);
    static const std::filesystem::path dir =
        std::filesystem::temp_directory_path() / ("demlab-fuzz-run-" + std::to_string(::getpid()));
    std::filesystem::remove_all(dir);
    try {
        demlab::Scenario s = demlab::parse_scenario(text, "fuzz.toml");
        demlab::finish_scenario(s);
        demlab::RunOptions o;
        o.out_dir = dir.string();
        o.plots = false;
        demlab::run_scenario(s, o);
        check_outputs(dir);
        if (std::getenv("DEMLAB_FUZZ_VERBOSE")) std::fprintf(stderr, "fuzz_run: ran\n");
    } catch (const demlab::InputError& e) {
        // a clear refusal
        if (std::getenv("DEMLAB_FUZZ_VERBOSE")) std::fprintf(stderr, "fuzz_run: refused: %s\n", e.what());
    } catch (const demlab::RunError& e) {
        // a diagnosed blow-up or lost disc ("stop")
        if (std::getenv("DEMLAB_FUZZ_VERBOSE")) std::fprintf(stderr, "fuzz_run: stopped: %s\n", e.what());
    }
    std::filesystem::remove_all(dir);
    return 0;
}
