// The version every sweepmap command and process prints for --version: the CMake project
// version and the git commit the build was made from ("unknown" outside a git checkout).
#pragma once

#include <string>

namespace sweepmap {

// "0.1.0 (git 1a2b3c4d5e6f)"
std::string versionText();

}  // namespace sweepmap
