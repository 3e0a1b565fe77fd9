#include "drivers/gpio/gpiod_backend.hpp"

#include <fcntl.h>
#include <gpiod.h>
#include <linux/gpio.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <map>

#include "drivers/gpio/step_clock.hpp"

namespace sweepmap {
namespace {

void writeLineHandle(int fd, int value) {
  gpiohandle_data data{};
  data.values[0] = static_cast<uint8_t>(value);
  ioctl(fd, GPIOHANDLE_SET_LINE_VALUES_IOCTL, &data);
}

std::string errnoText(int err) { return err != 0 ? std::strerror(err) : "unknown error"; }

int64_t toNs(const timespec& ts) { return int64_t(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec; }

// Kernels before 5.7 stamp line events with CLOCK_REALTIME: whichever clock the stamp is
// nearer to now is the one it was taken on.
int64_t eventMonotonicNs(const timespec& ts) {
  const int64_t t = toNs(ts);
  timespec real{};
  clock_gettime(CLOCK_REALTIME, &real);
  const int64_t mono = monotonicNowNs();
  const int64_t real_ns = toNs(real);
  return std::llabs(t - real_ns) < std::llabs(t - mono) ? t - (real_ns - mono) : t;
}

class GpiodBackend : public GpioBackend {
 public:
  GpiodBackend(const std::string& chip, std::string consumer) : consumer_(std::move(consumer)) {
    errno = 0;
    chip_ = gpiod_chip_open_lookup(chip.c_str());
    if (chip_ == nullptr) {
      throw GpioError("GPIO chip '" + chip + "': cannot open it: " + errnoText(errno));
    }
    name_ = gpiod_chip_name(chip_);
    const std::string dev = "/dev/" + name_;
    chip_fd_ = ::open(dev.c_str(), O_RDWR | O_CLOEXEC);
    if (chip_fd_ < 0) {
      const int err = errno;
      gpiod_chip_close(chip_);
      throw GpioError("GPIO chip '" + chip + "' (" + dev + "): cannot open it: " + errnoText(err));
    }
  }

  ~GpiodBackend() override {
    // After release the kernel leaves an output's level undefined: the enable line's external
    // pull decides (README, "Rig A's stepper and switch on GPIO").
    for (const auto& [offset, fd] : handles_) ::close(fd);
    for (const auto& [offset, line] : inputs_) gpiod_line_release(line);
    ::close(chip_fd_);
    gpiod_chip_close(chip_);
  }

  std::string chipName() const override { return name_; }

  void requestOutput(int offset, bool high, const std::string& role) override {
    checkOffset(offset, role);
    gpiohandle_request request{};
    request.lineoffsets[0] = static_cast<uint32_t>(offset);
    request.lines = 1;
    request.flags = GPIOHANDLE_REQUEST_OUTPUT;
    request.default_values[0] = high ? 1 : 0;
    std::strncpy(request.consumer_label, consumer_.c_str(), sizeof(request.consumer_label) - 1);
    if (ioctl(chip_fd_, GPIO_GET_LINEHANDLE_IOCTL, &request) < 0) {
      throw requestError(offset, role, errno);
    }
    handles_[offset] = request.fd;
  }

  void requestInput(int offset, GpioPull pull, const std::string& role) override {
    checkOffset(offset, role);
    gpiod_line* line = gpiod_chip_get_line(chip_, static_cast<unsigned>(offset));
    const int flags = pull == GpioPull::kUp     ? GPIOD_LINE_REQUEST_FLAG_BIAS_PULL_UP
                      : pull == GpioPull::kDown ? GPIOD_LINE_REQUEST_FLAG_BIAS_PULL_DOWN
                                                : GPIOD_LINE_REQUEST_FLAG_BIAS_DISABLE;
    if (line == nullptr ||
        gpiod_line_request_both_edges_events_flags(line, consumer_.c_str(), flags) < 0) {
      throw requestError(offset, role, errno);
    }
    inputs_[offset] = line;
  }

  void setOutput(int offset, bool high) override {
    const auto it = handles_.find(offset);
    if (it == handles_.end()) throw GpioError(gpioLineName(name_, offset, "?") + ": not requested");
    gpiohandle_data data{};
    data.values[0] = high ? 1 : 0;
    if (ioctl(it->second, GPIOHANDLE_SET_LINE_VALUES_IOCTL, &data) < 0) {
      throw GpioError(gpioLineName(name_, offset, "output") +
                      ": cannot set it: " + errnoText(errno));
    }
  }

  bool inputLevel(int offset) override {
    const int v = gpiod_line_get_value(input(offset));
    if (v < 0) {
      throw GpioError(gpioLineName(name_, offset, "input") +
                      ": cannot read it: " + errnoText(errno));
    }
    return v == 1;
  }

  std::vector<GpioInputEvent> readEvents(int offset) override {
    gpiod_line* line = input(offset);
    std::vector<GpioInputEvent> events;
    const timespec no_wait{0, 0};
    while (gpiod_line_event_wait(line, &no_wait) == 1) {
      gpiod_line_event buffer[16];
      const int n = gpiod_line_event_read_multiple(line, buffer, 16);
      if (n <= 0) break;
      for (int i = 0; i < n; ++i) {
        events.push_back(
            {eventMonotonicNs(buffer[i].ts), buffer[i].event_type == GPIOD_LINE_EVENT_RISING_EDGE});
      }
    }
    return events;
  }

  SignalSafeWrite signalSafeWrite(int offset, bool high) override {
    const auto it = handles_.find(offset);
    if (it == handles_.end()) return {};
    return {writeLineHandle, it->second, high ? 1 : 0};
  }

 private:
  void checkOffset(int offset, const std::string& role) const {
    const int lines = static_cast<int>(gpiod_chip_num_lines(chip_));
    if (offset < 0 || offset >= lines) {
      throw GpioError(gpioLineName(name_, offset, role) + ": not on this chip (" +
                      std::to_string(lines) + " lines): " + errnoText(EINVAL));
    }
  }

  GpioError requestError(int offset, const std::string& role, int err) const {
    std::string text = gpioLineName(name_, offset, role) + ": cannot request it: " + errnoText(err);
    gpiod_line* line = gpiod_chip_get_line(chip_, static_cast<unsigned>(offset));
    if (line != nullptr && gpiod_line_update(line) == 0 && gpiod_line_is_used(line)) {
      const char* consumer = gpiod_line_consumer(line);
      text += std::string(" (used by '") + (consumer != nullptr ? consumer : "?") + "')";
    }
    return GpioError(text);
  }

  gpiod_line* input(int offset) const {
    const auto it = inputs_.find(offset);
    if (it == inputs_.end()) throw GpioError(gpioLineName(name_, offset, "?") + ": not requested");
    return it->second;
  }

  std::string consumer_;
  gpiod_chip* chip_ = nullptr;
  std::string name_;
  int chip_fd_ = -1;
  std::map<int, int> handles_;
  std::map<int, gpiod_line*> inputs_;
};

}  // namespace

std::unique_ptr<GpioBackend> openGpiodChip(const std::string& chip, const std::string& consumer) {
  return std::make_unique<GpiodBackend>(chip, consumer);
}

}  // namespace sweepmap
