#include "core/process.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <sstream>

namespace demlab {

namespace {

// The executable `program` names: itself when it has a slash, else the first on PATH ("" if none).
std::string find_program(const std::string& program) {
    if (program.empty()) return "";
    if (program.find('/') != std::string::npos) return ::access(program.c_str(), X_OK) == 0 ? program : "";
    const char* path = std::getenv("PATH");
    std::istringstream dirs(path ? path : "/usr/local/bin:/usr/bin:/bin");
    std::string d;
    while (std::getline(dirs, d, ':')) {
        const std::string f = (d.empty() ? "." : d) + "/" + program;
        struct stat st {};
        if (::stat(f.c_str(), &st) == 0 && S_ISREG(st.st_mode) && ::access(f.c_str(), X_OK) == 0) return f;
    }
    return "";
}

}  // namespace

bool program_available(const std::string& program) { return !find_program(program).empty(); }

int run_process(const ProcessDef& def) {
    // the program's file found before the fork: the child only opens, duplicates and executes
    const std::string exe = def.argv.empty() ? std::string() : find_program(def.argv[0]);
    if (exe.empty()) return -1;
    std::vector<char*> args;
    for (const std::string& a : def.argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    // everything the child needs is prepared before fork (no allocation between fork and exec)
    const char* in = def.stdin_file.empty() ? "/dev/null" : def.stdin_file.c_str();
    const char* out = def.stdout_file.empty() ? "/dev/null" : def.stdout_file.c_str();
    const char* err = def.stderr_file.empty() ? "/dev/null" : def.stderr_file.c_str();
    const char* cwd = def.cwd.empty() ? nullptr : def.cwd.c_str();
    int pipe_fd[2] = {-1, -1};
    if (def.on_line && ::pipe2(pipe_fd, O_CLOEXEC) != 0) return -1;
    const pid_t pid = ::fork();
    if (pid < 0) {
        if (pipe_fd[0] >= 0) ::close(pipe_fd[0]), ::close(pipe_fd[1]);
        return -1;
    }
    if (pid == 0) {
        const auto redirect = [](const char* file, int flags, int fd) {
            const int f = ::open(file, flags | O_CLOEXEC, 0644);
            if (f < 0 || ::dup2(f, fd) < 0) ::_exit(127);
            ::close(f);
        };
        // (the files are named relative to the caller's folder: opened before the chdir)
        redirect(in, O_RDONLY, 0);
        // (an output file's name that is a symbolic link is refused, not written through)
        if (pipe_fd[1] >= 0) {
            if (::dup2(pipe_fd[1], 1) < 0) ::_exit(127);
        } else {
            redirect(out, O_WRONLY | O_CREAT | O_TRUNC | O_NOFOLLOW, 1);
        }
        if (pipe_fd[1] >= 0 && def.stderr_file.empty()) {
            if (::dup2(pipe_fd[1], 2) < 0) ::_exit(127);
        } else {
            redirect(err, O_WRONLY | O_CREAT | O_TRUNC | O_NOFOLLOW, 2);
        }
        if (cwd && ::chdir(cwd) != 0) ::_exit(127);
        ::execv(exe.c_str(), args.data());
        ::_exit(127);
    }
    if (pipe_fd[0] >= 0) {
        ::close(pipe_fd[1]);
        std::string line;
        char buf[4096];
        for (;;) {
            const ssize_t got = ::read(pipe_fd[0], buf, sizeof buf);
            if (got < 0 && errno == EINTR) continue;
            if (got <= 0) break;
            for (ssize_t i = 0; i < got; ++i) {
                line += buf[i];
                if (buf[i] == '\n') {
                    def.on_line(line);
                    line.clear();
                }
            }
        }
        if (!line.empty()) def.on_line(line);
        ::close(pipe_fd[0]);
    }
    int status = 0;
    while (::waitpid(pid, &status, 0) < 0)
        if (errno != EINTR) return -1;
    if (WIFEXITED(status)) return WEXITSTATUS(status);
    if (WIFSIGNALED(status)) return 128 + WTERMSIG(status);
    return -1;
}

std::string shell_word(const std::string& text) {
    const std::string word = !text.empty() && text[0] == '-' ? "./" + text : text;
    bool plain = !word.empty();
    for (const char c : word)
        plain = plain && c != '\0' && (std::isalnum(static_cast<unsigned char>(c)) || std::strchr("_./+,:=@%-", c) != nullptr);
    if (plain) return word;
    std::string o = "'";
    for (const char c : word) o += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return o + "'";
}

std::string gnuplot_quote(const std::string& text) {
    std::string o = "'";
    for (const char c : text) {
        const unsigned char u = static_cast<unsigned char>(c);
        if (c == '\'') o += "''";
        else if (u < 0x20 || u == 0x7f) o += '_';
        else o += c;
    }
    return o + "'";
}

}  // namespace demlab
