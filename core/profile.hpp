// One profile of a line-structured-light profile sensor (rig C) as the library sees it: the
// fields of profile_t (lcmtypes/profile_t.lcm) without LCM. Conversions in processes/convert.
#pragma once

#include <cstdint>
#include <vector>

namespace sweepmap {

struct Profile {
  int64_t utime = 0;           // exposure time [us]
  int64_t sequence = 0;        // the sensor's profile counter
  int32_t sweep_id = 0;        // the turntable's sweep counter
  int64_t encoder_counts = 0;  // turntable encoder at the exposure
  int32_t counts_per_revolution = 0;
  int32_t column_count = 0;
  std::vector<int16_t> column;  // per valid point
  std::vector<float> y_mm, z_mm;
};

}  // namespace sweepmap
