// Checkpoint and resume: a run stopped by a signal, or killed outright, and resumed gives the
// same bytes as a run never stopped; a killed run leaves only complete files under their
// final names. Geometry A at scale 20 (364 discs) to t = 1.2 s: past the barrier impact.
#include <gtest/gtest.h>
#include <fcntl.h>
#include <sys/file.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "core/crc32c.h"
#include "core/error.h"
#include "files.h"
#include "resume.h"
#include "core/interrupt.h"
#include "core/output_dir.h"
#include "run/run.h"
#include "run/series_columns.h"
#include "scenario/scenario.h"

extern char** environ;

using namespace demlab;
using demlab::test::read_file;
using demlab::test::temp_dir;
namespace fs = std::filesystem;

namespace {
const std::vector<std::string> kOverrides = {"release.scale=20", "stop.t_max=1.2", "output.snapshot_interval=0.2",
                                             "output.track=[5, 200]", "output.force_history_steps=50"};

Scenario scenario(const std::vector<std::string>& more = {}) {
    Scenario s = load_scenario(std::string(DEMLAB_SOURCE_DIR) + "/scenarios/geometry-A.toml");
    for (const std::string& a : kOverrides) apply_override(s, a);
    for (const std::string& a : more) apply_override(s, a);
    finish_scenario(s);
    return s;
}

// summary.json without the wall-clock figures (they differ between any two runs)
std::string summary_without_timing(const fs::path& p) {
    std::istringstream in(read_file(p));
    std::string line, out;
    while (std::getline(in, line))
        // timing, the broad phase's figures, the threads' balance and the machine are of the
        // process that ran them (the resume rebuilds the lists, and may run on another processor)
        if (line.find("wall_seconds") == std::string::npos && line.find("particle_steps_per_second") == std::string::npos &&
            line.find("broadphase_") == std::string::npos && line.find("force_pass_busy_") == std::string::npos &&
            line.find("\"machine\"") == std::string::npos)
            out += line + '\n';
    return out;
}

void expect_same_outputs(const fs::path& a, const fs::path& b) {
    for (const char* f : {"forces.csv", "front.csv", "energy.csv", "track.csv", "deposit.csv", "surface.csv", "release.csv", "barrier_pressure.csv", "peaks.csv",
                          "force_history.csv",
                          "snapshots/discs.pvd", "snapshots/walls.pvd"}) {
        ASSERT_TRUE(fs::exists(a / f)) << f;
        EXPECT_EQ(read_file(a / f), read_file(b / f)) << f << " differs";
    }
    int snapshots = 0;
    for (const auto& e : fs::directory_iterator(a / "snapshots")) {
        EXPECT_EQ(read_file(e.path()), read_file(b / "snapshots" / e.path().filename())) << e.path().filename();
        ++snapshots;
    }
    EXPECT_GE(snapshots, 14);  // 7 instants, discs and walls, plus the two series
    EXPECT_EQ(summary_without_timing(a / "summary.json"), summary_without_timing(b / "summary.json"));
    EXPECT_FALSE(fs::exists(b / kCheckpointFile)) << "a finished run keeps no checkpoint";
}

// Runs the demlab executable; returns its pid.
pid_t spawn(const std::vector<std::string>& args) {
    std::vector<char*> argv;
    std::string exe = DEMLAB_EXE;
    argv.push_back(exe.data());
    std::vector<std::string> copy = args;
    for (std::string& a : copy) argv.push_back(a.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_addopen(&fa, 1, "/dev/null", O_WRONLY, 0);
    posix_spawn_file_actions_addopen(&fa, 2, "/dev/null", O_WRONLY, 0);
    pid_t pid = -1;
    EXPECT_EQ(posix_spawn(&pid, exe.c_str(), &fa, nullptr, argv.data(), environ), 0);
    posix_spawn_file_actions_destroy(&fa);
    return pid;
}

// exit code, or 128 + signal
int wait_for(pid_t pid) {
    int status = 0;
    waitpid(pid, &status, 0);
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

std::vector<std::string> run_args(const fs::path& out) {
    std::vector<std::string> a = {"run", std::string(DEMLAB_SOURCE_DIR) + "/scenarios/geometry-A.toml", "--out",
                                  out.string(), "--no-plots"};
    for (const std::string& o : kOverrides) {
        a.push_back("--set");
        a.push_back(o);
    }
    return a;
}

// Waits until the run folder holds a checkpoint (the flow phase has begun).
bool wait_for_checkpoint(const fs::path& dir, pid_t pid) {
    for (int k = 0; k < 6000; ++k) {  // 10 min under the sanitizers at worst
        if (fs::exists(dir / kCheckpointFile)) return true;
        int status;
        if (waitpid(pid, &status, WNOHANG) == pid) return false;
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    return false;
}
}  // namespace

// In-process: a signal (simulated by request_interrupt, as the handler does) at the third
// snapshot; the series files then get bytes a killed run could have written after the
// checkpoint; the resume (asked for 2 threads; 364 discs stay below the pool's parallel
// threshold, so this checks the option, not the gather) must cut them off and match.
TEST(Checkpoint, ResumedRunIsByteIdentical) {
    const Scenario s = scenario();
    const fs::path ref = temp_dir("ck-ref"), cut = temp_dir("ck-cut");
    run_scenario(s, {ref.string(), false, {}});

    RunOptions ro{cut.string(), false, [](const std::string&, const std::string&, int index) {
                      if (index == 2) request_interrupt(SIGTERM);
                  }};
    ro.handle_signals = true;
    EXPECT_THROW(run_scenario(s, ro), Interrupted);
    ASSERT_TRUE(fs::exists(cut / kCheckpointFile));
    const CheckpointInfo info = read_checkpoint_info(cut.string());
    EXPECT_NEAR(info.time, 0.4, 1e-4);
    EXPECT_FALSE(fs::exists(cut / "forces.csv")) << "an unfinished series keeps its .part name";
    EXPECT_FALSE(fs::exists(cut / "summary.json"));
    for (const char* f : {"forces.csv.part", "energy.csv.part", "track.csv.part", "force_history.csv.part"}) {
        std::ofstream junk(cut / f, std::ios::app);
        junk << "9.99,written after the checkpoint by a run that was then killed\n";
    }

    const RunSummary r = demlab::test::resume_run(cut, 2);
    EXPECT_NEAR(r.t_end, 1.2, 1e-4);
    expect_same_outputs(ref, cut);
    fs::remove_all(ref);
    fs::remove_all(cut);
}

// A run folder whose scenario.toml holds a relative release.from_file, as builds before the key
// was taken from the scenario's folder wrote it (they read it from the working directory): the
// resume from that directory reads the same mass and continues to the bytes of a run started
// from it today; from another directory it is refused, saying where to resume from.
TEST(Checkpoint, AFolderWithARelativeReleaseFromAnEarlierBuildResumes) {
    const fs::path work = temp_dir("ck-legacy"), ref = work / "ref", cut = work / "cut";
    fs::create_directories(work / "rel");
    const fs::path first = work / "first";
    run_scenario(scenario({"stop.t_max=0.01", "stop.rest_duration=0.005"}), {first.string(), false, {}});
    fs::copy_file(first / "release.csv", work / "rel/release.csv");
    const fs::path cwd = fs::current_path();
    fs::current_path(work);
    // the run never stopped reads the mass by its absolute path, as today's build holds it (the
    // scenario's fingerprint names the path: the resumed run's is then this one's)
    Scenario s = scenario();
    s.release.from_file = (work / "rel/release.csv").lexically_normal().string();
    run_scenario(s, {ref.string(), false, {}});
    s.release.from_file = "rel/release.csv";  // as the earlier build held it
    RunOptions ro{cut.string(), false, [](const std::string&, const std::string&, int index) {
                      if (index == 2) request_interrupt(SIGTERM);
                  }};
    ro.handle_signals = true;
    EXPECT_THROW(run_scenario(s, ro), Interrupted);
    ASSERT_NE(read_file(cut / "scenario.toml").find("from_file = \"rel/release.csv\""), std::string::npos);
    fs::current_path(cwd);
    try {
        demlab::test::resume_run(cut, 1);
        ADD_FAILURE() << "resumed from a directory without rel/release.csv";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("resume from the directory the run was started in"), std::string::npos) << e.what();
    }
    fs::current_path(work);
    const RunSummary r = demlab::test::resume_run(cut, 1);
    fs::current_path(cwd);
    EXPECT_NEAR(r.t_end, 1.2, 1e-4);
    expect_same_outputs(ref, cut);
    fs::remove_all(work);
}

// A forced run interrupted keeps the old folder aside (nothing lost while the new one is
// unfinished); resumed to its end, the new run removes that folder, and no other: a folder the
// user named like it stays. The resume removes the temporary files demlab's writers leave, not
// a user's.
TEST(Checkpoint, AForcedRunResumedRemovesTheFolderItMovedAside) {
    const Scenario s = scenario();
    const fs::path dir = temp_dir("ck-force-aside");
    run_scenario(s, {dir.string(), false, {}});
    const std::string old_summary = demlab::test::read_file(dir / "summary.json");
    RunOptions ro{dir.string(), true, [](const std::string&, const std::string&, int index) {
                      if (index == 1) request_interrupt(SIGTERM);
                  }};
    ro.handle_signals = true;
    EXPECT_THROW(run_scenario(s, ro), Interrupted);
    const fs::path aside = replaced_output_dir(dir.string());
    EXPECT_EQ(demlab::test::read_file(aside / "summary.json"), old_summary);
    const fs::path users = dir.string() + ".replaced-2";
    fs::copy(aside, users, fs::copy_options::recursive);
    // a write the interrupt cut (its temporary file) goes on resume; a user's own .tmp stays
    std::ofstream(dir / "summary.json.tmp") << "{";
    fs::create_directories(dir / "analysis");
    std::ofstream(dir / "analysis/model.tmp") << "mine";
    std::ofstream(dir / "snapshots/notes.tmp") << "mine";
    demlab::test::resume_run(dir, 1);
    EXPECT_FALSE(fs::exists(dir / "summary.json.tmp"));
    EXPECT_TRUE(fs::exists(dir / "analysis/model.tmp"));
    EXPECT_TRUE(fs::exists(dir / "snapshots/notes.tmp"));
    fs::remove_all(dir / "analysis");
    fs::remove(dir / "snapshots/notes.tmp");
    EXPECT_FALSE(fs::exists(aside)) << "the folder the forced run moved aside stayed";
    EXPECT_EQ(demlab::test::read_file(users / "summary.json"), old_summary) << "a folder it did not move went";
    fs::remove_all(dir);
    fs::remove_all(users);
}

// The same with the discs renumbered in space order every 2,000 steps (world.space_order = on;
// geometry A at scale 20 is below auto's threshold): the checkpoint falls between two
// renumberings, holds the discs' order, and the resume renumbers at the same steps.
TEST(Checkpoint, RenumberedRunResumesToTheSameBytes) {
    const Scenario s = scenario({"world.space_order=on", "world.space_order_steps=2000"});
    const fs::path ref = temp_dir("ck-order-ref"), cut = temp_dir("ck-order-cut");
    const RunSummary whole = run_scenario(s, {ref.string(), false, {}});
    EXPECT_GT(whole.space_orderings, 10);
    RunOptions ro{cut.string(), false, [](const std::string&, const std::string&, int index) {
                      if (index == 2) request_interrupt(SIGTERM);
                  }};
    ro.handle_signals = true;
    EXPECT_THROW(run_scenario(s, ro), Interrupted);
    ASSERT_TRUE(fs::exists(cut / kCheckpointFile));
    const RunSummary r = demlab::test::resume_run(cut, 2);
    EXPECT_EQ(r.space_orderings, whole.space_orderings);
    expect_same_outputs(ref, cut);
    fs::remove_all(ref);
    fs::remove_all(cut);
}

// The same with the DEBRIS law (no contact history; its state is the positions, the velocities
// of the half step and the two last steps, which set the forces' weights and the next step):
// the Attabad-like section to 6 s, interrupted at 2 s, resumed on 2 threads (the thread count
// is not part of the state; 1,489 discs are below the pool's 4,096, so the pass itself stays
// one range: Debris.Determinism covers the ranges), every file of the run folder the same bytes.
TEST(Checkpoint, DebrisRunResumesToTheSameBytes) {
    auto make = [] {
        Scenario s = load_scenario(std::string(DEMLAB_SOURCE_DIR) + "/scenarios/attabad-2d.toml");
        for (const char* o : {"stop.t_max=6", "output.snapshot_interval=1", "output.series_interval=0.1"}) apply_override(s, o);
        finish_scenario(s);
        return s;
    };
    const fs::path ref = temp_dir("ck-debris-ref"), cut = temp_dir("ck-debris-cut");
    run_scenario(make(), {ref.string(), false, {}});
    RunOptions ro{cut.string(), false, [](const std::string&, const std::string&, int index) {
                      if (index == 2) request_interrupt(SIGTERM);
                  }};
    ro.handle_signals = true;
    EXPECT_THROW(run_scenario(make(), ro), Interrupted);
    ASSERT_TRUE(fs::exists(cut / kCheckpointFile));
    EXPECT_NEAR(read_checkpoint_info(cut.string()).time, 2.0, 0.01);
    demlab::test::resume_run(cut, 2);
    int files = 0;
    for (const auto& e : fs::recursive_directory_iterator(ref)) {
        if (!e.is_regular_file()) continue;
        const fs::path rel = fs::relative(e.path(), ref);
        if (rel.begin()->string() == "plots") continue;  // drawn from the series compared here
        ASSERT_TRUE(fs::exists(cut / rel)) << rel;
        if (rel == "summary.json")
            EXPECT_EQ(summary_without_timing(e.path()), summary_without_timing(cut / rel));
        else
            EXPECT_TRUE(read_file(e.path()) == read_file(cut / rel)) << rel << " differs";  // not printed: binary
        ++files;
    }
    EXPECT_GE(files, 12);  // the series, the deposit, the summary and 7 snapshots
    EXPECT_FALSE(fs::exists(cut / kCheckpointFile));
    fs::remove_all(ref);
    fs::remove_all(cut);
}

// A resume is refused with a clear message when its scenario was edited, or when the
// checkpoint was cut short (a full disk, a copy that did not finish) or has a flipped byte.
TEST(Checkpoint, EditedScenarioAndTruncatedCheckpointAreRefused) {
    Scenario s = scenario();
    const fs::path dir = temp_dir("ck-edit");
    RunOptions ro{dir.string(), false, [](const std::string&, const std::string&, int index) {
                      if (index == 1) request_interrupt(SIGINT);
                  }};
    ro.handle_signals = true;
    EXPECT_THROW(run_scenario(s, ro), Interrupted);
    RunOptions rr{dir.string(), false, {}};
    rr.resume = true;
    auto expect_refused = [&](const Scenario& sc, const std::string& message) {
        try {
            run_scenario(sc, rr);
            FAIL() << "resumed; expected: " << message;
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
        }
    };
    {
        SCOPED_TRACE("truncated");
        const fs::path ck = dir / kCheckpointFile;
        const std::string whole = read_file(ck);
        std::ofstream(ck, std::ios::binary | std::ios::trunc) << whole.substr(0, whole.size() / 2);
        expect_refused(s, "corrupt checkpoint");
        std::ofstream(ck, std::ios::binary | std::ios::trunc) << whole;
    }
    {
        // one flipped bit in the middle (a disc's state), in the world's tail, in the checksum
        // itself: refused before anything is restored, naming the file
        SCOPED_TRACE("flipped");
        const fs::path ck = dir / kCheckpointFile;
        const std::string whole = read_file(ck);
        for (const size_t at : {whole.size() / 2, whole.size() - 40, whole.size() - 2}) {
            std::string bad = whole;
            bad[at] = char(bad[at] ^ 0x10);
            std::ofstream(ck, std::ios::binary | std::ios::trunc) << bad;
            expect_refused(s, "CRC-32C does not match");
            EXPECT_THROW(read_checkpoint_info(dir.string()), InputError);
        }
        std::ofstream(ck, std::ios::binary | std::ios::trunc) << whole;
        EXPECT_NO_THROW(read_checkpoint_info(dir.string()));
    }
    {
        // a forces.csv begun by an earlier build with other columns (the 21 before the
        // every-step extremes): this build's rows would not match its header
        SCOPED_TRACE("earlier forces.csv");
        const fs::path part = dir / "forces.csv.part";
        const std::string whole = read_file(part);
        std::ofstream(part, std::ios::binary | std::ios::trunc) << kForcesColumns << whole.substr(whole.find('\n'));
        expect_refused(s, "begun by an earlier build with other columns (21, this build writes 39)");
        std::ofstream(part, std::ios::binary | std::ios::trunc) << whole;
    }
    {
        SCOPED_TRACE("edited");
        Scenario edited = s;
        apply_override(edited, "material.friction_disc_deg=20");
        finish_scenario(edited);
        expect_refused(edited, "differs from the scenario the checkpoint was written with");
    }
    fs::remove_all(dir);
}

// A checkpoint written by an earlier build holds its resolved scenario without the keys
// added since. Resolved again by this build (with their defaults) it is the same scenario and
// resumes; an edited value, or a key this build does not read, is not.
TEST(Checkpoint, ScenarioFromAnEarlierBuildIsTheSameScenario) {
    const Scenario s = scenario();
    const std::string now = resolved_toml(s);
    EXPECT_TRUE(same_scenario(now, now));
    // an earlier build's text: without release.space_order (a key added after the first checkpoints were written)
    const std::string key = "space_order = \"auto\"\n";
    const size_t at = now.find(key);
    ASSERT_NE(at, std::string::npos) << now;
    std::string earlier = now;
    earlier.erase(at, key.size());
    EXPECT_TRUE(same_scenario(earlier, now));
    // the same key with another value, another friction, or an unknown key: not the same
    std::string other = now;
    other.replace(at, key.size(), "space_order = \"on\"\n");
    EXPECT_FALSE(same_scenario(other, now));
    Scenario edited = s;
    apply_override(edited, "material.friction_disc_deg=20");
    finish_scenario(edited);
    EXPECT_FALSE(same_scenario(resolved_toml(edited), now));
    std::string unknown = now;
    unknown.insert(at, "no_such_key = 1\n");
    EXPECT_FALSE(same_scenario(unknown, now));
}

// The executable, killed with SIGKILL (no chance to clean up) and stopped with SIGTERM:
// only complete files under final names, exit code 4 for the signal, and `demlab resume`
// finishes both to the bytes of an uninterrupted run.
TEST(Checkpoint, KilledAndSignalledProcessesResumeToTheSameBytes) {
    const fs::path ref = temp_dir("cli-ref"), killed = temp_dir("cli-killed"), stopped = temp_dir("cli-stopped");
    ASSERT_EQ(wait_for(spawn(run_args(ref))), 0);

    {
        SCOPED_TRACE("SIGKILL");
        auto args = run_args(killed);
        args.insert(args.end(), {"--checkpoint-every", "0.05"});
        const pid_t pid = spawn(args);
        ASSERT_TRUE(wait_for_checkpoint(killed, pid));
        std::this_thread::sleep_for(std::chrono::milliseconds(300));
        kill(pid, SIGKILL);
        EXPECT_EQ(wait_for(pid), 128 + SIGKILL);
        // atomic outputs: series only as .part, whole-file outputs complete or absent
        for (const char* f : {"forces.csv", "energy.csv", "front.csv", "track.csv", "deposit.csv", "surface.csv", "barrier_pressure.csv", "peaks.csv", "summary.json"})
            EXPECT_FALSE(fs::exists(killed / f)) << f << " exists under its final name in an unfinished run";
        EXPECT_TRUE(fs::exists(killed / "forces.csv.part"));
        for (const auto& e : fs::directory_iterator(killed / "snapshots")) {
            if (e.path().extension() != ".vtp") continue;
            const std::string text = read_file(e.path());
            EXPECT_EQ(text.substr(text.size() - 11), "</VTKFile>\n") << e.path() << " is incomplete";
        }
        EXPECT_NO_THROW(read_checkpoint_info(killed.string()));
        EXPECT_EQ(wait_for(spawn({"resume", killed.string(), "--threads", "2"})), 0);
        expect_same_outputs(ref, killed);
        EXPECT_EQ(wait_for(spawn({"resume", killed.string()})), 2) << "a finished run has nothing to resume";
    }
    {
        SCOPED_TRACE("SIGTERM");
        const pid_t pid = spawn(run_args(stopped));
        // no timed checkpoints: wait for the flow phase (the first series lines), then signal
        for (int k = 0; k < 6000 && !fs::exists(stopped / "forces.csv.part"); ++k)
            std::this_thread::sleep_for(std::chrono::milliseconds(100));
        std::this_thread::sleep_for(std::chrono::milliseconds(300));
        kill(pid, SIGTERM);
        kill(pid, SIGTERM);  // the same request twice, as a process group's kill can deliver it
        EXPECT_EQ(wait_for(pid), int(kExitInterrupted));
        ASSERT_TRUE(fs::exists(stopped / kCheckpointFile));
        EXPECT_EQ(wait_for(spawn({"resume", stopped.string()})), 0);
        expect_same_outputs(ref, stopped);
    }
    for (const fs::path& p : {ref, killed, stopped}) fs::remove_all(p);
}

// The checkpoints' checksum has the standard CRC-32C check value, and a closed terminal
// (SIGHUP) is caught like SIGTERM: without the handler it would end this test process.
TEST(Checkpoint, Crc32cCheckValueAndSighupIsCaught) {
    EXPECT_EQ(crc32c("123456789"), 0xE3069283u);
    EXPECT_EQ(crc32c(""), 0u);
    EXPECT_EQ(crc32c("6789", crc32c("12345")), 0xE3069283u);  // in pieces
    InterruptScope scope;
    std::raise(SIGHUP);
    EXPECT_EQ(pending_interrupt(), SIGHUP);
}

// One request delivered twice (`timeout` signals the command, then its process group) stops the
// run as one: the repeat within half a second is ignored, where re-arming the default action at
// the first signal let the copy end the process without its checkpoint. A second request later
// than that ends the process at once. Each case in a child process, which the signal may end.
TEST(Checkpoint, ARepeatedSignalIsOneRequestAndALaterOneEndsTheProcess) {
    auto child_status = [](int pause_ms) {
        const pid_t pid = fork();
        if (pid == 0) {
            InterruptScope scope;
            std::raise(SIGINT);
            std::this_thread::sleep_for(std::chrono::milliseconds(pause_ms));
            std::raise(SIGINT);
            _exit(pending_interrupt() == SIGINT ? 7 : 8);
        }
        int status = 0;
        waitpid(pid, &status, 0);
        return status;
    };
    const int repeated = child_status(0);
    ASSERT_TRUE(WIFEXITED(repeated)) << "the repeat ended the process (signal " << WTERMSIG(repeated) << ")";
    EXPECT_EQ(WEXITSTATUS(repeated), 7);
    const int later = child_status(700);
    ASSERT_TRUE(WIFSIGNALED(later)) << "a second request 0.7 s later did not end the process";
    EXPECT_EQ(WTERMSIG(later), SIGINT);
}

// A second process on a running folder is refused (the run holds flock on RUN_DIR/.demlab.lock),
// and a finished run removes the lock file.
TEST(Checkpoint, ALockedRunFolderIsRefused) {
    const Scenario s = scenario();
    const fs::path dir = temp_dir("ck-lock");
    RunOptions ro{dir.string(), false, [](const std::string&, const std::string&, int index) {
                      if (index == 1) request_interrupt(SIGINT);
                  }};
    ro.handle_signals = true;
    EXPECT_THROW(run_scenario(s, ro), Interrupted);
    EXPECT_FALSE(fs::exists(dir / ".demlab.lock")) << "an interrupted run takes its lock file with it";
    // another process takes the lock (as a running `demlab resume` would)
    const int fd = ::open((dir / ".demlab.lock").c_str(), O_RDWR | O_CREAT, 0644);
    ASSERT_GE(fd, 0);
    ASSERT_EQ(::flock(fd, LOCK_EX | LOCK_NB), 0);
    RunOptions rr{dir.string(), false, {}};
    rr.resume = true;
    try {
        run_scenario(s, rr);
        ADD_FAILURE() << "resumed a folder another process holds";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("another demlab process is running in this folder"), std::string::npos) << e.what();
    }
    EXPECT_TRUE(fs::exists(dir / kCheckpointFile)) << "the refused resume touched nothing";
    EXPECT_TRUE(fs::exists(dir / ".demlab.lock")) << "the refused resume removed the other process' lock";
    ::close(fd);  // the other process ends: its lock goes with it
    run_scenario(s, rr);
    EXPECT_FALSE(fs::exists(dir / ".demlab.lock"));
    fs::remove_all(dir);
}

// A forced run locks the old folder, moves it aside with its lock inside, and locks the new one
// at the same path: dropping the old lock removes its file where it now is, so the new folder's
// lock stays in place, held, for the whole run (a second process is refused), and goes at its end.
TEST(Checkpoint, AForcedRunKeepsItsOwnLock) {
    const Scenario s = scenario();
    const fs::path dir = temp_dir("ck-force-lock");
    run_scenario(s, {dir.string(), false, {}});
    int checked = 0;
    RunOptions forced{dir.string(), true, [&](const std::string&, const std::string&, int index) {
                          if (index != 1) return;
                          ++checked;
                          const int fd = ::open((dir / ".demlab.lock").c_str(), O_RDWR);
                          EXPECT_GE(fd, 0) << "the forced run's lock file is gone while it runs";
                          if (fd < 0) return;
                          EXPECT_NE(::flock(fd, LOCK_EX | LOCK_NB), 0) << "another process could lock the running folder";
                          ::close(fd);
                      }};
    run_scenario(s, forced);
    EXPECT_EQ(checked, 1);
    EXPECT_FALSE(fs::exists(dir / ".demlab.lock"));
    EXPECT_FALSE(fs::exists(replaced_output_dir(dir.string()))) << "the old folder (and its lock) stayed aside";
    fs::remove_all(dir);
}

// A terrain profile edited between the signal and the resume: the checkpoint holds the content
// hash of every file the scenario reads, and the resume is refused naming the file (it ran on
// to a deposit of neither profile). The file restored, the run resumes.
TEST(Checkpoint, EditedInputFileIsRefusedNamingIt) {
    const fs::path dir = temp_dir("ck-input");
    fs::create_directories(dir);
    const fs::path profile = dir / "ground.csv";
    const std::string ground = "x,y\n0,0.5\n1,0\n3,0\n";
    std::ofstream(profile) << ground;
    std::ofstream(dir / "drop.toml") << "[terrain]\nprofile = \"ground.csv\"\n[stop]\nt_max = 0.3\nrest_duration = 0.1\n"
                                        "[output]\nsnapshot_interval = 0.05\n[[discs]]\nposition = [0.5, 0.6]\nradius = 0.05\n"
                                        "[[discs]]\nposition = [2.0, 0.2]\nradius = 0.05\n";
    Scenario s = load_scenario((dir / "drop.toml").string());
    finish_scenario(s);
    const fs::path run = dir / "run";
    RunOptions ro{run.string(), false, [](const std::string&, const std::string&, int index) {
                      if (index == 1) request_interrupt(SIGINT);
                  }};
    ro.handle_signals = true;
    EXPECT_THROW(run_scenario(s, ro), Interrupted);
    ASSERT_TRUE(fs::exists(run / kCheckpointFile));
    std::ofstream(profile) << "x,y\n0,0.55\n1,0\n3,0\n";
    try {
        test::resume_run(run, 1);
        FAIL() << "resumed with an edited terrain profile";
    } catch (const InputError& e) {
        const std::string m = e.what();
        EXPECT_NE(m.find(profile.string()), std::string::npos) << m;
        EXPECT_NE(m.find("terrain.profile"), std::string::npos) << m;
        EXPECT_NE(m.find("has changed since the checkpoint"), std::string::npos) << m;
    }
    EXPECT_TRUE(fs::exists(run / kCheckpointFile));
    EXPECT_FALSE(fs::exists(run / ".demlab.lock")) << "a resume refused after it locked the folder left its lock file";
    std::ofstream(profile) << ground;
    EXPECT_NO_THROW(test::resume_run(run, 1));
    EXPECT_TRUE(fs::exists(run / "summary.json"));
    fs::remove_all(dir);
}

// A DAN run goes through the same loop: stopped by a signal at its third snapshot (0.04 s),
// resumed, every file the same bytes as the uninterrupted run's.
TEST(Checkpoint, DanRunResumesToTheSameBytes) {
    Scenario s = load_scenario(std::string(DEMLAB_SOURCE_DIR) + "/scenarios/geometry-A.toml");
    apply_override(s, "scenario.solver=\"dan\"");
    finish_scenario(s);
    const fs::path ref = temp_dir("ck-dan-ref"), cut = temp_dir("ck-dan-cut");
    run_scenario(s, {ref.string(), false, {}});
    RunOptions ro{cut.string(), false, [](const std::string&, const std::string&, int index) {
                      if (index == 2) request_interrupt(SIGTERM);
                  }};
    ro.handle_signals = true;
    EXPECT_THROW(run_scenario(s, ro), Interrupted);
    ASSERT_TRUE(fs::exists(cut / kCheckpointFile));
    EXPECT_NEAR(read_checkpoint_info(cut.string()).time, 0.04, 1e-3);
    EXPECT_FALSE(fs::exists(cut / "summary.json"));
    std::ofstream(cut / "forces.csv.part", std::ios::app) << "9.99,written after the checkpoint\n";
    const RunSummary r = demlab::test::resume_run(cut, 1);
    EXPECT_EQ(r.stop_reason, "rest");
    for (const char* f : {"forces.csv", "front.csv", "energy.csv", "blocks.csv", "deposit.csv", "surface.csv"})
        EXPECT_EQ(read_file(ref / f), read_file(cut / f)) << f << " differs";
    EXPECT_EQ(summary_without_timing(ref / "summary.json"), summary_without_timing(cut / "summary.json"));
    EXPECT_FALSE(fs::exists(cut / kCheckpointFile));
    fs::remove_all(ref);
    fs::remove_all(cut);
}
