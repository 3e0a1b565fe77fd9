#include "drivers/gpio/gpio_backend.hpp"

namespace sweepmap {

std::string gpioLineName(const std::string& chip, int offset, const std::string& role) {
  return "GPIO chip '" + chip + "' line " + std::to_string(offset) + " (" + role + ")";
}

}  // namespace sweepmap
