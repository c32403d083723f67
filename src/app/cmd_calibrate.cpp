// demlab calibrate CONFIG: the dam-break friction calibration.
#include <cstdio>
#include <memory>
#include <sstream>

#include "calibration/calibration.h"
#include "app/commands.h"
#include "calibration/ranks.h"
#include "core/csv.h"
#include "core/error.h"

namespace demlab {

namespace {
struct CalibrateCli {
    std::string config, angles, apply;
    std::string out = "runs/calibration";  // (an --out '' given is refused, not taken for the default)
    int jobs = 0, seeds = 0, scale = 0;
    bool force = false, no_refine = false;
};

int calibrate_command(const CalibrateCli& o) {
    CalibrationConfig c = load_calibration(o.config);
    if (!o.angles.empty()) {
        c.angles.clear();
        std::stringstream s(o.angles);
        std::string item;
        while (std::getline(s, item, ',')) {
            double angle = 0.0;
            if (!parse_number(item, angle))  // all of it: "15x" is not 15
                throw InputError("--angles '" + o.angles + "': expected numbers in degrees separated by commas, e.g. 15,15.5,16");
            c.angles.push_back(angle);
            if (!(c.angles.back() >= 0 && c.angles.back() <= 60)) throw InputError("--angles: each angle must be in [0, 60] deg");
        }
        std::sort(c.angles.begin(), c.angles.end());
    }
    if (o.seeds) c.seeds = o.seeds;
    if (o.scale) c.scale = o.scale;
    if (o.no_refine) c.refine = false;
    CalibrationOptions opt;
    opt.out = o.out;
    opt.jobs = o.jobs;
    opt.force = o.force;
    if (!o.apply.empty()) check_apply_calibration(o.apply, o.force);  // before hours of runs
    const CalibrationResult r = calibrate(c, opt);
    if (!Ranks::world().root()) return kExitOk;  // rank 0 reports (and applies)
    std::printf("best friction angle %.2f deg (objective %.3f deg); %d new run(s), %d reused, %.0f s\n", r.best_angle,
                r.best_objective, r.runs_done, r.runs_reused, r.wall_seconds);
    const CalibrationConfidence confidence = calibration_confidence(r, c.seeds);
    std::printf("  confidence: %s\n", confidence.text.c_str());
    if (!confidence.established)
        std::fprintf(stderr, "demlab: warning: the best friction angle %.2f deg is not established against the noise over "
                             "seeds (table.md says why)\n", r.best_angle);
    std::printf("  table: %s/table.md, %s/table.csv; envelopes: %s/envelopes.png\n", opt.out.c_str(), opt.out.c_str(),
                opt.out.c_str());
    if (!o.apply.empty()) {
        char objective[160];
        std::snprintf(objective, sizeof objective, "objective %.3f deg (sum of |gamma_i - lab| over sections 3-5, mean over seeds)",
                      r.best_objective);
        const std::vector<std::string> provenance = {
            "calibration: " + o.config + ", scale " + (c.scale ? std::to_string(c.scale) : std::string("of its scenario")) + ", " +
                std::to_string(c.seeds) + " seed(s) per angle, run folder " + opt.out,
            objective, "confidence: " + confidence.text};
        std::printf("  applied: %s\n", apply_calibration(o.apply, r.best_angle, o.force, provenance).c_str());
    }
    return kExitOk;
}
}  // namespace

Command add_calibrate_command(CLI::App& app) {
    auto o = std::make_shared<CalibrateCli>();
    CLI::App* sub = app.add_subcommand("calibrate", "Dam-break friction calibration: sweep, deposit angles, best fit (Table 7)");
    sub->add_option("config", o->config, "Calibration file, e.g. calibration/dam-break.toml")->required();
    sub->add_option("--out", o->out, "Output folder (default runs/calibration); rerun with the same folder to resume");
    sub->add_option("--jobs", o->jobs, std::string("Runs at once on this machine (default: the number of cores); across machines: mpirun -n N demlab calibrate ...") +
                                           (have_mpi() ? "" : " (this build has no MPI)"))->check(CLI::Range(1, 256));
    sub->add_option("--angles", o->angles, "Friction angles to try, deg, comma-separated (default: the config's)");
    sub->add_option("--seeds", o->seeds, "Runs per angle with different seeds (the objective is their mean)")->check(CLI::Range(1, 100));
    sub->add_option("--scale", o->scale, "Upscaling of the sand (Table 14)")->check(CLI::Range(1, 100));
    sub->add_flag("--no-refine", o->no_refine, "Only the grid, no golden-section refinement");
    sub->add_option("--apply", o->apply, "Write SCENARIO-calibrated.toml with the best angle (never over the original)");
    sub->add_flag("--force", o->force, "Use a folder made for another configuration; replace an existing -calibrated file");
    return [o] { return Ranks::run_command([&] { return calibrate_command(*o); }); };
}

}  // namespace demlab
