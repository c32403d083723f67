// Error types. InputError: the user's input is wrong (exit code 2). RunError: a run
// failed or blew up (exit code 3). Messages always name the parameter and what is accepted.
#pragma once
#include <stdexcept>
#include <string>

namespace demlab {

struct InputError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

struct RunError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

// Exit codes of the demlab executable (documented in README.md).
enum ExitCode : int { kExitOk = 0, kExitUsage = 1, kExitInput = 2, kExitRun = 3, kExitInterrupted = 4 };

}  // namespace demlab
