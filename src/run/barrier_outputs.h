// The outputs engineers size barriers and map hazards with, for every run with a bed path:
//   barrier_pressure.csv  at each series sample, the normal pressure of the discs on the
//                         barrier in equal bins along it from its lower end (Pa, per metre of
//                         width; round(length / output.pressure_bin) bins). Each bin's
//                         pressure times its length, summed, is the barrier's normal force.
//   peaks.csv             per output.deposit_bin of the path, over the run: the largest flow
//                         height normal to the bed, the largest mean speed of the discs in
//                         the bin, and the largest normal pressure on the bed.
// The loads are the disc-wall contacts' own (World::wall_loads), binned by where each disc
// touches. Every disc counts for the heights and speeds, a block thrown ahead of the mass
// too (what reaches a place matters for a hazard map; the front and the deposit leave such
// discs out).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "core/binary_io.h"
#include "core/fileio.h"
#include "dem/world.h"
#include "run/measures.h"

namespace demlab {

class BarrierOutputs {
public:
    // walls: the world's walls (their geometry); m: the run's measurement context (the path,
    // the barrier's and the bed's walls)
    BarrierOutputs(std::string dir, const World& w, const MeasureContext& m);
    bool has_barrier() const { return enabled_ && !segments_.empty(); }
    void open();                        // a new barrier_pressure.csv with its header
    void reopen(uint64_t size);         // a resumed run's, cut back to this size
    uint64_t flush();                   // its size now
    void sample(const World& w, double t);
    void finish(RunSummary& sum);       // peaks.csv, the barrier file closed, its peak into the summary
    // checkpoints: the barrier file's size and the peaks so far; a checkpoint of an earlier
    // build has none (disable: the run resumes without these two files)
    void save(BinaryWriter& out);
    void load(BinaryReader& in);
    void disable() { enabled_ = false; }

    // the pressure bins' length along the barrier, m, and their count
    double bin_length() const { return bin_length_; }
    size_t bins() const { return pressure_.size(); }

private:
    struct Segment {
        int wall;
        Vec2 p0, p1;       // m, from the barrier's lower end
        Vec2 normal;       // unit, pointing out of the barrier towards the flow
        double s0, length; // m, where it starts along the barrier, and its length
    };
    std::string dir_;
    const MeasureContext& m_;
    bool enabled_ = true;
    std::vector<Segment> segments_;
    std::vector<uint8_t> bed_wall_;     // per wall: part of the bed (slope, arc, barrier)
    double bin_length_ = 0, path_bin_ = 0;
    std::vector<double> pressure_;      // Pa, this sample
    std::vector<double> peak_height_, peak_speed_, peak_pressure_;  // m, m/s, Pa per path bin
    double peak_barrier_pressure_ = 0, s_peak_barrier_pressure_ = -1, t_peak_barrier_pressure_ = -1;
    std::vector<World::WallLoad> loads_;
    SeriesFile file_;
};

}  // namespace demlab
