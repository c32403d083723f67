// Run output folders: created fresh; an existing folder is refused unless the user said --force.
#pragma once
#include <string>

namespace demlab {

// Creates dir (and parents). Throws InputError if it exists and force is false.
void prepare_output_dir(const std::string& dir, bool force);

}  // namespace demlab
