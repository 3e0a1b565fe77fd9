// A real lidar on a TCP socket or a serial port, behind LidarDevice: the connection worker of
// drivers/stream_device.hpp with a LidarSession (the protocol's part) that turns bytes into
// scans. poll() hands over the scans decoded so far; health() the counters and events.
#pragma once

#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "core/device_uri.hpp"
#include "core/rig_components.hpp"
#include "devices/lidar_device.hpp"
#include "drivers/io/byte_stream.hpp"
#include "drivers/protocols/decoder.hpp"
#include "drivers/stream_device.hpp"

namespace sweepmap {
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
  // The end of the input (a capture file): bytes held for a packet that cannot complete are
  // searched again, what they hold is decoded (a turn left open is not a scan).
  virtual void finish(std::vector<Scan2D>* scans, std::vector<std::string>* errors) {}
  // Best effort before closing on shutdown (stop the stream, motor off).
  virtual void stop(ByteStream& stream) {}
  // Decoder counters of the current connection (reset on reconnect).
  virtual DecoderCounters decoderCounters() const = 0;
  // What the session made of the decoded packets, cumulative (360° lidars: samples, turns,
  // partial_turns, broken_turns); in the lidar process's status beside the decoder's.
  using Counters = std::vector<std::pair<std::string, int64_t>>;
  virtual Counters sessionCounters() const { return {}; }
  virtual int64_t clockResets() const { return 0; }
  // "UST-10LX serial H1234567 firmware 1.2.3", after start().
  virtual std::string identity() const = 0;
};

struct RealLidarOptions : StreamDeviceOptions {
  size_t max_queued_scans = 400;  // poll() not called: oldest scans dropped (counted)
};

class RealLidar : public LidarDevice, public StreamDevice {
 public:
  // Opens `uri` (scip: TCP, ydlidar/rplidar: serial) on each connection attempt.
  RealLidar(const DeviceUri& uri, std::unique_ptr<LidarSession> session,
            const RealLidarOptions& options, std::function<int64_t()> now);
  // Starts the worker thread.
  void start() { startWorker(); }
  ~RealLidar() override;

  std::vector<Scan2D> poll(int64_t now_utime) override;
  DeviceHealth health() override { return StreamDevice::health(); }

 protected:
  void startSession(ByteStream& stream) override;
  int onBytes(const uint8_t* data, size_t size, int64_t arrival_utime,
              std::vector<std::string>* errors) override;
  void stopSession(ByteStream& stream) override { session_->stop(stream); }
  DecoderCounters decoderCounters() const override { return session_->decoderCounters(); }
  int64_t clockResets() const override { return session_->clockResets(); }
  std::string identity() const override { return session_->identity(); }
  const char* itemsName() const override { return "device_scans"; }
  std::vector<std::pair<std::string, int64_t>> extraCounters() override;

 private:
  std::unique_ptr<LidarSession> session_;
  size_t max_queued_scans_;
  std::vector<Scan2D> decoded_;  // worker only
  std::mutex mutex_;             // guards the two below
  std::vector<Scan2D> queue_;
  int64_t queue_drops_ = 0;
  LidarSession::Counters session_counters_;  // the worker's copy of sessionCounters()
};

// The driver for `uri`'s protocol, checked against what the rig file says of the lidar
// (drivers/lidar_sessions.cpp).
std::unique_ptr<RealLidar> makeRealLidar(const DeviceUri& uri, const LidarConfig& expected,
                                         const RealLidarOptions& options,
                                         std::function<int64_t()> now);

}  // namespace sweepmap
