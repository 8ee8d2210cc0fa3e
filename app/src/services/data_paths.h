// Where the program finds the data it ships: courses, presets and studies. Never through the
// source tree. Each sub-folder is taken from the first of these places that has it:
//   1. $AT_DATA_DIR, when set: an explicit override (a folder holding any of courses/, presets/,
//      studies/; what it lacks comes from the places below);
//   2. <folder of the executable>/../share/anatomy-tutor: an installed copy
//      (<prefix>/bin/anatomy-tutor beside <prefix>/share/anatomy-tutor), which the build tree
//      mirrors (build/app/anatomy-tutor beside build/share/anatomy-tutor, a link CMake makes to
//      the checkout's data/);
//   3. <install prefix>/share/anatomy-tutor as configured at build time, for a binary moved away
//      from its prefix.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace at::app {

// The places above, in order (the first only when AT_DATA_DIR is set).
std::vector<std::filesystem::path> dataSearchPath();

// <place>/<name> for the first place that has it; when none has it, the most likely place
// (AT_DATA_DIR's, else the executable's), so that errors name a path a user can check.
std::filesystem::path dataSubdirectory(const std::string& name);

}  // namespace at::app
