// Other programs (gnuplot, ffmpeg, LAMMPS) run without a shell: the program and its arguments
// as a vector, so no path, run name or option a user typed is ever parsed as a command.
#pragma once
#include <functional>
#include <string>
#include <vector>

namespace demlab {

struct ProcessDef {
    std::vector<std::string> argv;  // argv[0]: the program, looked up on PATH
    std::string cwd;                // run there (empty: the current folder)
    std::string stdin_file;         // read as standard input (empty: /dev/null)
    std::string stdout_file;        // standard output written there (empty: /dev/null, or on_line)
    std::function<void(const std::string&)> on_line;  // if set: each line of standard output, as it comes
    std::string stderr_file;        // standard error written there (empty: /dev/null)
};

// Runs the program to its end and returns its exit status (128 + the signal when a signal ended
// it); -1 when it could not be started (not installed). Never throws for the program's failure.
int run_process(const ProcessDef& def);

// Whether `program` is an executable file on PATH (or, with a slash, at that path).
bool program_available(const std::string& program);

// `text` as a gnuplot single-quoted string, where gnuplot substitutes nothing (no backquoted
// command, no `@` macro): a quote doubled, control characters (a line end would end the
// command) replaced by '_'.
std::string gnuplot_quote(const std::string& text);

// TEXT as one word a POSIX shell reads back unchanged, for a command printed for the user to
// paste (`continue with: demlab resume DIR`): as it is when it holds only characters no shell
// treats specially, else in single quotes (a quote inside as '\''); a leading '-' gets "./"
// before it, so that the word is never read as an option.
std::string shell_word(const std::string& text);

}  // namespace demlab
