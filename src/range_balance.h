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

// Whether the pass would have gone faster as one range over the last window: the ranges
// worked `busy` seconds in all, in passes of `wall` seconds on `r` threads. With the work cut
// in r parts, r ranges take (work / r) / share of the time one range takes, share =
// busy / (r wall); below 1 / r they are slower than one range. On an idle machine the share
// is about 0.95 (DB-9k, geometry A, 2 threads). It falls when another process takes a core:
// the operating system then stops one range for a time slice of milliseconds while the other
// waits at the join (DB-9k on 2 threads beside a compiler: 13 %, three times slower than 1
// thread; docs/performance.md, session 12).
inline bool one_range_would_be_faster(double busy, double wall, size_t r) {
    return r > 1 && wall > 0.0 && busy / (double(r) * wall) < 1.0 / double(r);
}

}  // namespace demlab
