// The output-folder policy, the writer that checks every byte and the runner without a shell
// (docs/reliability.md, "Outputs"): --force never deletes what demlab did not make or what a
// command reads, no name or path a user typed reaches a shell, a failed write ends the run with
// exit code 5 and leaves no partial file under a final name, and strings written back into
// scenario.toml read again.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/fileio.h"
#include "core/interrupt.h"
#include "core/output_dir.h"
#include "core/process.h"
#include "files.h"
#include "output/plot.h"
#include "scenario/key_registry.h"
#include "scenario/scenario.h"

namespace demlab {
namespace {

namespace fs = std::filesystem;
using test::read_file;
using test::temp_dir;

// Two discs dropped on a floor: a run of a fraction of a second, series every `series` s.
std::string drop_scenario(const std::string& name, double series = 0.005, double snapshots = 0.02,
                          const std::string& extra = "") {
    return "[scenario]\nname = " + keys::toml_string(name) + "\n[stop]\nt_max = 0.1\nrest_duration = 0.01\nrest_ke_fraction = 1e-12\n" +
           "[output]\nseries_interval = " + std::to_string(series) + "\nsnapshot_interval = " + std::to_string(snapshots) +
           "\n" + extra + "[[discs]]\nposition = [0.0, 0.05]\nradius = 0.01\n[[discs]]\nposition = [0.05, 0.05]\nradius = 0.01\n" +
           "[[walls]]\nstart = [-1, 0]\nend = [1, 0]\n";
}

void write_text(const fs::path& p, const std::string& text) {
    fs::create_directories(p.parent_path());
    std::ofstream(p) << text;
}

// The demlab executable with these arguments in folder `cwd`; its exit status.
int demlab(const std::vector<std::string>& args, const fs::path& cwd) {
    ProcessDef p;
    p.argv = {DEMLAB_EXE};
    p.argv.insert(p.argv.end(), args.begin(), args.end());
    p.cwd = cwd.string();
    p.stderr_file = (cwd / "stderr.txt").string();
    return run_process(p);
}

// A finished run (snapshots and plots) at `work`/`name`.
fs::path finished_run(const fs::path& work, const std::string& name) {
    write_text(work / (name + ".toml"), drop_scenario(name));
    EXPECT_EQ(demlab({"run", name + ".toml", "--out", name}, work), 0) << read_file(work / "stderr.txt");
    return work / name;
}

std::vector<std::string> listing(const fs::path& dir) {
    std::vector<std::string> names;
    for (const auto& e : fs::recursive_directory_iterator(dir)) names.push_back(fs::relative(e.path(), dir).string());
    std::sort(names.begin(), names.end());
    return names;
}

}  // namespace

// Row 1: --force on a folder of the user's own files, or on one that holds the scenario or the
// working directory, is refused and nothing in it changes.
TEST(OutputPolicy, ForceNeverDeletesWhatDemlabDidNotMakeOrAnInput) {
    const fs::path work = temp_dir("force-user");
    write_text(work / "project/base.toml", drop_scenario("base"));
    write_text(work / "project/userdata/notes.txt", "my notes\n");
    write_text(work / "project/userdata/sub/data.csv", "1,2\n");
    const auto before = listing(work);
    EXPECT_EQ(demlab({"run", "base.toml", "--out", "userdata", "--force"}, work / "project"), kExitInput);
    EXPECT_NE(read_file(work / "project/stderr.txt").find("not made by demlab"), std::string::npos);
    fs::remove(work / "project/stderr.txt");
    EXPECT_EQ(listing(work), before);
    // the folder holding the scenario and the working directory, from inside it
    EXPECT_EQ(demlab({"run", "base.toml", "--out", "..", "--force"}, work / "project"), kExitInput);
    fs::remove(work / "project/stderr.txt");
    EXPECT_EQ(listing(work), before);
    // a run folder of demlab's that holds the scenario read: refused, and no lock left in it
    const fs::path run = finished_run(work, "r");
    const auto run_files = listing(run);
    EXPECT_EQ(demlab({"run", "r/scenario.toml", "--out", "r", "--force"}, work), kExitInput);
    EXPECT_NE(read_file(work / "stderr.txt").find("input"), std::string::npos) << read_file(work / "stderr.txt");
    EXPECT_EQ(demlab({"run", "../r.toml", "--out", ".", "--force"}, run), kExitInput);
    fs::remove(run / "stderr.txt");
    EXPECT_EQ(listing(run), run_files);  // (no .demlab.lock either)
    // and a demlab folder that is none of these is replaced as before
    EXPECT_EQ(demlab({"run", "r.toml", "--out", "r", "--force"}, work), 0);
    EXPECT_FALSE(fs::exists(replaced_output_dir(run.string())));
    fs::remove_all(work);
}

// Row 1c: another output made inside a finished run folder (a run, frames rendered under
// another name) is not the run's: a --force on the run is refused naming it, and it stays. The
// run's own plots/ and frames/, also when `demlab plot` or `demlab render` made them later, are
// replaced with the run. (A marked folder inside counted as the run's whatever its name, and
// --force deleted the other run without a word.)
TEST(OutputPolicy, ForceOnARunKeepsTheOtherOutputsMadeInsideIt) {
    const fs::path work = temp_dir("force-nested");
    const fs::path run = finished_run(work, "r");
    EXPECT_EQ(demlab({"run", "r.toml", "--out", "r/other", "--no-plots"}, work), 0) << read_file(work / "stderr.txt");
    EXPECT_EQ(demlab({"render", "r", "--out", "r/frames-hd", "--size", "64x48"}, work), 0) << read_file(work / "stderr.txt");
    EXPECT_EQ(demlab({"render", "r", "--size", "64x48", "--force"}, work), 0) << read_file(work / "stderr.txt");  // r/frames
    if (program_available("gnuplot")) {
        EXPECT_EQ(demlab({"plot", "r"}, work), 0) << read_file(work / "stderr.txt");
    }
    const auto other = listing(run / "other");
    EXPECT_EQ(demlab({"run", "r.toml", "--out", "r", "--force"}, work), kExitInput);
    const std::string said = read_file(work / "stderr.txt");
    EXPECT_NE(said.find("'frames-hd'"), std::string::npos) << said;
    EXPECT_NE(said.find("'other'"), std::string::npos) << said;
    EXPECT_EQ(said.find("'frames'"), std::string::npos) << said;
    EXPECT_EQ(said.find("'plots'"), std::string::npos) << said;
    EXPECT_EQ(listing(run / "other"), other);
    EXPECT_TRUE(fs::exists(run / "frames-hd"));
    // moved out of the way, the run is replaced with its own frames and plots
    fs::rename(run / "other", work / "other");
    fs::rename(run / "frames-hd", work / "frames-hd");
    EXPECT_EQ(demlab({"run", "r.toml", "--out", "r", "--force"}, work), 0) << read_file(work / "stderr.txt");
    EXPECT_EQ(listing(work / "other"), other);
    // an earlier build's run: its plots/ drawn after the run's list was written, so unlisted
    EXPECT_EQ(demlab({"run", "r.toml", "--out", "r", "--force", "--no-plots"}, work), 0) << read_file(work / "stderr.txt");
    write_text(run / "plots/forces_x.png", "png\n");
    mark_output_dir((run / "plots").string());
    record_output_files((run / "plots").string());
    EXPECT_EQ(demlab({"run", "r.toml", "--out", "r", "--force"}, work), 0) << read_file(work / "stderr.txt");
    fs::remove_all(work);
}

// Row 1d: a symbolic link put into a run folder is never written through: `demlab plot` is
// refused while plots/ holds one (it drew a PNG over the file the link named, outside the
// folder), and a resume refuses a series file replaced by one (it cut the linked file back).
TEST(OutputPolicy, ALinkInARunFolderIsRefusedNotWrittenThrough) {
    if (!program_available("gnuplot")) GTEST_SKIP() << "gnuplot is not installed";
    const fs::path work = temp_dir("links");
    const fs::path run = finished_run(work, "r");
    write_text(work / "victim.txt", "the user's\n");
    fs::remove(run / "plots/forces_x.png");
    fs::create_symlink(work / "victim.txt", run / "plots/forces_x.png");
    EXPECT_EQ(demlab({"plot", "r"}, work), kExitInput);
    EXPECT_NE(read_file(work / "stderr.txt").find("forces_x.png"), std::string::npos) << read_file(work / "stderr.txt");
    EXPECT_EQ(demlab({"run", "r.toml", "--out", "r", "--force"}, work), kExitInput);
    EXPECT_EQ(read_file(work / "victim.txt"), "the user's\n");
    // a plots/ of the user's (no marker) holding a plots.gp and a link: not taken for demlab's
    fs::remove_all(run / "plots");
    write_text(run / "plots/plots.gp", "# mine\n");
    fs::create_symlink(work / "victim.txt", run / "plots/gnuplot.log");
    EXPECT_EQ(demlab({"plot", "r"}, work), kExitInput);
    EXPECT_EQ(read_file(work / "victim.txt"), "the user's\n");
    // a series file resumed through a link
    SeriesFile series;
    fs::create_symlink(work / "victim.txt", work / "front.csv.part");
    EXPECT_THROW(series.reopen((work / "front.csv").string(), 3), InputError);
    EXPECT_EQ(read_file(work / "victim.txt"), "the user's\n");
    fs::remove_all(work);
}

// Row 1b: a folder that merely has the name a forced output would move its old folder to (a
// user's run called X.replaced) is never removed or moved: not by a new output into X, not by
// a forced one (which takes the next free name), not by one that fails; and the old folder a
// forced run did move aside goes once the run is complete, also when it completes on resume.
TEST(OutputPolicy, OnlyTheFolderAForcedOutputMovedAsideIsRemoved) {
    const fs::path work = temp_dir("aside");
    const fs::path mine = finished_run(work, "a.replaced");
    write_text(mine / "notes.txt", "my notes\n");
    const auto files_mine = listing(mine);
    write_text(work / "b.toml", drop_scenario("b"));
    // a new folder beside it: nothing moved aside, nothing removed
    EXPECT_EQ(demlab({"run", "b.toml", "--out", "a"}, work), 0) << read_file(work / "stderr.txt");
    EXPECT_EQ(listing(mine), files_mine);
    // a forced run over `a`: its old folder goes to a.replaced-2, removed at the end
    EXPECT_EQ(demlab({"run", "b.toml", "--out", "a", "--force"}, work), 0) << read_file(work / "stderr.txt");
    EXPECT_EQ(listing(mine), files_mine);
    EXPECT_FALSE(fs::exists(work / "a.replaced-2"));
    // a render that fails once its folder is made (a snapshot cut short) removes only its own
    // folder, and puts back no folder it did not move
    fs::copy(work / "a", work / "cut", fs::copy_options::recursive);
    write_text(work / "cut/snapshots/discs_00001.vtp", "<?xml version=\"1.0\"?>\n<VTKFile");
    fs::copy(mine, work / "g.replaced", fs::copy_options::recursive);
    EXPECT_NE(demlab({"render", "cut", "--size", "64x48", "--out", "g"}, work), 0);
    EXPECT_FALSE(fs::exists(work / "g"));
    EXPECT_EQ(listing(work / "g.replaced"), files_mine);
    // a forced render over its own earlier folder, beside a user's f.replaced
    EXPECT_EQ(demlab({"render", "a", "--size", "64x48", "--out", "f"}, work), 0) << read_file(work / "stderr.txt");
    fs::copy(mine, work / "f.replaced", fs::copy_options::recursive);
    EXPECT_EQ(demlab({"render", "a", "--size", "64x48", "--out", "f", "--force"}, work), 0);
    EXPECT_EQ(listing(work / "f.replaced"), files_mine);
    EXPECT_FALSE(fs::exists(work / "f.replaced-2"));
    fs::remove_all(work);
}

// Row 1b': an unfinished forced output (a run stopped before its first checkpoint) forced again,
// as resume does when it reruns such a run from the start: the unfinished folder is replaced and
// the new output takes over its token, so the user's old folder, still aside, goes once the new
// output is complete, and no second aside is left behind.
TEST(OutputPolicy, AnUnfinishedForcedOutputForcedAgainKeepsTheOldFolderUntilTheEnd) {
    const fs::path work = temp_dir("aside-again");
    const fs::path x = work / "x";
    prepare_output_dir(x.string(), false);
    write_text(x / "result.csv", "old\n");
    remove_replaced_output(x.string());  // complete
    prepare_output_dir(x.string(), true);  // forced: the old one aside
    write_text(x / "partial.csv", "new, unfinished\n");
    const fs::path aside = replaced_output_dir(x.string());
    EXPECT_EQ(read_file(aside / "result.csv"), "old\n");
    prepare_output_dir(x.string(), true);  // forced again before it finished
    EXPECT_EQ(read_file(aside / "result.csv"), "old\n");
    EXPECT_FALSE(fs::exists(x / "partial.csv"));
    EXPECT_FALSE(fs::exists(work / "x.replaced-2"));
    remove_replaced_output(x.string());  // now complete
    EXPECT_FALSE(fs::exists(aside));
    fs::remove_all(work);
}

// Row 1c: demlab plot writes into a run's plots/ only when it is demlab's and holds nothing else:
// a user's file there is neither overwritten nor listed as demlab's (which a --force on the run
// would then delete). A plots/ an earlier build made without the marker is still drawn into.
TEST(OutputPolicy, PlotNeverAdoptsTheUsersFiles) {
    const fs::path work = temp_dir("plot-adopt");
    const fs::path run = finished_run(work, "r");
    fs::remove_all(run / "plots");
    write_text(run / "plots/kinetic_energy.png", "hand-drawn");
    EXPECT_EQ(demlab({"plot", "r"}, work), kExitInput);
    EXPECT_NE(read_file(work / "stderr.txt").find("not made by demlab"), std::string::npos) << read_file(work / "stderr.txt");
    EXPECT_EQ(read_file(run / "plots/kinetic_energy.png"), "hand-drawn");
    // a plots/ of a build before the marker (its plots.gp and PNGs, nothing else) is demlab's
    write_text(run / "plots/plots.gp", "# an earlier build's\n");
    EXPECT_EQ(demlab({"plot", "r"}, work), 0) << read_file(work / "stderr.txt");
    EXPECT_NE(read_file(run / "plots/kinetic_energy.png"), "hand-drawn");
    fs::remove_all(run / "plots");
    EXPECT_EQ(demlab({"plot", "r"}, work), 0) << read_file(work / "stderr.txt");
    write_text(run / "plots/my_fig.svg", "mine");
    EXPECT_EQ(demlab({"plot", "r"}, work), kExitInput);
    EXPECT_NE(read_file(work / "stderr.txt").find("my_fig.svg"), std::string::npos) << read_file(work / "stderr.txt");
    EXPECT_EQ(demlab({"run", "r.toml", "--out", "r", "--force"}, work), kExitInput);
    EXPECT_EQ(read_file(run / "plots/my_fig.svg"), "mine");
    fs::remove_all(work);
}

// Row 2: render's --strip does not overwrite an existing file without --force, and never a
// file of the run itself.
TEST(OutputPolicy, RenderStripNeverOverwritesUnasked) {
    const fs::path work = temp_dir("strip");
    const fs::path run = finished_run(work, "r");
    const std::string summary = read_file(run / "summary.json");
    EXPECT_EQ(demlab({"render", "r", "--size", "64x48", "--strip", "r/summary.json"}, work), kExitInput);
    EXPECT_EQ(demlab({"render", "r", "--size", "64x48", "--strip", "r/summary.json", "--force"}, work), kExitInput);
    EXPECT_EQ(read_file(run / "summary.json"), summary);
    EXPECT_FALSE(fs::exists(run / "frames"));  // a refused render leaves no folder behind
    write_text(work / "strip.png", "mine");
    EXPECT_EQ(demlab({"render", "r", "--size", "64x48", "--strip", "strip.png"}, work), kExitInput);
    EXPECT_EQ(read_file(work / "strip.png"), "mine");
    EXPECT_EQ(demlab({"render", "r", "--size", "64x48", "--strip", "strip.png", "--force"}, work), 0);
    EXPECT_NE(read_file(work / "strip.png"), "mine");
    fs::remove_all(work);
}

// Row 3: an output that is one of the command's inputs is refused before anything moves.
TEST(OutputPolicy, AnOutputThatIsAnInputIsRefusedBeforeAnythingMoves) {
    const fs::path work = temp_dir("out-input");
    const fs::path a = finished_run(work, "a"), b = finished_run(work, "b");
    const auto files_a = listing(a), files_b = listing(b);
    EXPECT_EQ(demlab({"render", "a", "--size", "64x48", "--out", "a", "--force"}, work), kExitInput);
    EXPECT_EQ(demlab({"compare", "a", "b", "--out", "b", "--force"}, work), kExitInput);
    EXPECT_EQ(demlab({"compare", "a", "b", "--out", ".", "--force"}, a), kExitInput);
    fs::remove(a / "stderr.txt");
    EXPECT_EQ(listing(a), files_a);
    EXPECT_EQ(listing(b), files_b);
    EXPECT_FALSE(fs::exists(replaced_output_dir(a.string())));
    EXPECT_FALSE(fs::exists(replaced_output_dir(b.string())));
    fs::remove_all(work);
}

// Row 4: quotes, $() and backquotes in a scenario's name or an output path reach no shell:
// the run and its plots are made, and no command in them runs.
TEST(OutputPolicy, NoNameOrPathReachesAShell) {
    if (!program_available("gnuplot")) GTEST_SKIP() << "gnuplot is not installed";
    const fs::path work = temp_dir("shell");
    write_text(work / "s.toml", drop_scenario("a';touch PWNED;'`touch TICK`$(touch DOLLAR)"));
    EXPECT_EQ(demlab({"run", "s.toml"}, work), 0) << read_file(work / "stderr.txt");
    const std::string out = "x';touch X;'\"$(touch Y)\"`touch Z`";
    EXPECT_EQ(demlab({"run", "s.toml", "--out", out}, work), 0) << read_file(work / "stderr.txt");
    EXPECT_TRUE(fs::exists(work / out / "plots/forces_x.png"));
    // compare's script and labels: two continuum runs (seconds) under such names
    const std::string geometry = std::string(DEMLAB_SOURCE_DIR) + "/scenarios/geometry-A.toml";
    for (const std::string& d : {out + "-dan", std::string("b'$(touch DOLLAR)`touch TICK`")})
        EXPECT_EQ(demlab({"run", geometry, "--solver", "dan", "--out", d, "--no-plots"}, work), 0) << read_file(work / "stderr.txt");
    EXPECT_EQ(demlab({"compare", out + "-dan", "b'$(touch DOLLAR)`touch TICK`", "--out", out + "-cmp"}, work), 0)
        << read_file(work / "stderr.txt");
    EXPECT_TRUE(fs::exists(work / (out + "-cmp") / "front.png"));
    for (const char* f : {"PWNED", "TICK", "DOLLAR", "X", "Y", "Z"}) {
        EXPECT_FALSE(fs::exists(work / f)) << f;
        EXPECT_FALSE(fs::exists(work / out / "plots" / f)) << f;
    }
    fs::remove_all(work);
}

// Row 5: a write refused by the file system (here a file size limit, as a full disk refuses)
// ends the run with exit code 5 naming the file, and no cut file gets its final name.
TEST(OutputPolicy, AFailedWriteEndsTheRunWithItsOwnExitCode) {
    const fs::path work = temp_dir("full");
    // series every step or so: forces.csv passes 64 KiB within the run
    write_text(work / "s.toml", drop_scenario("full", 1e-5, 0.0));
    const pid_t pid = ::fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) {
        ::signal(SIGXFSZ, SIG_IGN);  // the write then fails with EFBIG, as on a full disk
        const rlimit lim{64 * 1024, 64 * 1024};
        ::setrlimit(RLIMIT_FSIZE, &lim);
        if (::chdir(work.c_str()) != 0) ::_exit(99);
        const int fd = ::open("stderr.txt", O_WRONLY | O_CREAT | O_TRUNC, 0644);
        ::dup2(fd, 2);
        ::execl(DEMLAB_EXE, DEMLAB_EXE, "run", "s.toml", "--out", "out", "--no-plots", static_cast<char*>(nullptr));
        ::_exit(98);
    }
    int status = 0;
    ::waitpid(pid, &status, 0);
    ASSERT_TRUE(WIFEXITED(status));
    EXPECT_EQ(WEXITSTATUS(status), kExitWrite) << read_file(work / "stderr.txt");
    EXPECT_NE(read_file(work / "stderr.txt").find(".csv (File too large)"), std::string::npos) << read_file(work / "stderr.txt");
    int parts = 0;
    for (const auto& e : fs::directory_iterator(work / "out"))
        if (e.path().extension() == ".part") {
            ++parts;
            EXPECT_FALSE(fs::exists(fs::path(e.path()).replace_extension(""))) << e.path() << " has its final name too";
        }
    EXPECT_GT(parts, 0);
    EXPECT_FALSE(fs::exists(work / "out/summary.json"));
    fs::remove_all(work);
}

