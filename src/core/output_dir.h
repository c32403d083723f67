// Run output folders: created fresh; an existing folder is refused unless the user said --force.
// With --force the old folder is moved aside (FOLDER.replaced) and a new one made, so nothing
// of the old run stays beside the new one's files; the old one is removed only when the new
// output is complete (remove_replaced_output), so a failed run loses nothing.
#pragma once
#include <string>

namespace demlab {

// Creates dir (and parents). Throws InputError if it exists and force is false.
void prepare_output_dir(const std::string& dir, bool force);

// The folder a forced prepare_output_dir moved the old one to.
std::string replaced_output_dir(const std::string& dir);

// Removes the old folder a forced prepare_output_dir moved aside (nothing when there is none).
void remove_replaced_output(const std::string& dir);

}  // namespace demlab
