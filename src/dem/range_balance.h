// The force pass's measured balancing (World::balance_force_pass) as a small pure function:
// given each range's target share of the work model and the time it took over the last
// window, move the shares halfway towards the ranges' measured speeds.
#pragma once
#include <algorithm>
#include <cstddef>

namespace demlab {

// share[t]: range t's target share (they sum to 1); seconds(t): its time over the window, s.
// When the longest time is more than `tolerance` above the mean, each share becomes
//     0.5 share + 0.5 speed / sum(speed),   speed = share / seconds
// (the share that would have made the times equal, damped by half against noise) and the
// function returns true; otherwise it leaves the shares alone and returns false.
template <typename Seconds>
bool rebalance_shares(double* share, Seconds seconds, size_t r, double tolerance) {
    if (r < 2) return false;
    double sum = 0.0, longest = 0.0;
    for (size_t t = 0; t < r; ++t) {
        sum += seconds(t);
        longest = std::max(longest, seconds(t));
    }
    const double mean = sum / double(r);
    if (!(mean > 0.0) || longest <= (1.0 + tolerance) * mean) return false;
    auto speed = [&](size_t t) { return share[t] / std::max(seconds(t), 1e-12); };
    double norm = 0.0;
    for (size_t t = 0; t < r; ++t) norm += speed(t);
    // norm is taken from the old shares; each new share needs only its own old one
    for (size_t t = 0; t < r; ++t) share[t] = 0.5 * share[t] + 0.5 * speed(t) / norm;
    return true;
}

// Whether the pass would have gone faster as one range over the last window: the r ranges
// worked `busy` seconds in all, in passes of `wall` seconds. One range does the same work in
// about `busy` seconds (the ranges split it without loss: docs/performance.md), so
// it is faster when busy < wall, i.e. when the ranges worked less than 1 / r of the threads'
// time (r wall). On an idle machine they work about 0.95 of it (DB-9k, geometry A, 2 threads).
// It falls when another process takes a core: the operating system then stops one range for
// a time slice of milliseconds while the other waits at the join (DB-9k on 2 threads beside a
// compiler: 0.13, three times slower than 1 thread).
inline bool one_range_would_be_faster(double busy, double wall, size_t r) { return r > 1 && busy < wall; }

// The decision to fall back to one range (World::balance_force_pass): after kWindows
// balancing windows in a row in which one range would have been faster. One window is not
// enough: on an idle machine a window now and then has a core stopped for a few milliseconds
// (one DB-9k run in seven fell back once), while a core taken by another process slows every
// window.
struct BusyWatch {
    static constexpr int kWindows = 3;
    int slow = 0;  // windows in a row so far
    // one window's figures; true when the pass should now run as one range (and starts counting again)
    bool window(double busy, double wall, size_t r) {
        slow = one_range_would_be_faster(busy, wall, r) ? slow + 1 : 0;
        if (slow < kWindows) return false;
        slow = 0;
        return true;
    }
};

}  // namespace demlab
