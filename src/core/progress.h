// Progress of a long run on a terminal: percent of simulated time, steps/s and ETA on one
// line of stderr, refreshed at most twice a second. Silent when stderr is not a terminal.
#pragma once
#include <atomic>
#include <chrono>
#include <cstdio>
#include <unistd.h>

namespace demlab {

// Set while several runs share the terminal (calibration workers): no progress lines then.
inline std::atomic<bool> g_progress_muted{false};

class Progress {
public:
    // done0, steps0: where a resumed run starts (the rate and ETA count from there)
    // (show: false keeps it silent, for a loop whose caller shows its own)
    explicit Progress(double total, const char* unit = "s", double done0 = 0.0, long steps0 = 0, bool show = true)
        : total_(total), done0_(done0), steps0_(steps0), unit_(unit),
          enabled_(show && isatty(STDERR_FILENO) != 0 && !g_progress_muted), start_(Clock::now()), last_(start_) {}

    void update(double done, long steps) {
        if (!enabled_) return;
        const auto now = Clock::now();
        if (now - last_ < std::chrono::milliseconds(500)) return;
        last_ = now;
        const double elapsed = std::chrono::duration<double>(now - start_).count();
        const double frac = total_ > 0 ? done / total_ : 0.0;
        const double eta = done > done0_ ? elapsed * (total_ - done) / (done - done0_) : 0.0;
        std::fprintf(stderr, "\r  %5.1f %%  %.3f / %.3f %s  %.0f steps/s  ETA %.0f s   ", 100.0 * frac, done, total_, unit_,
                     elapsed > 0 ? double(steps - steps0_) / elapsed : 0.0, eta);
        std::fflush(stderr);
        shown_ = true;
    }
    void finish() {
        if (shown_) std::fprintf(stderr, "\r%*s\r", 78, "");
        shown_ = false;
    }
    ~Progress() { finish(); }

private:
    using Clock = std::chrono::steady_clock;
    double total_, done0_;
    long steps0_;
    const char* unit_;
    bool enabled_, shown_ = false;
    Clock::time_point start_, last_;
};

}  // namespace demlab
