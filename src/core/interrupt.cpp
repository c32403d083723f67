#include "core/interrupt.h"

#include <csignal>

namespace demlab {

namespace {
std::atomic<int> g_signal{0};
static_assert(std::atomic<int>::is_always_lock_free, "the signal handler needs a lock-free flag");

extern "C" void on_signal(int signal_number) {
    g_signal.store(signal_number, std::memory_order_relaxed);
    std::signal(signal_number, SIG_DFL);  // a second Ctrl-C ends the process
}
}  // namespace

int pending_interrupt() { return g_signal.load(std::memory_order_relaxed); }
void request_interrupt(int signal_number) { g_signal.store(signal_number, std::memory_order_relaxed); }
void clear_interrupt() { g_signal.store(0, std::memory_order_relaxed); }

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
