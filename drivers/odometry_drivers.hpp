// Rig B's real odometry devices on serial ports: the HiPNUC HI219 IMU
// (drivers/protocols/hi219.hpp) and our wheel board (drivers/protocols/wheelboard.hpp), each a
// StreamDevice (connect, reconnect with backoff, counters, events) around a session that turns
// their bytes into samples. The sessions have no I/O: `sweepmap decode` runs them on captures.
//
// Time stamps. Both devices stamp their data with their own clocks (the HI219's 0x91 record:
// milliseconds since power-on; the wheel board: microseconds). With receive times (live, or a
// capture), a stamp is mapped to host time by DeviceClockSync: the stamps' offset and drift
// from the lower envelope of (arrival - stamp), so the host's read jitter does not reach the
// samples. Frames without a stamp (an HI219 configured without 0x91) get the receive time of
// their first byte (the chunk's receive time less the line time of the bytes after it). Raw
// bytes without receive times: the device's own clock, or the line time from the first byte.
#pragma once

#include <cmath>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "devices/odometry_devices.hpp"
#include "drivers/clock_sync.hpp"
#include "drivers/line_clock.hpp"
#include "drivers/protocols/hi219.hpp"
#include "drivers/protocols/wheelboard.hpp"
#include "drivers/stream_device.hpp"

namespace sweepmap {

// Cumulative counts of a 32-bit counter that wraps.
struct Unwrap32 {
  bool have = false;
  uint32_t last = 0;
  int64_t value = 0;
  int64_t operator()(uint32_t raw) {
    value = have ? value + static_cast<int32_t>(raw - last) : static_cast<int32_t>(raw);
    have = true;
    last = raw;
    return value;
  }
};

// HI219 bytes → IMU samples (frames with both acceleration and angular rate; the others are
// counted, not used). `raw`: no receive times (arrival_utime ignored).
class Hi219Session {
 public:
  using Decoder = hi219::Decoder;
  using Event = hi219::Event;
  Hi219Session(int baud, bool raw);
  // Returns the samples completed.
  int onBytes(const uint8_t* data, size_t size, int64_t arrival_utime,
              std::vector<ImuSample>* samples, std::vector<std::string>* errors);
  // The end of the input (a file): the bytes held for a frame are searched again.
  int finish(std::vector<ImuSample>* samples, std::vector<std::string>* errors);
  const DecoderCounters& counters() const { return decoder_.counters(); }
  int64_t clockResets() const { return clock_.resets(); }
  int userId() const { return user_id_; }
  void reset();

 private:
  int decode(const uint8_t* data, size_t size, int64_t arrival_utime, bool at_end,
             std::vector<ImuSample>* samples, std::vector<std::string>* errors);
  hi219::Decoder decoder_;
  DeviceClockSync clock_;
  LineClock line_;
  bool raw_;
  int64_t fed_ = 0;
  int user_id_ = -1;
  std::vector<hi219::Event> events_;
};

// Wheel board bytes → encoder readings (counts unwrapped). SPEED frames in the stream (a
// capture of both directions) are skipped.
class WheelBoardSession {
 public:
  using Decoder = wheelboard::Decoder;
  using Event = wheelboard::Event;
  WheelBoardSession(int baud, bool raw);
  int onBytes(const uint8_t* data, size_t size, int64_t arrival_utime,
              std::vector<WheelTicks>* ticks, std::vector<std::string>* errors);
  // The end of the input (a file): the bytes held for a frame are searched again.
  int finish(std::vector<WheelTicks>* ticks, std::vector<std::string>* errors);
  const DecoderCounters& counters() const { return decoder_.counters(); }
  int64_t framesLost() const { return decoder_.sequenceGaps(); }
  int64_t clockResets() const { return clock_.resets(); }
  void reset();

