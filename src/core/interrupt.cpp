#include "core/interrupt.h"

#include <csignal>
#include <cstdint>
#include <ctime>

namespace demlab {

namespace {
std::atomic<int> g_signal{0};
// when the first signal arrived (CLOCK_MONOTONIC, ns; 0: none yet)
std::atomic<int64_t> g_first_ns{0};
static_assert(std::atomic<int>::is_always_lock_free && std::atomic<int64_t>::is_always_lock_free,
              "the signal handler needs lock-free flags");

// A repeat this soon after the first signal is the same request delivered twice, not a second
// Ctrl-C: `timeout`, for one, signals the command and then its whole process group, and a
// process can receive both. Re-arming the default action at the first signal let the copy end
// 3 runs in 60 (timeout -s INT, 2 threads) without their checkpoint or a word. A person's second
// Ctrl-C comes later than this.
constexpr int64_t kSameRequestNs = 500'000'000;

int64_t monotonic_ns() {  // clock_gettime is async-signal-safe (POSIX)
    timespec ts{};
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return int64_t(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

extern "C" void on_signal(int signal_number) {
    const int64_t now = monotonic_ns();
    int none = 0;
    if (g_signal.compare_exchange_strong(none, signal_number)) {
        g_first_ns.store(now);
        return;
    }
    // (0: the first handler, on another thread, has not stored its time yet: the same request)
    const int64_t first = g_first_ns.load();
    if (first == 0 || now - first < kSameRequestNs) return;
    std::signal(signal_number, SIG_DFL);  // a second request: end the process at once
    std::raise(signal_number);            // (blocked while this handler runs, delivered after)
}
}  // namespace

int pending_interrupt() { return g_signal.load(std::memory_order_relaxed); }
void request_interrupt(int signal_number) {
    g_first_ns.store(monotonic_ns());
    g_signal.store(signal_number);
}
void clear_interrupt() {
    g_signal.store(0);
    g_first_ns.store(0);
}

InterruptScope::InterruptScope() {
    clear_interrupt();
    previous_[0] = std::signal(SIGINT, on_signal);
    previous_[1] = std::signal(SIGTERM, on_signal);
    // a closed terminal or SSH connection: checkpoint and stop, as for SIGTERM
    previous_[2] = std::signal(SIGHUP, on_signal);
}

InterruptScope::~InterruptScope() {
    std::signal(SIGINT, previous_[0]);
    std::signal(SIGTERM, previous_[1]);
    std::signal(SIGHUP, previous_[2]);
    clear_interrupt();  // handled: the next run in this process starts afresh
}

}  // namespace demlab
