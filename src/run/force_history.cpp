#include "run/force_history.h"

#include "dem/world.h"

namespace demlab {

void ForceHistory::open() {
    if (!enabled()) return;
    file_.open(path_);
    std::string h = "t_s";
    for (const ForceGroup& g : groups_) h += ",fx_" + g.name + "_N_per_m,fy_" + g.name + "_N_per_m";
    file_.out() << h << ",fx_total_N_per_m,fy_total_N_per_m\n";
}

void ForceHistory::step(const World& w) {
    if (!enabled() || w.step_count() % every_ != 0) return;
    std::ofstream& o = file_.out();
    o << w.time();
    // each group summed as forces.csv sums it (the first wall's value, then the others added)
    Vec2 total = Vec2::Zero();
    for (size_t g = 0; g < groups_.size(); ++g) {
        Vec2 f = Vec2::Zero();
        for (size_t k = 0; k < groups_[g].walls.size(); ++k) {
            const Vec2 v = w.wall_force(groups_[g].walls[k]);
            f = k == 0 ? v : Vec2(f + v);
        }
        total = g == 0 ? f : Vec2(total + f);
        o << ',' << f.x() << ',' << f.y();
    }
    o << ',' << total.x() << ',' << total.y() << '\n';
    if (w.step_count() % (64L * every_) == 0) file_.check();
}

void ForceHistory::save(BinaryWriter& out) { out.put(enabled() ? file_.flush() : uint64_t(0)); }

void ForceHistory::load(BinaryReader& in) {
    uint64_t size = 0;
    in.get(size);
    if (enabled()) file_.reopen(path_, size);
}

}  // namespace demlab