// Row 5b: the same under a plain `ulimit -f` (SIGXFSZ as the shell leaves it, which would kill
// the process), and for the plots gnuplot draws: a PNG it could not finish is removed and named
// (exit 5), and no cut PNG stays under its final name.
TEST(OutputPolicy, AFileSizeLimitEndsRunAndPlotWithExitFiveAndNoCutPlot) {
    const fs::path work = temp_dir("fsize");
    write_text(work / "s.toml", drop_scenario("fsize", 1e-5, 0.0));
    const fs::path run = finished_run(work, "r");
    auto limited = [&](std::vector<const char*> args, rlim_t bytes) {
        const pid_t pid = ::fork();
        if (pid == 0) {
            ::signal(SIGXFSZ, SIG_DFL);  // as a shell's ulimit -f leaves it
            const rlimit lim{bytes, bytes};
            ::setrlimit(RLIMIT_FSIZE, &lim);
            if (::chdir(work.c_str()) != 0) ::_exit(99);
            const int fd = ::open("stderr.txt", O_WRONLY | O_CREAT | O_TRUNC, 0644);
            ::dup2(fd, 2);
            args.insert(args.begin(), DEMLAB_EXE);
            args.push_back(nullptr);
            ::execv(DEMLAB_EXE, const_cast<char* const*>(args.data()));
            ::_exit(98);
        }
        int status = 0;
        ::waitpid(pid, &status, 0);
        return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    };
    EXPECT_EQ(limited({"run", "s.toml", "--out", "out", "--no-plots"}, 64 * 1024), kExitWrite) << read_file(work / "stderr.txt");
    EXPECT_FALSE(fs::exists(work / "out/scenario.toml.tmp"));
    // the plots: small enough that some PNGs pass and some are cut
    fs::remove_all(run / "plots");
    EXPECT_EQ(limited({"plot", "r"}, 24 * 1024), kExitWrite) << read_file(work / "stderr.txt");
    EXPECT_NE(read_file(work / "stderr.txt").find(".png: gnuplot could not write"), std::string::npos) << read_file(work / "stderr.txt");
    int whole = 0;
    for (const auto& e : fs::directory_iterator(run / "plots")) {
        if (e.path().extension() != ".png") continue;
        const std::string png = read_file(e.path());
        ASSERT_GE(png.size(), 12u) << e.path();
        EXPECT_EQ(png.substr(png.size() - 8, 4), "IEND") << e.path() << " is cut";
        ++whole;
    }
    EXPECT_GT(whole, 0);  // (the smaller ones passed)
    EXPECT_EQ(limited({"plot", "r"}, RLIM_INFINITY), 0) << read_file(work / "stderr.txt");
    fs::remove_all(work);
}

