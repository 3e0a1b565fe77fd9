// A stepper motor with its driver board and the photoelectric home switch, as the motor
// process sees it. There is no encoder: the controller knows only what it commanded.
#pragma once

#include <cstdint>
#include <vector>

namespace sweepmap {

struct StepperCommand {
  enum class Kind {
    kRun,     // ramp (at accel) to velocity_rad_s (signed) and hold it
    kStop,    // ramp (at accel) down to standstill
    kMoveBy,  // from standstill, turn by delta_rad: trapezoid with max |velocity| and accel
  };
  Kind kind = Kind::kStop;
  double velocity_rad_s = 0.0;  // kRun: target (signed); kMoveBy: max speed (> 0)
  double accel_rad_s2 = 0.0;    // ramp magnitude (> 0)
  double delta_rad = 0.0;       // kMoveBy only
};

struct SwitchEdge {
  int64_t utime = 0;     // when the device reported the edge [us]
  bool blocked = false;  // true: the shading sheet entered the beam
};

class StepperDevice {
 public:
  virtual ~StepperDevice() = default;
  // Issues a command at `now_utime`; the device executes it after its own response time.
  virtual void command(int64_t now_utime, const StepperCommand& cmd) = 0;
  // Switch edges reported up to `now_utime`, in time order, each once.
  virtual std::vector<SwitchEdge> poll(int64_t now_utime) = 0;
  // Current switch level at the last poll (true = blocked).
  virtual bool switchBlocked() const = 0;
};

}  // namespace sweepmap
