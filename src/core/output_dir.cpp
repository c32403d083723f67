#include "core/output_dir.h"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

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
// The line by which a forced output and the old folder it moved aside name each other: the same
// token in both markers. Only a folder carrying the token of the output in hand is ever removed
// or moved back, never a folder that merely has the name (a user's own run called X.replaced).
constexpr const char* kAsidePrefix = "old folder moved aside: ";

// The marker's lines before its file list but its aside line (the head), and the list's lines;
// whether it has the list.
bool read_marker(const std::string& dir, std::string& head, std::vector<std::string>* files) {
    std::ifstream in(marker_path(dir));
    std::string line;
    bool listed = false;
    while (std::getline(in, line)) {
        if (listed) {
            if (files) files->push_back(line);
        } else if (line + "\n" == kFilesLine) {
            listed = true;
        } else if (line.compare(0, std::string(kAsidePrefix).size(), kAsidePrefix) != 0) {
            head += line + "\n";  // (an aside line is the caller's to write)
        }
    }
    return listed;
}

// The aside token in dir's marker ("" for none).
std::string aside_token(const std::string& dir) {
    std::ifstream in(marker_path(dir));
    const std::string prefix = kAsidePrefix;
    for (std::string line; std::getline(in, line);) {
        if (line + "\n" == kFilesLine) break;
        if (line.compare(0, prefix.size(), prefix) == 0) return line.substr(prefix.size());
    }
    return "";
}

// A token no other folder carries: 128 random bits.
std::string new_aside_token() {
    std::random_device rd;
    std::ostringstream t;
    t << std::hex;
    for (int k = 0; k < 4; ++k) t << rd();
    return t.str();
}

// The names a forced output may move its old folder to: X.replaced, X.replaced-2, ... (k = 1 to
// kAsideNames).
constexpr int kAsideNames = 1000;
std::string aside_name(const std::string& dir, int k) {
    const std::string base = replaced_output_dir(dir);
    return k == 1 ? base : base + "-" + std::to_string(k);
}

// A marker's text: the head, the aside line when there is a token, the file list when given.
std::string marker_text(const std::string& head, const std::string& token, const std::vector<std::string>* files) {
    std::string text = head + (token.empty() ? "" : kAsidePrefix + token + "\n");
    if (files) {
        text += kFilesLine;
        for (const std::string& f : *files) text += f + "\n";
    }
    return text;
}

// The old folder the output in dir moved aside, if it is still there and carries dir's token.
std::string own_aside(const std::string& dir) {
    std::error_code ec;
    const std::string token = aside_token(dir);
    if (token.empty()) return "";
    for (int k = 1; k <= kAsideNames; ++k) {
        const std::string aside = aside_name(dir, k);
        if (!fs::exists(fs::symlink_status(aside, ec))) continue;
        if (!fs::is_symlink(fs::symlink_status(aside, ec)) && is_demlab_output(aside) && aside_token(aside) == token)
            return aside;
    }
    return "";
}

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
    std::string head;
    return read_marker(dir, head, &files);
}

// The entries below dir that its marker does not list (prefixed with `prefix`), and those of
// the folders with their own marker inside it that it lists, which keep their own lists. A
// marked folder the list does not name is another output the user made there (a run, a
// comparison, frames rendered elsewhere): foreign as a whole, never deleted with this one. Only
// a run's own plots/ and frames/ belong to it unlisted: earlier builds drew the plots after the
// run's list was written, and a plot or render stopped before its end does not list them.
void collect_foreign(const std::string& dir, const std::string& prefix, std::vector<std::string>& foreign) {
    std::vector<std::string> recorded;
    const bool listed = recorded_entries(dir, recorded);  // no list: all of it is demlab's as before
    for (const std::string& e : listed_entries(dir)) {
        const std::string path = dir + "/" + e;
        // demlab makes no symbolic links: one is the user's, and writing to its name would
        // write to the file it points at, outside the folder (a plot drawn over a user's file)
        std::error_code ec;
        if (fs::is_symlink(fs::symlink_status(path, ec))) foreign.push_back(prefix + e);
        else if (!listed) continue;
        else if (is_demlab_output(path) && (std::binary_search(recorded.begin(), recorded.end(), e) ||
                                            (prefix.empty() && (e == "plots" || e == "frames"))))
            collect_foreign(path, prefix + e + "/", foreign);
        else if (!std::binary_search(recorded.begin(), recorded.end(), e)) foreign.push_back(prefix + e);
    }
}

