#include "tools/devices/capture.hpp"

#include <chrono>
#include <cmath>
#include <mutex>
#include <ostream>
#include <stdexcept>
#include <thread>

#include "core/device_uri.hpp"
#include "core/event_log.hpp"
#include "drivers/io/capture_file.hpp"
#include "drivers/lidar_sessions.hpp"
#include "drivers/odometry_drivers.hpp"
#include "processes/channels.hpp"
#include "processes/convert.hpp"
#include "processes/live_runner.hpp"
#include "processes/node.hpp"
#include "sweepmap/imu_t.hpp"
#include "sweepmap/wheel_ticks_t.hpp"

namespace sweepmap {
namespace {

constexpr int64_t kMaxReportedErrors = 1000;

DeviceProtocol protocolOf(const std::string& name) {
  if (name == "scip") return DeviceProtocol::kScip;
  if (name == "x4") return DeviceProtocol::kYdlidarX4;
  if (name == "rplidar") return DeviceProtocol::kRplidar;
  throw std::runtime_error("unknown protocol '" + name + "' (scip, x4, rplidar)");
}

}  // namespace

int runCapture(const CaptureOptions& o, const LidarConfig& expected, std::ostream& report) {
  const DeviceUri uri = parseDeviceUri(o.uri);
  if (uri.protocol == DeviceProtocol::kSim) {
    throw std::runtime_error("capture needs a device URI, not sim");
  }
  CaptureWriter writer(o.out, o.uri);
  std::mutex mutex;
  std::string write_error;
  int64_t first_utime = -1, last_utime = -1;
  RealLidarOptions options;
  options.tap = [&](int64_t utime, const uint8_t* data, size_t size) {
    std::lock_guard<std::mutex> lock(mutex);
    if (!write_error.empty()) return;
    try {
      writer.append(utime, data, size);
    } catch (const std::exception& e) {
      write_error = e.what();
    }
    if (first_utime < 0) first_utime = utime;
    last_utime = utime;
  };
  auto device = std::make_unique<RealLidar>(
      uri, makeLidarSession(uri.protocol, expected, SessionOptions{}), options, wallUtime);
  device->start();
  installStopSignals();
  const auto deadline_without_data =
      std::chrono::steady_clock::now() + std::chrono::duration<double>(o.seconds + 10.0);
  int64_t scans = 0;
  for (;;) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    scans += static_cast<int64_t>(device->poll(0).size());
    DeviceHealth h = device->health();
    for (const auto& e : h.events) report << "capture: " << e << "\n";
    if (!h.fatal.empty()) {
      report << "capture: " << h.fatal << "\n";
      break;
    }
    std::lock_guard<std::mutex> lock(mutex);
    if (!write_error.empty()) break;
    if (stopRequested()) break;
    if (first_utime >= 0 && wallUtime() - first_utime >= static_cast<int64_t>(o.seconds * 1e6))
      break;
    if (first_utime < 0 && std::chrono::steady_clock::now() > deadline_without_data) break;
  }
  // The worker stops before the file closes: no chunk is written after close.
  const DeviceHealth h = device->health();
  device.reset();
  writer.close();
  if (!write_error.empty()) {
    report << "capture: " << write_error << "\n";
    return 1;
  }
  report << "capture: " << writer.bytes() << " bytes in "
         << (first_utime < 0 ? 0.0 : (last_utime - first_utime) * 1e-6) << " s, " << scans
         << " scans -> " << o.out << "\n";
  for (const auto& [name, value] : h.counters) {
    if (value != 0) report << "  " << name << " " << value << "\n";
  }
  return writer.bytes() > 0 ? 0 : 1;
}

