// GPIO lines as the stepper driver sees them: outputs (STEP, DIR, ENABLE) and an input with
// edge events carrying the kernel's timestamps (the home switch). Two implementations:
// libgpiod 1.6 on a real chip (gpiod_backend.hpp) and a fake one for tests and the bench
// (fake_gpio_backend.hpp).
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/device_uri.hpp"

namespace sweepmap {

// A chip that cannot be opened, a line that is not on it or is busy: one message naming the
// chip, the line and the errno text.
class GpioError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct GpioInputEvent {
  int64_t monotonic_ns = 0;  // the kernel's timestamp, CLOCK_MONOTONIC
  bool rising = false;       // the line went high
};

// What a fatal-signal handler needs to set one output: a plain function and a file
// descriptor, no allocation, no locks (write(2) and ioctl(2) are async-signal-safe).
struct SignalSafeWrite {
  void (*write)(int fd, int value) = nullptr;
  int fd = -1;
  int value = 0;  // the level to write
};

// "GPIO chip 'gpiochip0' line 17 (step)": how errors name a line.
std::string gpioLineName(const std::string& chip, int offset, const std::string& role);

class GpioBackend {
 public:
  virtual ~GpioBackend() = default;
  virtual std::string chipName() const = 0;
  // Requests `offset` as an output driven to `high`. `role` names the line in errors.
  // Throws GpioError.
  virtual void requestOutput(int offset, bool high, const std::string& role) = 0;
  // Requests `offset` as an input with events on both edges and the given bias. Throws
  // GpioError.
  virtual void requestInput(int offset, GpioPull pull, const std::string& role) = 0;
  virtual void setOutput(int offset, bool high) = 0;
  virtual bool inputLevel(int offset) = 0;
  // The input's edges since the last call, oldest first. Never blocks.
  virtual std::vector<GpioInputEvent> readEvents(int offset) = 0;
  // How a fatal-signal handler drives the (requested) output `offset` to `high`.
  virtual SignalSafeWrite signalSafeWrite(int offset, bool high) = 0;
};

}  // namespace sweepmap
