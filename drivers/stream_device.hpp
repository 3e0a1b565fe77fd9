// The connection half of every real device driver on a TCP socket or a serial port: a
// worker thread owns the connection: open → startSession (flush, identify, check against the
// rig file, start streaming) → read and decode until a hang-up, a read timeout or a run of
// decode errors → close → back off → open again. Blocking reads with timeouts: a dead
// descriptor is never polled in a loop. The backoff starts at backoff_min_ms and doubles up to
// backoff_max_ms, so a device that comes back streams again within backoff_max_ms + its
// start-up exchange. The protocol's part (what to send at start, how bytes become items, what
// to send while streaming) is the subclass's; health() reports the counters every driver has.
//
// Subclasses call startWorker() once they are constructed and stopWorker() first thing in their
// destructor (the worker calls their virtual functions).
#pragma once

#include <atomic>
#include <functional>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "core/device_uri.hpp"
#include "devices/lidar_device.hpp"
#include "drivers/io/byte_stream.hpp"
#include "drivers/protocols/decoder.hpp"

namespace sweepmap {

// The device is not the one the rig file describes: permanent, not retried.
class IdentityMismatch : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct StreamDeviceOptions {
  int connect_timeout_ms = 1000;
  int read_timeout_ms = 1000;  // no byte this long while streaming: reconnect
  int error_run = 20;          // this many decode errors with nothing decoded between: reconnect
  int backoff_min_ms = 100;
  int backoff_max_ms = 1000;
  int read_poll_ms = 100;  // a read waits this long before service() runs again
  // Called (worker thread) with every chunk read from the device, the start-up exchange
  // included, and its receive time: `sweepmap capture` records them.
  std::function<void(int64_t utime, const uint8_t* data, size_t size)> tap;
};

class StreamDevice {
 public:
  // Opens `uri` (scip: TCP; the serial protocols: the port at uri.baud) on each attempt.
  // `now` reads the host clock [us] (the process's utime).
  StreamDevice(const DeviceUri& uri, const StreamDeviceOptions& options,
               std::function<int64_t()> now);
  virtual ~StreamDevice();
  StreamDevice(const StreamDevice&) = delete;
  StreamDevice& operator=(const StreamDevice&) = delete;

  // Cumulative counters (items = what the subclass decoded, under `items_name`) and the
  // events since the last call.
  DeviceHealth health();
  // Between a successful startSession and the end of that connection.
  bool streaming() const { return streaming_.load(); }
  // Whether the worker, started and not finished, has gone `max_silence_ms` without a turn of
  // its loops (a read, a connection attempt, a step of its backoff): stuck in a call that does
  // not return. The process then withholds its watchdog ping (LiveOptions::healthy), so that
  // its supervisor restarts it.
  bool workerStalled(int64_t max_silence_ms) const;
  const DeviceUri& uri() const { return uri_; }

 protected:
  void startWorker();
  void stopWorker();
  bool stopping() const { return stop_.load(); }
  std::function<int64_t()> clock() const { return now_; }

  // After (re)connecting. Throws IdentityMismatch (permanent) or StreamError /
  // std::runtime_error (then: reconnect).
  virtual void startSession(ByteStream& stream) = 0;
  // Bytes that arrived complete at host time `arrival_utime` (once with size 0 right after
  // startSession: bytes it read ahead). Returns how many items it completed; problems →
  // *errors.
  virtual int onBytes(const uint8_t* data, size_t size, int64_t arrival_utime,
                      std::vector<std::string>* errors) = 0;
  // While streaming, after every read (at least every read_poll_ms): send what is due.
  virtual void service(ByteStream& stream, int64_t now_utime) {}
  // Best effort before closing on shutdown (stop the stream, motor off).
  virtual void stopSession(ByteStream& stream) {}
  // Decoder counters of the current connection (reset by startSession).
  virtual DecoderCounters decoderCounters() const = 0;
  virtual int64_t clockResets() const { return 0; }
  // "UST-10LX serial H1234567 firmware 1.2.3", after startSession.
  virtual std::string identity() const = 0;
  // The counter name of decoded items in health(): "device_scans", "imu_samples", ...
  virtual const char* itemsName() const = 0;
  // Extra counters of the subclass (called under no lock of ours).
  virtual std::vector<std::pair<std::string, int64_t>> extraCounters() { return {}; }

  void event(const std::string& what);

 private:
  void run();
  void streamOnce(ByteStream& stream);

  DeviceUri uri_;
  StreamDeviceOptions options_;
  std::function<int64_t()> now_;
  std::thread worker_;
  std::atomic<bool> stop_{false};
  std::atomic<bool> streaming_{false};
  std::atomic<bool> running_{false};  // the worker is in run()
  std::atomic<int64_t> beat_ms_{0};   // the worker's last turn, steady clock [ms]
  void beat();

  std::mutex mutex_;  // guards everything below
  std::vector<std::string> events_;
  std::string fatal_;
  std::string last_event_;
  DecoderCounters decoded_total_;  // of closed connections
  DecoderCounters decoded_now_;    // of the current one
  int64_t clock_resets_total_ = 0, clock_resets_now_ = 0;
  int64_t items_ = 0, timeouts_ = 0, reconnects_ = 0, connect_failures_ = 0;
  int64_t events_suppressed_ = 0;
};

}  // namespace sweepmap
