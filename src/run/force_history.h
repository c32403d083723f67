// force_history.csv: the forces on the set-up's wall groups every N steps (output.force_history_steps),
// as PFC's history of a wall force is recorded, for those who want its dense curves; off by
// default (at scale 4 a flow to rest is about 10^6 steps). The columns are forces.csv's first
// ones: t_s, each group's fx and fy and the total's (N/m).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "core/binary_io.h"
#include "core/fileio.h"
#include "setups/setup.h"

namespace demlab {

class World;

class ForceHistory {
public:
    ForceHistory(std::string path, const ForceWalls& walls, int every_steps)
        : path_(std::move(path)), groups_(walls.written()), every_(every_steps) {}
    bool enabled() const { return every_ > 0; }
    void open();                  // a new file with its header
    void step(const World& w);    // after each step: a row when the step count is a multiple of N
    // checkpoints: its size now (flushed), and a resume's cut back to it
    void save(BinaryWriter& out);
    void load(BinaryReader& in);
    void close() { file_.close(); }

private:
    std::string path_;
    std::vector<ForceGroup> groups_;
    int every_;
    SeriesFile file_;
};

}  // namespace demlab
