#include "drivers/gpio/fake_gpio_backend.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace sweepmap {
namespace {

void writeToPipe(int fd, int value) {
  const char byte = static_cast<char>(value);
  [[maybe_unused]] const ssize_t n = ::write(fd, &byte, 1);
}

}  // namespace

FakeGpioBackend::FakeGpioBackend(StepClock& clock, int num_lines, std::string name)
    : clock_(clock), num_lines_(num_lines), name_(std::move(name)) {
  if (::pipe2(pipe_, O_CLOEXEC | O_NONBLOCK) != 0) pipe_[0] = pipe_[1] = -1;
}

FakeGpioBackend::~FakeGpioBackend() {
  for (int fd : pipe_) {
    if (fd >= 0) ::close(fd);
  }
}

void FakeGpioBackend::checkLine(int offset, const std::string& role) {
  if (offset < 0 || offset >= num_lines_) {
    throw GpioError(gpioLineName(name_, offset, role) + ": not on this chip (" +
                    std::to_string(num_lines_) + " lines): " + std::strerror(EINVAL));
  }
  if (busy_.count(offset) != 0 || output_levels_.count(offset) != 0 ||
      input_levels_.count(offset) != 0) {
    throw GpioError(gpioLineName(name_, offset, role) +
                    ": cannot request it: " + std::strerror(EBUSY));
  }
}

void FakeGpioBackend::requestOutput(int offset, bool high, const std::string& role) {
  {
    std::lock_guard<PriorityInheritanceMutex> lock(mutex_);
    checkLine(offset, role);
  }
  record(offset, high);
}

void FakeGpioBackend::requestInput(int offset, GpioPull, const std::string& role) {
  std::lock_guard<PriorityInheritanceMutex> lock(mutex_);
  const auto level = input_levels_.find(offset);
  const bool initial = level == input_levels_.end() ? false : level->second;
  if (level != input_levels_.end()) input_levels_.erase(level);
  checkLine(offset, role);
  input_levels_[offset] = initial;
}

void FakeGpioBackend::setInputLevel(int offset, bool high) {
  std::lock_guard<PriorityInheritanceMutex> lock(mutex_);
  input_levels_[offset] = high;
}

void FakeGpioBackend::injectEdge(int offset, int64_t t_ns, bool rising) {
  std::lock_guard<PriorityInheritanceMutex> lock(mutex_);
  pending_events_[offset].push_back({t_ns, rising});
}

void FakeGpioBackend::setOnOutput(std::function<void(const OutputChange&)> on_output) {
  std::lock_guard<PriorityInheritanceMutex> lock(mutex_);
  on_output_ = std::move(on_output);
}

void FakeGpioBackend::record(int offset, bool high) {
  OutputChange change{offset, high, clock_.nowNs()};
  std::function<void(const OutputChange&)> on_output;
  {
    std::lock_guard<PriorityInheritanceMutex> lock(mutex_);
    output_levels_[offset] = high;
    outputs_.push_back(change);
    on_output = on_output_;
  }
  if (on_output) on_output(change);
}

void FakeGpioBackend::failWrites(int offset) {
  std::lock_guard<PriorityInheritanceMutex> lock(mutex_);
  failing_.insert(offset);
}

void FakeGpioBackend::setOutput(int offset, bool high) {
  {
    std::lock_guard<PriorityInheritanceMutex> lock(mutex_);
    if (failing_.count(offset) != 0) {
      throw GpioError(gpioLineName(name_, offset, "output") +
                      ": cannot set it: " + std::strerror(EIO));
    }
  }
  record(offset, high);
}

bool FakeGpioBackend::inputLevel(int offset) {
  std::lock_guard<PriorityInheritanceMutex> lock(mutex_);
  return input_levels_[offset];
}

std::vector<GpioInputEvent> FakeGpioBackend::readEvents(int offset) {
  std::lock_guard<PriorityInheritanceMutex> lock(mutex_);
  std::vector<GpioInputEvent> events;
  events.swap(pending_events_[offset]);
  if (!events.empty()) input_levels_[offset] = events.back().rising;
  return events;
}

SignalSafeWrite FakeGpioBackend::signalSafeWrite(int, bool high) {
  return {writeToPipe, pipe_[1], high ? 1 : 0};
}

std::vector<FakeGpioBackend::OutputChange> FakeGpioBackend::outputs() const {
  std::lock_guard<PriorityInheritanceMutex> lock(mutex_);
  return outputs_;
}

bool FakeGpioBackend::outputLevel(int offset) const {
  std::lock_guard<PriorityInheritanceMutex> lock(mutex_);
  const auto it = output_levels_.find(offset);
  return it != output_levels_.end() && it->second;
}

}  // namespace sweepmap
