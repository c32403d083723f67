// `demlab compare RUN_DIR RUN_DIR... [--out DIR]`: the thesis' comparison figures for any set of
// finished runs (DEM and DAN, models, scales): the front's position over time (DAN's
// time-synchronised front too, when it has one), the final deposits over the flume (or along
// the bed path for other set-ups), the barrier's force histories, and a table of the landmarks
// (comparison.md, comparison.csv). Each PNG has a legend naming the runs.
#pragma once
#include <string>
#include <vector>

namespace demlab {

struct CompareOptions {
    std::vector<std::string> runs;
    std::string out = "runs/compare";
    bool force = false;
};

// Returns the files written. Throws InputError for a folder that is not a finished run (before
// anything is written), RunError when gnuplot is missing or fails.
std::vector<std::string> compare_runs(const CompareOptions& o);

}  // namespace demlab