// gnuplot stopped by the Ctrl-C that stops demlab (one process group) is an interruption (exit
// 4, what it draws from being complete), not a failed run (exit 3); failing on its own, a
// failed run.
TEST(OutputPolicy, GnuplotStoppedByAnInterruptIsAnInterruption) {
    if (!gnuplot_available()) GTEST_SKIP() << "gnuplot is not installed";
    const fs::path work = temp_dir("gp-int");
    fs::create_directories(work);
    write_text(work / "bad.gp", "this is not gnuplot\n");
    EXPECT_THROW(run_gnuplot(work.string(), "bad.gp", {}), RunError);
    request_interrupt(SIGINT);
    EXPECT_THROW(run_gnuplot(work.string(), "bad.gp", {}), Interrupted);
    clear_interrupt();
    fs::remove_all(work);
}

// The writers themselves: a refused write throws WriteError, removes its temporary file and
// gives no final name.
TEST(OutputPolicy, WritersCheckEveryByte) {
    const fs::path dir = temp_dir("writers");
    fs::create_directories(dir);
    rlimit old{};
    ::getrlimit(RLIMIT_FSIZE, &old);
    const auto old_handler = ::signal(SIGXFSZ, SIG_IGN);
    rlimit lim = old;
    lim.rlim_cur = 4096;
    ASSERT_EQ(::setrlimit(RLIMIT_FSIZE, &lim), 0);
    EXPECT_THROW(write_file_atomic((dir / "big.txt").string(), std::string(10000, 'x')), WriteError);
    SeriesFile series;
    series.open((dir / "series.csv").string());
    bool thrown = false;
    try {
        for (int i = 0; i < 10000; ++i) {
            series.out() << "0.123456789,0.123456789\n";
            series.check();
        }
        series.close();
    } catch (const WriteError&) {
        thrown = true;
    }
    ::setrlimit(RLIMIT_FSIZE, &old);
    ::signal(SIGXFSZ, old_handler);
    EXPECT_TRUE(thrown);
    EXPECT_FALSE(fs::exists(dir / "big.txt"));
    EXPECT_FALSE(fs::exists(dir / "big.txt.tmp"));
    EXPECT_FALSE(fs::exists(dir / "series.csv"));
    EXPECT_NO_THROW(write_file_atomic((dir / "big.txt").string(), std::string(10000, 'x')));
    fs::remove_all(dir);
}

