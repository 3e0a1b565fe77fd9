#include "core/version.hpp"

#include "core/version_info.hpp"  // generated at build time (cmake/version_header.cmake)

namespace sweepmap {

std::string versionText() {
  return std::string(SWEEPMAP_VERSION) + " (git " + SWEEPMAP_GIT_COMMIT + ")";
}

}  // namespace sweepmap
