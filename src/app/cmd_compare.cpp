// demlab compare: the comparison figures and table of several finished runs (output/compare.h).
#include <cstdio>
#include <memory>

#include "app/commands.h"
#include "core/error.h"
#include "output/compare.h"

namespace demlab {

Command add_compare_command(CLI::App& app) {
    auto o = std::make_shared<CompareOptions>();
    CLI::App* sub = app.add_subcommand(
        "compare", "Compare finished runs (DEM, DAN, models, scales): fronts, deposits, barrier forces and a landmark table");
    sub->add_option("runs", o->runs, "Run folders written by demlab run")->required();
    sub->add_option("--out", o->out, "Output folder; must not exist unless --force")->capture_default_str();
    sub->add_flag("--force", o->force, "Replace the files of an existing output folder");
    return [o] {
        const auto files = compare_runs(*o);
        std::printf("compared %zu runs into %s/:", o->runs.size(), o->out.c_str());
        for (const std::string& f : files) std::printf(" %s", f.substr(o->out.size() + 1).c_str());
        std::printf("\n");
        return kExitOk;
    };
}

}  // namespace demlab
