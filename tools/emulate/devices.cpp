#include "tools/emulate/devices.hpp"

#include <cmath>
#include <stdexcept>

#include "tools/emulate/scip_device.hpp"
#include "tools/emulate/serial_devices.hpp"

namespace sweepmap {

EmulatedModel emulatedModel(const std::string& name) {
  if (name == "ust10lx") return EmulatedModel::kUst10lx;
  if (name == "x4") return EmulatedModel::kX4;
  if (name == "rplidar") return EmulatedModel::kRplidarA1;
  throw std::invalid_argument("unknown emulated lidar '" + name + "' (ust10lx, x4, rplidar)");
}

int64_t EmulatedClock::counterAt(int64_t power_on_us, int64_t t_us) const {
  const double ms = static_cast<double>(start_ms) + offset_ms +
                    static_cast<double>(t_us - power_on_us) * 1e-3 * (1.0 + drift_ppm * 1e-6);
  const auto ticks = static_cast<int64_t>(std::floor(ms));
  return ((ticks % (int64_t{1} << 24)) + (int64_t{1} << 24)) % (int64_t{1} << 24);
}

BeamOffset beamOffsetOf(EmulatedModel model) {
  if (model == EmulatedModel::kX4) return X4Device::beamOffsetRad;
  return nullptr;
}

std::unique_ptr<EmulatedLidar> makeEmulatedLidar(EmulatedModel model, ScanSource source,
                                                 const EmulatedClock& clock, int64_t power_on_us,
                                                 const std::string& scip_model) {
  switch (model) {
    case EmulatedModel::kUst10lx:
      return std::make_unique<ScipDevice>(std::move(source), clock, power_on_us, scip_model);
    case EmulatedModel::kX4:
      return std::make_unique<X4Device>(std::move(source));
    case EmulatedModel::kRplidarA1:
      return std::make_unique<RplidarDevice>(std::move(source));
  }
  throw std::invalid_argument("unknown emulated lidar");
}

}  // namespace sweepmap
