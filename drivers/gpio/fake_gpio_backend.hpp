// A GPIO chip in memory, for tests and the bench: records every output level change with the
// clock's time, lets a test inject input edges (with bounce) and make lines busy. Its
// signal-safe writes go to a pipe, so a test can see what a crashing child wrote.
#pragma once

#include <functional>
#include <map>
#include <mutex>
#include <set>

#include "drivers/gpio/gpio_backend.hpp"
#include "drivers/gpio/priority_inheritance_mutex.hpp"
#include "drivers/gpio/step_clock.hpp"

namespace sweepmap {

class FakeGpioBackend : public GpioBackend {
 public:
  struct OutputChange {
    int offset = 0;
    bool high = false;
    int64_t t_ns = 0;  // the clock's time of the write (or of the request)
  };

  explicit FakeGpioBackend(StepClock& clock, int num_lines = 54,
                           std::string name = "fake-gpiochip");
  ~FakeGpioBackend() override;
  FakeGpioBackend(const FakeGpioBackend&) = delete;
  FakeGpioBackend& operator=(const FakeGpioBackend&) = delete;

  // Test set-up.
  void makeBusy(int offset) { busy_.insert(offset); }
  // From now on, writing output `offset` fails (EIO), as on a chip that went away.
  void failWrites(int offset);
  void setInputLevel(int offset, bool high);  // the level an input has when requested
  // Queues an edge of input `offset` at `t_ns` (the level follows it when read).
  void injectEdge(int offset, int64_t t_ns, bool rising);
  // Called after every output change (on the writing thread, without the lock held).
  void setOnOutput(std::function<void(const OutputChange&)> on_output);

  // What the device saw.
  std::vector<OutputChange> outputs() const;
  bool outputLevel(int offset) const;
  int signalPipeReadFd() const { return pipe_[0]; }

  std::string chipName() const override { return name_; }
  void requestOutput(int offset, bool high, const std::string& role) override;
  void requestInput(int offset, GpioPull pull, const std::string& role) override;
  void setOutput(int offset, bool high) override;
  bool inputLevel(int offset) override;
  std::vector<GpioInputEvent> readEvents(int offset) override;
  SignalSafeWrite signalSafeWrite(int offset, bool high) override;

 private:
  void checkLine(int offset, const std::string& role);
  void record(int offset, bool high);

  StepClock& clock_;
  int num_lines_;
  std::string name_;
  std::set<int> busy_;
  std::set<int> failing_;                   // guarded by mutex_
  mutable PriorityInheritanceMutex mutex_;  // the step thread writes, a poll reads
  std::map<int, bool> output_levels_;
  std::vector<OutputChange> outputs_;
  std::map<int, bool> input_levels_;
  std::map<int, std::vector<GpioInputEvent>> pending_events_;
  std::function<void(const OutputChange&)> on_output_;
  int pipe_[2] = {-1, -1};
};

}  // namespace sweepmap
