// A real lidar on a TCP socket or a serial port, behind LidarDevice.
//
// A worker thread owns the connection: open → session.start (stop a stream left running,
// flush, identify and check the device against the rig file, start streaming) → read and
// decode until a hang-up, a read timeout or a run of decode errors → close → back off →
// open again. Blocking reads with timeouts: a dead descriptor is never polled in a loop.
// The backoff starts at backoff_min_ms and doubles up to backoff_max_ms, so a device that
// comes back streams again within backoff_max_ms + its start-up exchange.
// poll() hands over the scans decoded so far; health() the counters and events.
#pragma once

#include <atomic>
#include <functional>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "core/device_uri.hpp"
#include "core/rig_components.hpp"
#include "drivers/io/byte_stream.hpp"
#include "drivers/lidar_device.hpp"
#include "drivers/protocols/decoder.hpp"

namespace sweepmap {

// The device is not the one the rig file describes: permanent, not retried.
class IdentityMismatch : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The protocol's part of a driver. Called from the driver's worker thread only.
class LidarSession {
 public:
  virtual ~LidarSession() = default;
  // After (re)connecting: stop a stream left running, flush, identify, check against the
  // rig (throws IdentityMismatch naming both values), start streaming. Throws StreamError
  // or std::runtime_error when the device does not answer as it should (then: reconnect).
  // `now` reads the host clock [us].
  virtual void start(ByteStream& stream, const std::function<int64_t()>& now) = 0;
  // Bytes that arrived complete at host time `arrival_utime`: finished scans → *scans,
  // problems → *errors. Called once with size 0 right after start(): bytes start() read
  // beyond its replies (the stream's first data) are decoded then.
  virtual void onBytes(const uint8_t* data, size_t size, int64_t arrival_utime,
                       std::vector<Scan2D>* scans, std::vector<std::string>* errors) = 0;
  // Best effort before closing on shutdown (stop the stream, motor off).
  virtual void stop(ByteStream& stream) {}
  // Decoder counters of the current connection (reset on reconnect).
  virtual DecoderCounters decoderCounters() const = 0;
  virtual int64_t clockResets() const { return 0; }
  // "UST-10LX serial H1234567 firmware 1.2.3", after start().
  virtual std::string identity() const = 0;
};

struct RealLidarOptions {
  int connect_timeout_ms = 1000;
  int read_timeout_ms = 1000;  // no byte this long while streaming: reconnect
  int error_run = 20;          // this many decode errors with no scan between: reconnect
  int backoff_min_ms = 100;
  int backoff_max_ms = 1000;
  size_t max_queued_scans = 400;  // poll() not called: oldest scans dropped (counted)
  // Called (worker thread) with every chunk read from the device, the start-up exchange
  // included, and its receive time: `sweepmap capture` records them.
  std::function<void(int64_t utime, const uint8_t* data, size_t size)> tap;
};

class RealLidar : public LidarDevice {
 public:
  using Opener = std::function<std::unique_ptr<ByteStream>()>;
  // Opens `uri` (scip: TCP, ydlidar/rplidar: serial) on each connection attempt.
  RealLidar(const DeviceUri& uri, std::unique_ptr<LidarSession> session,
            const RealLidarOptions& options, std::function<int64_t()> now);
  // Starts the worker thread.
  void start();
  ~RealLidar() override;

  std::vector<Scan2D> poll(int64_t now_utime) override;
  DeviceHealth health() override;
  // Scans of the current connection's stream since start.
  bool streaming() const { return streaming_.load(); }

 private:
  void run();
  void streamOnce(ByteStream& stream);
  void event(const std::string& what);

  DeviceUri uri_;
  std::unique_ptr<LidarSession> session_;
  RealLidarOptions options_;
  std::function<int64_t()> now_;
  std::thread worker_;
  std::atomic<bool> stop_{false};
  std::atomic<bool> streaming_{false};

  std::mutex mutex_;  // guards everything below
  std::vector<Scan2D> queue_;
  std::vector<std::string> events_;
  std::string fatal_;
  std::string last_event_;
  DecoderCounters decoded_total_;  // of closed connections
  DecoderCounters decoded_now_;    // of the current one
  int64_t clock_resets_total_ = 0, clock_resets_now_ = 0;
  int64_t scans_ = 0, timeouts_ = 0, reconnects_ = 0, connect_failures_ = 0, queue_drops_ = 0;
  int64_t events_suppressed_ = 0;
};

// The driver for `uri`'s protocol, checked against what the rig file says of the lidar
// (drivers/lidar_sessions.cpp).
std::unique_ptr<RealLidar> makeRealLidar(const DeviceUri& uri, const LidarConfig& expected,
                                         const RealLidarOptions& options,
                                         std::function<int64_t()> now);

}  // namespace sweepmap