 private:
  int decode(const uint8_t* data, size_t size, int64_t arrival_utime, bool at_end,
             std::vector<WheelTicks>* ticks, std::vector<std::string>* errors);
  wheelboard::Decoder decoder_;
  DeviceClockSync clock_;
  LineClock line_;
  bool raw_;
  int64_t fed_ = 0;
  Unwrap32 left_, right_;
  Unwrap32 board_clock_;  // raw bytes: the board's time [us]
  int64_t board_clock0_ = 0;
  std::vector<wheelboard::Event> events_;
};

struct OdometryDriverOptions : StreamDeviceOptions {
  size_t max_queued = 4000;        // samples not polled: the oldest dropped (counted)
  int identify_timeout_ms = 1000;  // start-up: a valid frame within this, or reconnect
};

// What both drivers share: a device that streams on its own, whose session turns bytes into
// samples. Start-up flushes what the port buffered and waits for one valid `Frame` (a port with
// another device behind it is an error, retried); the samples queue for take() (the oldest
// dropped beyond max_queued, counted in queue_drops).
template <class Session, class Sample, class Frame>
class SampleStreamDevice : public StreamDevice {
 protected:
  SampleStreamDevice(const DeviceUri& uri, const OdometryDriverOptions& options,
                     std::function<int64_t()> now, const char* frame_name);
  std::vector<Sample> take();
  void startSession(ByteStream& stream) override;
  int onBytes(const uint8_t* data, size_t size, int64_t arrival_utime,
              std::vector<std::string>* errors) override;
  DecoderCounters decoderCounters() const override { return session_.counters(); }
  int64_t clockResets() const override { return session_.clockResets(); }
  std::vector<std::pair<std::string, int64_t>> extraCounters() override;
  // Hooks, called with mutex_ held: a new connection; samples decoded (before queueing).
  virtual void onSessionStart() {}
  virtual void onDecoded(const std::vector<Sample>& samples) {}

  OdometryDriverOptions options_;
  Session session_;  // worker only
  std::mutex mutex_;

 private:
  const char* frame_name_;
  std::vector<uint8_t> read_ahead_;
  std::vector<Sample> decoded_;
  std::vector<Sample> queue_;  // guarded by mutex_
  int64_t queue_drops_ = 0;    // guarded by mutex_
};

// The HI219 on hi219:///dev/PORT: it streams on power-up.
class Hi219Driver : public ImuDevice,
                    public SampleStreamDevice<Hi219Session, ImuSample, hi219::Frame> {
 public:
  Hi219Driver(const DeviceUri& uri, const OdometryDriverOptions& options,
              std::function<int64_t()> now);
  ~Hi219Driver() override;
  void start() { startWorker(); }
  std::vector<ImuSample> poll(int64_t) override { return take(); }
  DeviceHealth health() override { return StreamDevice::health(); }
  bool streaming() const override { return StreamDevice::streaming(); }

 protected:
  std::string identity() const override;
  const char* itemsName() const override { return "imu_samples"; }
};

// The wheel board on wheelboard:///dev/PORT: TICKS in, SPEED out (each command() once, at the
// next service of the connection; the board's own watchdog stops the wheels when they stop).
class WheelBoardDriver
    : public WheelDevice,
      public SampleStreamDevice<WheelBoardSession, WheelTicks, wheelboard::Ticks> {
 public:
  WheelBoardDriver(const DeviceUri& uri, const OdometryDriverOptions& options,
                   std::function<int64_t()> now);
  ~WheelBoardDriver() override;
  void start() { startWorker(); }
  std::vector<WheelTicks> poll(int64_t) override { return take(); }
  void command(int64_t now_utime, double v_m_s, double w_rad_s) override;
  DeviceHealth health() override { return StreamDevice::health(); }
  bool streaming() const override { return StreamDevice::streaming(); }

 protected:
  void service(ByteStream& stream, int64_t now_utime) override;
  void stopSession(ByteStream& stream) override;
  std::string identity() const override { return "wheel board"; }
  const char* itemsName() const override { return "wheel_readings"; }
  std::vector<std::pair<std::string, int64_t>> extraCounters() override;
  void onSessionStart() override;
  void onDecoded(const std::vector<WheelTicks>& ticks) override;

 private:
  uint16_t tx_seq_ = 0;  // worker only
  // Guarded by mutex_:
  std::deque<std::pair<double, double>> commands_;  // (v, w) not yet sent
  int64_t commands_sent_ = 0, watchdog_stops_ = 0;
  int64_t frames_lost_total_ = 0, frames_lost_now_ = 0;  // closed connections, this one
  uint16_t last_flags_ = 0;
};

}  // namespace sweepmap
