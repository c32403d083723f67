// The machine's own interruptions, as a thread on each core sees them: how often a core is
// taken from a running thread (by the host of a virtual machine, or by the kernel's own
// interrupts), and for how long. A step that joins its threads every 150 us waits for the
// gaps of every core it runs on; independent runs each pay only their own
// (docs/performance.md). `demlab bench jitter` prints them.
#pragma once
#include <vector>

namespace demlab {

struct CoreGaps {
    int core = 0;         // the core the probe ran on (-1: it could not be pinned)
    long gaps = 0;        // clock readings further apart than the threshold
    double lost = 0.0;    // s, the sum of those gaps
    double longest = 0.0; // s
    double seconds = 0.0; // s, how long the probe ran
};

// One probe thread on each of `cores` cores (pinned to cores 0 .. cores-1 where the system
// allows), all started together, each reading the steady clock in a tight loop for `seconds`
// and counting the readings more than `threshold` seconds apart.
std::vector<CoreGaps> measure_gaps(int cores, double seconds, double threshold = 10e-6);

}  // namespace demlab
