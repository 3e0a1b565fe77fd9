// The GPIO backend on a real chip, through libgpiod 1.6 (Debian 12's, the v1 C API).
//
// The chip is found by gpiod_chip_open_lookup (name, number, label or path). The home input
// is a libgpiod event request on both edges (bias from the URI; the kernel's timestamps,
// CLOCK_MONOTONIC since Linux 5.7 — an older kernel's CLOCK_REALTIME stamps are recognised
// and converted). The outputs are kernel line handles requested with
// GPIO_GET_LINEHANDLE_IOCTL, the same request libgpiod 1.6 makes for an output, because
// libgpiod 1.6 keeps a request's file descriptor private and the fatal-signal handler must
// write the enable line with a single ioctl on it (fatal_signal_guard.hpp).
#pragma once

#include <memory>
#include <string>

#include "drivers/gpio/gpio_backend.hpp"

namespace sweepmap {

// Opens `chip`; lines are requested with `consumer` as their label. Throws GpioError naming
// the chip and the errno text when it cannot be opened.
std::unique_ptr<GpioBackend> openGpiodChip(const std::string& chip,
                                           const std::string& consumer = "sweepmap-motor");

}  // namespace sweepmap
