// demlab sweep SWEEP.toml: a scenario over a table of overrides and seeds (calibration/sweep.h).
#include <cstdio>
#include <memory>
#include <string>

#include "app/commands.h"
#include "calibration/ranks.h"
#include "calibration/sweep.h"
#include "core/error.h"

namespace demlab {

namespace {
struct SweepCli {
    std::string file;
    std::string out = "runs/sweep";  // (an --out '' given is refused, not taken for the default)
    int jobs = 0;
    bool force = false;
};

int sweep_command(const SweepCli& o) {
    const SweepConfig c = load_sweep(o.file);
    SweepOptions opt;
    opt.out = o.out;
    opt.jobs = o.jobs;
    opt.force = o.force;
    const Ranks& ranks = Ranks::world();
    if (ranks.size() > 1) std::printf("rank %d of %d: ", ranks.rank(), ranks.size());
    std::printf("sweep: %zu row(s) x %d seed(s) of %s\n", c.rows.size(), c.seeds, c.scenario.c_str());
    const SweepResult r = run_sweep(c, opt);
    if (!ranks.root()) return kExitOk;
    std::printf("%d new run(s), %d reused, %.0f s; table: %s/sweep.csv (wall times: timings.csv)\n", r.runs_done,
                r.runs_reused, r.wall_seconds, opt.out.c_str());
    return kExitOk;
}
}  // namespace

Command add_sweep_command(CLI::App& app) {
    auto o = std::make_shared<SweepCli>();
    CLI::App* sub = app.add_subcommand("sweep", "Run a scenario over a grid or table of overrides and seeds; sweep.csv gathers the summaries");
    sub->add_option("sweep", o->file, "Sweep file (TOML: [sweep] scenario, seeds, set; [grid] or [[rows]])")->required();
    sub->add_option("--out", o->out, "Output folder (default runs/sweep); rerun with the same folder to resume");
    sub->add_option("--jobs", o->jobs, std::string("Runs at once on this machine (default: the number of cores); across machines: mpirun -n N demlab sweep ...") +
                                           (have_mpi() ? "" : " (this build has no MPI)"))
        ->check(CLI::Range(1, 256));
    sub->add_flag("--force", o->force, "Use a folder made for another sweep");
    return [o] { return Ranks::run_command([&] { return sweep_command(*o); }); };
}

}  // namespace demlab