// Row 13: every string written back into scenario.toml is escaped, so the resolved scenario
// of a multi-line description reads again with the same text.
TEST(OutputPolicy, StringsWrittenBackReadAgain) {
    Scenario s = parse_scenario(drop_scenario("esc") + "", "esc.toml");
    s.description = "two\nlines with a \"quote\", a tab\t, a \\ and a bell \x07";
    finish_scenario(s);
    const Scenario back = parse_scenario(resolved_toml(s), "resolved.toml");
    EXPECT_EQ(back.description, s.description);
}

// The runner starts no shell: its arguments arrive as given.
TEST(OutputPolicy, ProcessArgumentsArriveAsGiven) {
    const fs::path dir = temp_dir("argv");
    fs::create_directories(dir);
    ProcessDef p;
    p.argv = {"printf", "%s|", "a b", "'$(touch X)'", "`touch Y`"};
    p.cwd = dir.string();
    std::string got;
    p.on_line = [&](const std::string& l) { got += l; };
    EXPECT_EQ(run_process(p), 0);
    EXPECT_EQ(got, "a b|'$(touch X)'|`touch Y`|");
    EXPECT_FALSE(fs::exists(dir / "X"));
    EXPECT_FALSE(fs::exists(dir / "Y"));
    ProcessDef missing;
    missing.argv = {"no-such-program-demlab"};
    EXPECT_EQ(run_process(missing), -1);
    fs::remove_all(dir);
}

