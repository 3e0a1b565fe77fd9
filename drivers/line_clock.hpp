// Host time of a serial stream's byte offset, for the lidar and odometry sessions: the chunk
// that holds the byte arrived at `arrival` (host µs), and a UART delivers baud/10 bytes per
// second (10 bits per byte, 8N1), so a byte `behind` bytes before the chunk's end left the
// device that much earlier. Without receive times (a raw file, or a session told to ignore
// them): the line time from the stream's first byte.
#pragma once

#include <cmath>
#include <cstdint>

namespace sweepmap {

class LineClock {
 public:
  // `use_arrival` false: every time is the line time from the first byte, whatever arrived.
  explicit LineClock(int baud = 115200, bool use_arrival = true)
      : byte_us_(10e6 / (baud > 0 ? baud : 115200)), use_arrival_(use_arrival) {}

  // The chunk that ends at stream offset `end_offset` arrived at `arrival` (< 0: unknown).
  void chunk(int64_t arrival, int64_t end_offset) {
    arrival_ = arrival;
    end_offset_ = end_offset;
  }
  int64_t at(int64_t offset) const {
    if (!use_arrival_ || arrival_ < 0) {
      return static_cast<int64_t>(std::llround(static_cast<double>(offset) * byte_us_));
    }
    return arrival_ -
           static_cast<int64_t>(std::llround(static_cast<double>(end_offset_ - offset) * byte_us_));
  }
  int64_t arrival() const { return arrival_; }
  double byteUs() const { return byte_us_; }

 private:
  double byte_us_;
  bool use_arrival_;
  int64_t arrival_ = -1;
  int64_t end_offset_ = 0;
};

}  // namespace sweepmap
