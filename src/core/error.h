// Error types. InputError: the user's input is wrong (exit code 2). RunError: a run
// failed or blew up (exit code 3). WriteError: an output file could not be written whole (a
// full disk, a file size limit, a folder gone; exit code 5). Messages always name the
// parameter or file and what is accepted.
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

// (a RunError, so a caller that stops on any failed run stops on it too)
struct WriteError : RunError {
    using RunError::RunError;
};

// Exit codes of the demlab executable (documented in README.md).
enum ExitCode : int { kExitOk = 0, kExitUsage = 1, kExitInput = 2, kExitRun = 3, kExitInterrupted = 4, kExitWrite = 5 };

}  // namespace demlab