// A path printed inside a command for the user to paste (`continue with: demlab resume DIR`)
// is one shell word that reads back as the path: nothing in it runs, and a leading '-' is not
// an option. (It was printed bare: a run named r$(touch X) printed a command that ran touch.)
TEST(OutputPolicy, APathInAPrintedCommandIsOneShellWord) {
    const fs::path dir = temp_dir("shell-word");
    fs::create_directories(dir);
    for (const std::string& name : {std::string("runs/plain-1.0_a"), std::string("r$(touch X)"), std::string("a b"),
                                    std::string("it's"), std::string("`touch Y`;touch Z"), std::string("-h"),
                                    std::string("x\nnew line"), std::string("")}) {
        ProcessDef p;
        p.argv = {"sh", "-c", "printf '%s|' " + shell_word(name)};
        p.cwd = dir.string();
        std::string got;
        p.on_line = [&](const std::string& l) { got += l; };
        EXPECT_EQ(run_process(p), 0) << name;
        EXPECT_EQ(got, (name[0] == '-' ? "./" + name : name) + "|") << shell_word(name);
    }
    EXPECT_EQ(shell_word("runs/plain-1.0_a"), "runs/plain-1.0_a");
    for (const char* f : {"X", "Y", "Z"}) EXPECT_FALSE(fs::exists(dir / f)) << f;
    fs::remove_all(dir);
}

}  // namespace demlab

namespace demlab {

// render --strip without --out writes the strip alone: beside the frames a run already has,
// which stay as they were (before, frames/ existing refused it, and --force would delete them).
TEST(OutputPolicy, AStripIsMadeBesideExistingFrames) {
    const fs::path work = test::temp_dir("strip-beside");
    const fs::path run = finished_run(work, "r");
    ASSERT_EQ(demlab({"render", "r", "--size", "64x48"}, work), 0) << read_file(work / "stderr.txt");
    const auto frames = listing(run / "frames");
    const std::string first = read_file(run / "frames/frame_00000.png");
    EXPECT_EQ(demlab({"render", "r", "--size", "64x48", "--every", "0.04", "--strip", "strip.png"}, work), 0)
        << read_file(work / "stderr.txt");
    EXPECT_GT(fs::file_size(work / "strip.png"), 100u);
    EXPECT_EQ(listing(run / "frames"), frames);
    EXPECT_EQ(read_file(run / "frames/frame_00000.png"), first);
    fs::remove_all(work);
}

}  // namespace demlab