// Refuses a --force that would delete what the user put into a completed output folder (notes,
// an analysis) beside demlab's own files: anything its marker does not list.
void check_only_demlab_files(const std::string& dir,
                             const std::string& consequence = "--force would delete them",
                             const std::string& way_out = "choose another --out") {
    std::vector<std::string> foreign;
    collect_foreign(dir, "", foreign);
    if (foreign.empty()) return;
    std::string names;
    for (size_t i = 0; i < foreign.size() && i < 5; ++i) names += (i ? ", '" : "'") + foreign[i] + "'";
    if (foreign.size() > 5) names += " and " + std::to_string(foreign.size() - 5) + " more";
    throw InputError("output folder '" + dir + "' holds " + std::to_string(foreign.size()) +
                     (foreign.size() == 1 ? " entry" : " entries") + " demlab did not write (" + names +
                     "); " + consequence + ": move them out of the folder first, or " + way_out);
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

void check_output_path(const std::string& dir) {
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
}

void check_output_dir(const std::string& dir, bool force, const std::vector<std::string>& inputs) {
    check_output_path(dir);
    std::error_code ec;
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

void check_regenerated_output_dir(const std::string& dir) {
    std::error_code ec;
    if (!fs::exists(fs::symlink_status(dir, ec))) return;
    if (fs::is_symlink(fs::symlink_status(dir, ec)) || !fs::is_directory(dir, ec) || !is_demlab_output(dir))
        throw InputError("'" + dir + "' exists and was not made by demlab (it has no " + kOutputMarker +
                         " marker); demlab writes only into folders it made: move or rename it first");
    check_only_demlab_files(dir, "writing there would overwrite them or count them as demlab's",
                            "delete the folder to have it made anew");
}

void create_output_tree(const std::string& dir, const std::string& path) {
    std::error_code ec;
    fs::create_directories(path, ec);
    if (!ec) return;
    std::error_code ignore;
    if (fs::is_symlink(fs::symlink_status(dir, ignore)) && !fs::exists(dir, ignore))
        throw InputError("cannot create output folder '" + dir + "': it is a symbolic link to '" +
                         fs::read_symlink(dir, ignore).string() + "', which does not exist");
    throw InputError("cannot create output folder '" + dir + "': " + ec.message());
}

void mark_output_dir(const std::string& dir) {
    if (!is_demlab_output(dir)) write_file_atomic(marker_path(dir), kMarkerHead);
}

void prepare_output_dir(const std::string& dir, bool force, const std::vector<std::string>& inputs) {
    check_output_dir(dir, force, inputs);
    std::error_code ec;
    std::string token, moved;
    if (fs::exists(dir, ec)) {
        std::vector<std::string> listed;
        if (!own_aside(dir).empty() && !recorded_entries(dir, listed)) {
            // an unfinished forced output (no file list) whose own old folder is still aside (a
            // run interrupted before its first checkpoint, rerun by resume, or forced again):
            // the unfinished output is replaced, and the new one takes over its token, so that
            // the old folder goes once the new output is complete
            token = aside_token(dir);
            fs::remove_all(dir, ec);
            if (ec) throw InputError("cannot remove the unfinished output folder '" + dir + "' for --force: " + ec.message());
        } else {
            // the old content aside, under the first free name (X.replaced, X.replaced-2, ...):
            // whatever already has such a name (a user's own folder, say) stays as it is. Both
            // markers get the same token, so that only this folder is removed once the new
            // output is complete, or moved back if it fails.
            std::string aside;
            for (int k = 1; k <= kAsideNames && aside.empty(); ++k)
                if (!fs::exists(fs::symlink_status(aside_name(dir, k), ec))) aside = aside_name(dir, k);
            if (aside.empty())
                throw InputError("cannot move the old output folder '" + dir + "' aside: '" + aside_name(dir, 1) + "' to '" +
                                 aside_name(dir, kAsideNames) + "' all exist; move or delete them yourself");
            token = new_aside_token();
            // the token into the old marker before anything moves (a folder that cannot take it,
            // read-only say, is refused here, still in place)
            std::string head;
            std::vector<std::string> files;
            const bool has_list = read_marker(dir, head, &files);
            write_file_atomic(marker_path(dir), marker_text(head, token, has_list ? &files : nullptr));
            fs::rename(dir, aside, ec);
            if (ec)
                throw InputError("cannot move the old output folder '" + dir + "' aside to '" + aside + "' for --force: " +
                                 ec.message());
            moved = aside;
        }
    }
    try {
        fs::create_directories(dir, ec);
        if (ec) throw InputError("cannot create output folder '" + dir + "': " + ec.message());
        write_file_atomic(marker_path(dir), marker_text(kMarkerHead, token, nullptr));
    } catch (...) {
        if (!moved.empty()) {  // the old folder back where it was
            std::error_code ignore;
            fs::remove_all(dir, ignore);
            fs::rename(moved, dir, ignore);
        }
        throw;
    }
}

void record_output_files(const std::string& dir) {
    if (!is_demlab_output(dir)) return;
    const std::vector<std::string> entries = listed_entries(dir);
    for (const std::string& e : entries)
        if (is_demlab_output(dir + "/" + e)) record_output_files(dir + "/" + e);
    write_file_atomic(marker_path(dir), marker_text(kMarkerHead, aside_token(dir), &entries));
}

void remove_replaced_output(const std::string& dir) {
    record_output_files(dir);  // complete: what is in it now is demlab's
    std::error_code ec;
    const std::string aside = own_aside(dir);
    if (!aside.empty()) fs::remove_all(aside, ec);
}

void abandon_output(const std::string& dir) {
    std::error_code ec;
    if (!is_demlab_output(dir)) return;
    const std::string aside = own_aside(dir);
    fs::remove_all(dir, ec);
    if (!aside.empty()) fs::rename(aside, dir, ec);
}

}  // namespace demlab
