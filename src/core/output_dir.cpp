#include "core/output_dir.h"

#include <algorithm>
#include <filesystem>
#include <fstream>

#include "core/error.h"
#include "core/fileio.h"

namespace demlab {

namespace fs = std::filesystem;

namespace {

// An absolute path with symbolic links and `.`/`..` resolved as far as it exists.
fs::path resolved(const std::string& p) {
    std::error_code ec;
    fs::path r = fs::weakly_canonical(fs::absolute(p, ec), ec);
    if (ec) r = fs::absolute(p, ec).lexically_normal();
    return r;
}

std::string marker_path(const std::string& dir) { return dir + "/" + kOutputMarker; }

constexpr const char* kMarkerHead = "made by demlab; `--force` may replace this folder\n";
constexpr const char* kFilesLine = "files it wrote (a --force keeps off any other):\n";

// Every file and folder below dir (relative, '/'-separated, sorted), its marker and a run's
// lock left out. A folder that carries its own marker (frames/, plots/, made by a later
// command) is listed, its content not: that folder keeps its own list.
std::vector<std::string> listed_entries(const std::string& dir) {
    std::vector<std::string> out;
    std::error_code ec;
    auto it = fs::recursive_directory_iterator(dir, fs::directory_options::none, ec);
    for (; !ec && it != fs::recursive_directory_iterator(); it.increment(ec)) {
        const fs::path rel = it->path().lexically_relative(dir);
        if (rel == kOutputMarker || rel == kRunLockName) continue;  // the folder's own bookkeeping
        out.push_back(rel.generic_string());
        if (it->is_directory(ec) && !it->is_symlink(ec) && is_demlab_output(it->path().string())) it.disable_recursion_pending();
    }
    std::sort(out.begin(), out.end());
    return out;
}

// The files a completed output recorded in its marker; false for a marker without the list (a
// folder still being written, or made by an earlier build).
bool recorded_entries(const std::string& dir, std::vector<std::string>& files) {
    std::ifstream in(marker_path(dir));
    std::string line;
    bool listed = false;
    while (std::getline(in, line)) {
        if (listed) files.push_back(line);
        else if (line + "\n" == kFilesLine) listed = true;
    }
    return listed;
}

// The entries below dir that its marker does not list (prefixed with `prefix`), and those of
// the folders with their own marker inside it (frames/, plots/), which keep their own lists.
void collect_foreign(const std::string& dir, const std::string& prefix, std::vector<std::string>& foreign) {
    std::vector<std::string> recorded;
    if (!recorded_entries(dir, recorded)) return;  // no list: all of it is demlab's as before
    for (const std::string& e : listed_entries(dir)) {
        const std::string path = dir + "/" + e;
        if (is_demlab_output(path)) collect_foreign(path, prefix + e + "/", foreign);
        else if (!std::binary_search(recorded.begin(), recorded.end(), e)) foreign.push_back(prefix + e);
    }
}

// Refuses a --force that would delete what the user put into a completed output folder (notes,
// an analysis) beside demlab's own files: anything its marker does not list.
void check_only_demlab_files(const std::string& dir) {
    std::vector<std::string> foreign;
    collect_foreign(dir, "", foreign);
    if (foreign.empty()) return;
    std::string names;
    for (size_t i = 0; i < foreign.size() && i < 5; ++i) names += (i ? ", '" : "'") + foreign[i] + "'";
    if (foreign.size() > 5) names += " and " + std::to_string(foreign.size() - 5) + " more";
    throw InputError("output folder '" + dir + "' holds " + std::to_string(foreign.size()) +
                     (foreign.size() == 1 ? " entry" : " entries") + " demlab did not write (" + names +
                     "); --force would delete them: move them out of the folder first, or choose another --out");
}

}  // namespace

bool path_within(const std::string& path, const std::string& base) {
    const fs::path p = resolved(path), b = resolved(base);
    auto pi = p.begin();
    for (auto bi = b.begin(); bi != b.end(); ++bi, ++pi) {
        if (bi->empty()) continue;  // a trailing separator
        if (pi == p.end() || *pi != *bi) return false;
    }
    return true;
}

bool is_demlab_output(const std::string& dir) {
    std::error_code ec;
    return fs::is_regular_file(marker_path(dir), ec);
}

std::string replaced_output_dir(const std::string& dir) {
    std::string d = dir;
    while (d.size() > 1 && d.back() == '/') d.pop_back();
    return d + ".replaced";
}

void check_output_dir(const std::string& dir, bool force, const std::vector<std::string>& inputs) {
    if (dir.empty()) throw InputError("--out '': an output folder needs a name");
    std::error_code ec;
    // a `..` after a folder that does not exist: the system cannot resolve it (so the folder
    // would seem new), while making the folders would resolve it and write into an existing one
    fs::path prefix;
    for (const fs::path& part : fs::path(dir)) {
        if (part == ".." && !prefix.empty() && !fs::is_directory(prefix, ec))
            throw InputError("--out '" + dir + "': its '..' follows '" + prefix.string() +
                             "', which does not exist; give the folder without it ('" +
                             fs::path(dir).lexically_normal().string() + "')");
        prefix /= part;
    }
    if (!fs::exists(fs::symlink_status(dir, ec))) return;
    if (!force)
        throw InputError("output folder '" + dir +
                         "' exists already; choose another --out or pass --force to replace its files");
    if (fs::is_symlink(fs::symlink_status(dir, ec)))
        throw InputError("output path '" + dir + "' is a symbolic link; --force replaces only a folder demlab made");
    if (!fs::is_directory(dir, ec)) throw InputError("output path '" + dir + "' exists and is not a folder");
    for (const std::string& in : inputs)
        if (!in.empty() && path_within(in, dir))
            throw InputError("--out '" + dir + "' " + (path_within(dir, in) ? "is" : "holds") + " the input '" + in +
                             "'; --force would delete it: choose another --out");
    if (path_within(fs::current_path(ec).string(), dir))
        throw InputError("--out '" + dir +
                         "' holds the working directory; --force would delete it: choose another --out");
    if (!is_demlab_output(dir))
        throw InputError("output folder '" + dir + "' was not made by demlab (it has no " + kOutputMarker +
                         " marker); --force replaces only demlab's own output folders, never other files: "
                         "choose another --out, or move or delete the folder yourself");
    check_only_demlab_files(dir);
}

void mark_output_dir(const std::string& dir) {
    if (!is_demlab_output(dir)) write_file_atomic(marker_path(dir), kMarkerHead);
}

void prepare_output_dir(const std::string& dir, bool force, const std::vector<std::string>& inputs) {
    check_output_dir(dir, force, inputs);
    std::error_code ec;
    if (fs::exists(dir, ec)) {
        // the old content aside (a leftover of an earlier forced run that failed goes first,
        // if it too is demlab's)
        const std::string aside = replaced_output_dir(dir);
        if (fs::exists(fs::symlink_status(aside, ec))) {
            if (!is_demlab_output(aside) || fs::is_symlink(fs::symlink_status(aside, ec)))
                throw InputError("cannot move the old output folder '" + dir + "' aside: '" + aside +
                                 "' exists and was not made by demlab; move or delete it yourself");
            fs::remove_all(aside, ec);
        }
        fs::rename(dir, aside, ec);
        if (ec)
            throw InputError("cannot move the old output folder '" + dir + "' aside to '" + aside + "' for --force: " +
                             ec.message());
    }
    fs::create_directories(dir, ec);
    if (ec) throw InputError("cannot create output folder '" + dir + "': " + ec.message());
    mark_output_dir(dir);
}

void record_output_files(const std::string& dir) {
    if (!is_demlab_output(dir)) return;
    std::string marker = std::string(kMarkerHead) + kFilesLine;
    for (const std::string& e : listed_entries(dir)) {
        marker += e + "\n";
        if (is_demlab_output(dir + "/" + e)) record_output_files(dir + "/" + e);
    }
    write_file_atomic(marker_path(dir), marker);
}

void remove_replaced_output(const std::string& dir) {
    record_output_files(dir);  // complete: what is in it now is demlab's
    std::error_code ec;
    const std::string aside = replaced_output_dir(dir);
    if (is_demlab_output(aside)) fs::remove_all(aside, ec);
}

void abandon_output(const std::string& dir) {
    std::error_code ec;
    if (!is_demlab_output(dir)) return;
    fs::remove_all(dir, ec);
    const std::string aside = replaced_output_dir(dir);
    if (is_demlab_output(aside)) fs::rename(aside, dir, ec);
}

}  // namespace demlab