namespace {

// What a decode found, after the problems it listed one by one with their offsets.
void reportCounts(const DecodeOptions& o, const DecodeResult& r, const std::string& what,
                  std::ostream& report) {
  const DecoderCounters& c = r.counters;
  report << "decode: " << r.bytes << " bytes, " << r.scans << " " << what << " -> " << o.out
         << "\n  found: " << c.packets << " packets";
  for (const auto& [name, value] : r.session) report << ", " << value << " " << name;
  report << "\n  problems: " << c.checksum_errors << " checksum errors, " << c.resyncs
         << " resyncs, " << c.discarded_bytes << " bytes skipped (offsets above), "
         << c.device_errors << " device errors, " << c.anomalies << " anomalies";
  if (r.errors > kMaxReportedErrors) {
    report << " (" << r.errors - kMaxReportedErrors << " more problems not listed)";
  }
  report << "\n";
  if (!r.file_error.empty()) report << "decode: " << r.file_error << "\n";
}

// Each problem with its offset, the first kMaxReportedErrors of them.
void reportErrors(const DecodeOptions& o, const std::vector<std::string>& errors, DecodeResult* r,
                  std::ostream& report) {
  for (const std::string& e : errors) {
    if (r->errors < kMaxReportedErrors) report << o.in << ": " << e << "\n";
    ++r->errors;
  }
}

// The rig-B devices: HI219 frames to IMU, wheel board frames to WHEEL_TICKS, by the drivers'
// own sessions (drivers/odometry_drivers.hpp). IMU axes as the IMU reports them (its mounting
// is the driver's business); Euler angles when the frame has them, else NaN.
DecodeResult decodeRigBDevice(const DecodeOptions& o, const Capture& capture,
                              std::ostream& report) {
  DecodeResult r;
  EventLogWriter log(o.out);
  const bool is_imu = o.protocol == "hi219";
  const int baud = o.baud > 0 ? o.baud : 115200;
  Hi219Session imu(baud, capture.raw);
  WheelBoardSession board(baud, capture.raw);
  std::vector<ImuSample> samples;
  std::vector<WheelTicks> ticks;
  std::vector<std::string> errors;
  // One chunk of the capture (nullptr: the end of the input) through the session.
  const auto decode = [&](const CaptureChunk* chunk) {
    samples.clear();
    ticks.clear();
    errors.clear();
    Outbox out;
    if (is_imu) {
      if (chunk) {
        imu.onBytes(chunk->bytes.data(), chunk->bytes.size(), chunk->utime, &samples, &errors);
      } else {
        imu.finish(&samples, &errors);
      }
      for (const ImuSample& s : samples) out.publish(channels::kImu, s.utime, toLcm(s));
      r.scans += static_cast<int64_t>(samples.size());
    } else {
      if (chunk) {
        board.onBytes(chunk->bytes.data(), chunk->bytes.size(), chunk->utime, &ticks, &errors);
      } else {
        board.finish(&ticks, &errors);
      }
      for (const WheelTicks& t : ticks) out.publish(channels::kWheelTicks, t.utime, toLcm(t));
      r.scans += static_cast<int64_t>(ticks.size());
    }
    reportErrors(o, errors, &r, report);
    for (const Message& m : out.take()) log.write(m.utime, m.channel, m.data);
  };
  for (const CaptureChunk& chunk : capture.chunks) {
    r.bytes += static_cast<int64_t>(chunk.bytes.size());
    decode(&chunk);
  }
  decode(nullptr);
  log.close();
  r.file_error = capture.error;
  r.counters = is_imu ? imu.counters() : board.counters();
  if (!is_imu) r.session = {{"frames lost", board.framesLost()}};
  reportCounts(o, r, is_imu ? "IMU samples" : "wheel readings", report);
  return r;
}

}  // namespace

DecodeResult runDecode(const DecodeOptions& o, const LidarConfig& expected, std::ostream& report) {
  if (o.protocol == "hi219" || o.protocol == "wheelboard") {
    return decodeRigBDevice(o, readCapture(o.in), report);
  }
  const DeviceProtocol protocol = protocolOf(o.protocol);
  const Capture capture = readCapture(o.in);
  SessionOptions so;
  so.time = capture.raw ? ScanTime::kStream : ScanTime::kArrival;
  so.baud = o.baud;
  if (!capture.raw) {
    try {
      const DeviceUri uri = parseDeviceUri(capture.uri);
      if (uri.protocol != protocol) {
        report << "decode: note: " << o.in << " was captured from " << capture.uri
               << ", decoding as " << o.protocol << "\n";
      }
      if (uri.baud > 0 && so.baud == 0) so.baud = uri.baud;
    } catch (const std::invalid_argument&) {
    }
  }
  std::unique_ptr<LidarSession> session = makeLidarSession(protocol, expected, so);
  EventLogWriter log(o.out);
  DecodeResult r;
  std::vector<Scan2D> scans;
  std::vector<std::string> errors;
  // The scans and problems of one chunk (nullptr: the end of the input).
  const auto decode = [&](const CaptureChunk* chunk) {
    scans.clear();
    errors.clear();
    if (chunk) {
      session->onBytes(chunk->bytes.data(), chunk->bytes.size(), chunk->utime, &scans, &errors);
    } else {
      session->finish(&scans, &errors);
    }
    reportErrors(o, errors, &r, report);
    for (const Scan2D& s : scans) {
      const std::string why = validateScan(s, 0);  // any length: each ray has its angle
      if (!why.empty()) {
        report << o.in << ": scan " << s.seq << " dropped: " << why << "\n";
        ++r.errors;
        continue;
      }
      Outbox out;
      out.publish(channels::kLidarScan, s.utime, toLcm(s));
      for (const Message& m : out.take()) log.write(m.utime, m.channel, m.data);
      ++r.scans;
    }
  };
  for (const CaptureChunk& chunk : capture.chunks) {
    r.bytes += static_cast<int64_t>(chunk.bytes.size());
    decode(&chunk);
  }
  decode(nullptr);
  log.close();
  r.file_error = capture.error;
  r.counters = session->decoderCounters();
  r.session = session->sessionCounters();
  reportCounts(o, r, "scans (LIDAR_SCAN)", report);
  return r;
}

}  // namespace sweepmap
