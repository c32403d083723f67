#include "core/jitter.h"

#include <chrono>
#include <latch>
#include <thread>

#if defined(__linux__)
#include <pthread.h>
#include <sched.h>
#endif

namespace demlab {

namespace {
// pins the calling thread to `core`; false where the system does not allow it
bool pin_to(int core) {
#if defined(__linux__)
    cpu_set_t set;
    CPU_ZERO(&set);
    CPU_SET(core, &set);
    return pthread_setaffinity_np(pthread_self(), sizeof set, &set) == 0;
#else
    (void)core;
    return false;
#endif
}
}  // namespace

std::vector<CoreGaps> measure_gaps(int cores, double seconds, double threshold) {
    using Clock = std::chrono::steady_clock;
    std::vector<CoreGaps> out(static_cast<size_t>(cores));
    std::latch start(cores);
    std::vector<std::thread> probes;
    for (int c = 0; c < cores; ++c)
        probes.emplace_back([&, c] {
            CoreGaps& g = out[size_t(c)];
            g.core = pin_to(c) ? c : -1;
            start.arrive_and_wait();
            const Clock::time_point t0 = Clock::now();
            const Clock::duration limit = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
            const Clock::duration gap = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(threshold));
            Clock::time_point last = t0;
            Clock::duration lost{0}, longest{0};
            for (;;) {
                const Clock::time_point t = Clock::now();
                const Clock::duration d = t - last;
                if (d > gap) {
                    ++g.gaps;
                    lost += d;
                    if (d > longest) longest = d;
                }
                last = t;
                if (t - t0 >= limit) break;
            }
            g.lost = std::chrono::duration<double>(lost).count();
            g.longest = std::chrono::duration<double>(longest).count();
            g.seconds = std::chrono::duration<double>(last - t0).count();
        });
    for (std::thread& t : probes) t.join();
    return out;
}

}  // namespace demlab
