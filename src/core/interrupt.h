// SIGINT, SIGTERM and SIGHUP during a run: the handler only records the signal; the run loop sees it
// at the end of the step, writes a final checkpoint and throws Interrupted, which the
// executable turns into exit code 4 (kExitInterrupted) with the command that resumes.
// A second signal ends the process at once, unless it comes within half a second of the first:
// then it is the same request delivered twice (a process group's kill) and is ignored.
#pragma once
#include <atomic>
#include <stdexcept>
#include <string>

namespace demlab {

struct Interrupted : std::runtime_error {
    using std::runtime_error::runtime_error;
};

// 0, or the number of the signal that asked the run to stop
int pending_interrupt();
// As if the signal had arrived (tests; also used by the handler)
void request_interrupt(int signal_number);
void clear_interrupt();

// Installs the handlers for the lifetime of the object and restores the previous ones after.
class InterruptScope {
public:
    InterruptScope();
    ~InterruptScope();
    InterruptScope(const InterruptScope&) = delete;
    InterruptScope& operator=(const InterruptScope&) = delete;

private:
    using Handler = void (*)(int);
    Handler previous_[3];  // SIGINT, SIGTERM, SIGHUP
};

}  // namespace demlab
