// libFuzzer target for the output-folder policy and the checked writer (docs/reliability.md,
// "Outputs"). Each input draws a run of a small scenario into a sandbox that holds a user's
// files, a scenario, a folder demlab made earlier and files above the working folder:
//  - an output path of components such as `..`, `.`, the user's folder, the scenario file,
//    demlab's folder, names with quotes, `$()`, backquotes, newlines and spaces (relative or
//    absolute; never more `..` than keep it inside the sandbox);
//  - a scenario name of the same characters (runs/<name> when no path is drawn);
//  - --force or not, a saved release mass read from inside the sandbox or not;
//  - at times a file size limit (as a full disk refuses a write) of 1 to 64 KiB.
// Invariants: no file outside the run's own output folder is changed, added or removed (a
// folder demlab made may be replaced only when it is the output); and a run whose output could
// not be written whole never returns normally (it throws WriteError), so a run that returns
// has no file at the size limit (a cut one). Run: scripts/fuzz.sh [RUNS].
#include <fuzzer/FuzzedDataProvider.h>
#include <signal.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>

#include "core/error.h"
#include "core/output_dir.h"
#include "run/run.h"
#include "scenario/key_registry.h"
#include "scenario/scenario.h"

namespace {

namespace fs = std::filesystem;

// The sandbox: ROOT/a/b/work is the working folder, so three `..` stay inside ROOT.
const fs::path& root() {
    static const fs::path r = fs::temp_directory_path() / ("demlab-fuzz-output-" + std::to_string(::getpid()));
    return r;
}
fs::path work() { return root() / "a/b/work"; }

void put(const fs::path& p, const std::string& text) {
    fs::create_directories(p.parent_path());
    std::ofstream(p) << text;
}

std::string scenario_text(const std::string& name) {
    return "[scenario]\nname = " + demlab::keys::toml_string(name) +
           "\n[stop]\nt_max = 0.05\nrest_duration = 0.01\nmax_steps = 60\nrest_ke_fraction = 1e-12\n"
           "[output]\nseries_interval = 0.0005\nsnapshot_interval = 0.01\n"
           "[[discs]]\nposition = [0.0, 0.02]\nradius = 0.01\n[[discs]]\nposition = [0.05, 0.02]\nradius = 0.01\n"
           "[[walls]]\nstart = [-1, 0]\nend = [1, 0]\n";
}

// The sandbox as each case finds it.
void lay_out() {
    fs::remove_all(root());
    put(root() / "outside.txt", "above the working folder\n");
    put(root() / "a/notes.txt", "a user's notes\n");
    put(work() / "base.toml", scenario_text("base"));
    put(work() / "user/notes.txt", "my notes\n");
    put(work() / "user/sub/data.csv", "1,2\n");
    put(work() / "old-run/summary.json", "{}\n");
    put(work() / "old-run" / demlab::kOutputMarker, "made by demlab\n");
    put(work() / "old-run/keep/inner.txt", "inside demlab's folder\n");
}

// Every file under the sandbox with its content.
std::map<std::string, std::string> files() {
    std::map<std::string, std::string> all;
    for (const auto& e : fs::recursive_directory_iterator(root())) {
        if (!e.is_regular_file()) continue;
        std::ifstream in(e.path(), std::ios::binary);
        std::stringstream b;
        b << in.rdbuf();
        all[e.path().string()] = b.str();
    }
    return all;
}

[[noreturn]] void fail(const std::string& what) {
    std::fprintf(stderr, "fuzz_output: %s\n", what.c_str());
    std::abort();
}

std::string draw_component(FuzzedDataProvider& in) {
    static const char* parts[] = {"..",        ".",    "user", "base.toml", "old-run", "new",     "a'b",   "$(touch P)",
                                  "`touch Q`", "x\ny", "sp ace", "q\"d",    "runs",    "keep",   "sub",  "%05d"};
    return parts[in.ConsumeIntegralInRange<size_t>(0, sizeof parts / sizeof *parts - 1)];
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    static const fs::path home = fs::current_path();  // libFuzzer's own files are named from here
    static const bool once = [] {
        lay_out();
        ::signal(SIGXFSZ, SIG_IGN);  // a write past the size limit fails (EFBIG) as on a full disk
        return true;
    }();
    (void)once;
    FuzzedDataProvider in(data, size);
    lay_out();
    if (::chdir(work().c_str()) != 0) fail("cannot enter the sandbox");
    // the output path: none (runs/<name>), or components, with at most three `..` in all
    std::string out;
    const int components = in.ConsumeIntegralInRange(0, 4);
    int ups = 0;
    for (int k = 0; k < components; ++k) {
        std::string c = draw_component(in);
        if (c == ".." && ++ups > 3) c = "new";
        out += (out.empty() ? "" : "/") + c;
    }
    if (!out.empty() && in.ConsumeIntegralInRange(0, 7) == 0) out = (work() / out).string();
    if (!out.empty() && in.ConsumeBool()) out += "/";
    std::string name = draw_component(in) + draw_component(in);
    const bool force = in.ConsumeBool();
    const bool from_inside = in.ConsumeIntegralInRange(0, 3) == 0;  // the scenario read from demlab's folder
    const size_t limit = in.ConsumeBool() ? 0 : size_t(1024) << in.ConsumeIntegralInRange(0, 6);
    if (from_inside) put(work() / "old-run/scenario.toml", scenario_text("inner"));
    const auto before = files();

    demlab::RunOptions o;
    bool returned = false;
    std::string dir;
    bool was_demlab = false;
    std::string why = "ran";
    rlimit old{};
    ::getrlimit(RLIMIT_FSIZE, &old);
    try {
        demlab::Scenario s = demlab::parse_scenario(from_inside ? scenario_text("inner") : scenario_text(name),
                                                    from_inside ? "old-run/scenario.toml" : "base.toml");
        demlab::finish_scenario(s);
        o.out_dir = out.empty() ? "runs/" + s.name : out;
        o.force = force;
        o.plots = false;
        dir = o.out_dir;
        was_demlab = demlab::is_demlab_output(o.out_dir);
        if (limit > 0) {
            rlimit lim = old;
            lim.rlim_cur = limit;
            ::setrlimit(RLIMIT_FSIZE, &lim);
        }
        demlab::run_scenario(s, o);
        returned = true;
    } catch (const demlab::InputError& e) {
        why = std::string("refused: ") + e.what();
    } catch (const demlab::RunError& e) {
        why = std::string("failed: ") + e.what();
    }
    ::setrlimit(RLIMIT_FSIZE, &old);
    if (::chdir(home.c_str()) != 0) fail("cannot leave the sandbox");
    const fs::path outdir = dir.empty() ? fs::path() : fs::weakly_canonical(work() / dir);
    auto under_out = [&](const std::string& f) {
        return !dir.empty() && (demlab::path_within(f, outdir.string()) ||
                                demlab::path_within(f, demlab::replaced_output_dir(outdir.string())));
    };
    // what was there may change only inside a folder demlab made, replaced with --force, that
    // holds neither the scenario read nor the working folder
    const fs::path input = work() / (from_inside ? "old-run/scenario.toml" : "base.toml");
    const bool replaceable = force && was_demlab && !dir.empty() && !demlab::path_within(input.string(), outdir.string()) &&
                             !demlab::path_within(work().string(), outdir.string());
    const auto after = files();
    for (const auto& [f, text] : before) {
        if (under_out(f) && replaceable) continue;
        const auto it = after.find(f);
        if (it == after.end()) fail("removed: " + f + " (out '" + dir + "', force " + std::to_string(force) + ")");
        if (it->second != text) fail("changed: " + f + " (out '" + dir + "', force " + std::to_string(force) + ")");
    }
    for (const auto& [f, text] : after)
        if (!before.count(f) && !under_out(f)) fail("written outside the run's folder: " + f + " (out '" + dir + "')");
    if (returned) {
        if (!demlab::is_demlab_output(outdir.string())) fail("a run's folder has no marker: " + dir);
        for (const auto& [f, text] : after)
            if (under_out(f) && limit > 0 && text.size() >= limit)
                fail("a run returned although " + f + " reached the size limit (" + std::to_string(limit) + " bytes)");
    }
    if (std::getenv("DEMLAB_FUZZ_VERBOSE"))
        std::fprintf(stderr, "fuzz_output: out '%s' force %d limit %zu: %s\n", dir.c_str(), int(force), limit, why.c_str());
    return 0;
}
