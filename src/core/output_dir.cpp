#include "core/output_dir.h"

#include <filesystem>

#include "core/error.h"

namespace demlab {

void prepare_output_dir(const std::string& dir, bool force) {
    namespace fs = std::filesystem;
    if (dir.empty()) throw InputError("--out '': an output folder needs a name");
    std::error_code ec;
    if (fs::exists(dir, ec)) {
        if (!force)
            throw InputError("output folder '" + dir +
                             "' exists already; choose another --out or pass --force to replace its files");
        if (!fs::is_directory(dir, ec)) throw InputError("output path '" + dir + "' exists and is not a folder");
    }
    fs::create_directories(dir, ec);
    if (ec) throw InputError("cannot create output folder '" + dir + "': " + ec.message());
}

}  // namespace demlab
