#include "core/output_dir.h"

#include <filesystem>

#include "core/error.h"

namespace demlab {

std::string replaced_output_dir(const std::string& dir) {
    std::string d = dir;
    while (d.size() > 1 && d.back() == '/') d.pop_back();
    return d + ".replaced";
}

void prepare_output_dir(const std::string& dir, bool force) {
    namespace fs = std::filesystem;
    if (dir.empty()) throw InputError("--out '': an output folder needs a name");
    std::error_code ec;
    if (fs::exists(dir, ec)) {
        if (!force)
            throw InputError("output folder '" + dir +
                             "' exists already; choose another --out or pass --force to replace its files");
        if (!fs::is_directory(dir, ec)) throw InputError("output path '" + dir + "' exists and is not a folder");
        // the old content aside (a leftover of an earlier forced run that failed goes first)
        const std::string aside = replaced_output_dir(dir);
        fs::remove_all(aside, ec);
        fs::rename(dir, aside, ec);
        if (ec)
            throw InputError("cannot move the old output folder '" + dir + "' aside to '" + aside + "' for --force: " +
                             ec.message());
    }
    fs::create_directories(dir, ec);
    if (ec) throw InputError("cannot create output folder '" + dir + "': " + ec.message());
}

void remove_replaced_output(const std::string& dir) {
    std::error_code ec;
    std::filesystem::remove_all(replaced_output_dir(dir), ec);
}

}  // namespace demlab
