#include "drivers/lidar_sessions.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include "drivers/clock_sync.hpp"
#include "drivers/protocols/scip.hpp"

namespace sweepmap {
namespace {

std::string fmt(double v, int precision = 3) {
  std::ostringstream s;
  s.precision(precision);
  s << v;
  return s.str();
}

std::string at(int64_t offset) { return "byte " + std::to_string(offset) + ": "; }

// ---- SCIP 2.0 (Hokuyo) ----------------------------------------------------------------

class ScipSession : public LidarSession {
 public:
  ScipSession(const LidarConfig& expected, const SessionOptions& options)
      : expected_(expected), options_(options) {
    // Until the device's PP is seen (a raw file from the middle of a stream): the rig's.
    params_.model = "(rig file)";
    params_.ares = expected.steps_per_revolution;
    const double step = 2.0 * M_PI / params_.ares;
    params_.afrt = static_cast<int>(std::lround(-expected.angle_min_deg * M_PI / 180.0 / step));
    params_.amin = 0;
    params_.amax = expected.beam_count - 1;
    params_.dmin_mm = static_cast<int>(std::lround(expected.range_min_m * 1000.0));
    params_.dmax_mm = static_cast<int>(std::lround(expected.range_max_m * 1000.0));
    params_.scan_rpm = static_cast<int>(std::lround(expected.scan_rate_hz * 60.0));
  }

  void start(ByteStream& stream, const std::function<int64_t()>& now) override {
    decoder_.reset();
    clock_.clear();
    pending_.clear();
    // A stream left running by a previous client: stop it, then forget what is in flight.
    stream.write(std::string("QT\n"));
    drain(stream, now);
    decoder_.reset();
    const scip::Reply vv = exchange(stream, now, "VV");
    const scip::Reply pp = exchange(stream, now, "PP");
    params_ = scip::parseParams(pp.params);
    identity_ = pp.params.count("MODL") ? pp.params.at("MODL") : "SCIP sensor";
    if (vv.params.count("SERI")) identity_ += " serial " + vv.params.at("SERI");
    if (vv.params.count("FIRM")) identity_ += " firmware " + vv.params.at("FIRM");
    check();
    // The sensor's clock against ours: TM1 exchanges narrow the offset down to about a
    // round trip (DeviceClockSync::anchor).
    exchange(stream, now, "TM0");
    for (int k = 0; k < 10; ++k) {
      const int64_t sent = now();
      const scip::Reply tm = exchange(stream, now, "TM1");
      const int64_t received = now();
      if (!tm.time_ms) throw StreamError("TM1 reply without a time");
      clock_.anchor(*tm.time_ms, sent, received);
    }
    exchange(stream, now, "TM2");
    // Ranges and intensities (ME) where the sensor has them, else ranges (MD).
    const int start =
        params_.afrt +
        static_cast<int>(std::lround(expected_.angle_min_deg * M_PI / 180.0 / params_.stepRad()));
    const int end = start + expected_.beam_count - 1;
    scip::Reply r = exchange(stream, now, scip::scanCommand("ME", start, end, 0, 0, 0), false);
    if (!r.ok) r = exchange(stream, now, scip::scanCommand("MD", start, end, 0, 0, 0), false);
    if (!r.ok) {
      throw StreamError("SCIP " + r.command + " status " + r.status + ": " +
                        scip::statusText(r.command, r.status));
    }
  }

  void onBytes(const uint8_t* data, size_t size, int64_t arrival, std::vector<Scan2D>* scans,
               std::vector<std::string>* errors) override {
    std::vector<scip::Event> events;
    events.swap(pending_);
    decoder_.feed(data, size, &events);
    for (scip::Event& e : events) {
      if (auto* d = std::get_if<DecodeError>(&e)) {
        errors->push_back(at(d->offset) + d->what);
      } else if (auto* r = std::get_if<scip::Reply>(&e)) {
        reply(*r, arrival, errors);
      } else {
        scan(std::get<scip::ScanData>(e), arrival, scans, errors);
      }
    }
  }

  void stop(ByteStream& stream) override { stream.write(std::string("QT\n"), 200); }
  DecoderCounters decoderCounters() const override { return decoder_.counters(); }
  int64_t clockResets() const override { return clock_.resets(); }
  std::string identity() const override { return identity_; }

 private:
  // Reads and discards until the line is quiet for 100 ms (at most 2 s).
  void drain(ByteStream& stream, const std::function<int64_t()>& now) {
    uint8_t buffer[4096];
    const int64_t deadline = now() + 2000000;
    while (stream.read(buffer, sizeof buffer, 100) > 0) {
      if (now() > deadline) throw StreamError("the device does not stop sending after QT");
    }
  }

  // Sends `command` and waits (1 s) for its reply; scans still in flight are dropped,
  // anything after the reply is kept for onBytes.
  scip::Reply exchange(ByteStream& stream, const std::function<int64_t()>& now,
                       const std::string& command, bool require_ok = true) {
    const std::string line = command.back() == '\n' ? command : command + "\n";
    stream.write(line);
    const std::string letters = line.substr(0, 2);
    const int64_t deadline = now() + 1000000;
    uint8_t buffer[4096];
    while (now() < deadline) {
      const size_t n = stream.read(buffer, sizeof buffer, 50);
      std::vector<scip::Event> events;
      decoder_.feed(buffer, n, &events);
      for (size_t i = 0; i < events.size(); ++i) {
        const auto* r = std::get_if<scip::Reply>(&events[i]);
        if (!r || r->command != letters) continue;
        pending_.assign(events.begin() + static_cast<std::ptrdiff_t>(i) + 1, events.end());
        if (require_ok && !r->ok) {
          throw StreamError("SCIP " + line.substr(0, line.size() - 1) + ": status " + r->status +
                            " (" + scip::statusText(letters, r->status) + ")");
        }
        return *r;
      }
    }
    throw StreamError("no reply to SCIP " + line.substr(0, line.size() - 1) + " within 1 s");
  }

  // The device must be the lidar the rig file describes.
  void check() const {
    const auto mismatch = [&](const std::string& what, const std::string& rig,
                              const std::string& device) {
      throw IdentityMismatch(what + ": the rig file says " + rig + ", the " + identity_ + " has " +
                             device);
    };
    const int beams = params_.amax - params_.amin + 1;
    if (beams != expected_.beam_count) {
      mismatch("beams", std::to_string(expected_.beam_count),
               std::to_string(beams) + " (steps " + std::to_string(params_.amin) + ".." +
                   std::to_string(params_.amax) + ")");
    }
    if (params_.ares != expected_.steps_per_revolution ||
        std::fabs(360.0 / params_.ares - expected_.angle_increment_deg) > 1e-6) {
      mismatch("angular resolution",
               fmt(expected_.angle_increment_deg, 6) + " deg (" +
                   std::to_string(expected_.steps_per_revolution) + " steps per turn)",
               fmt(360.0 / params_.ares, 6) + " deg (ARES " + std::to_string(params_.ares) + ")");
    }
    const double angle_min_deg = params_.angleRad(params_.amin) * 180.0 / M_PI;
    if (std::fabs(angle_min_deg - expected_.angle_min_deg) > 0.5 * 360.0 / params_.ares) {
      mismatch("first ray angle", fmt(expected_.angle_min_deg, 6) + " deg",
               fmt(angle_min_deg, 6) + " deg");
    }
    if (expected_.range_min_m < params_.dmin_mm * 1e-3 ||
        expected_.range_max_m > params_.dmax_mm * 1e-3) {
      mismatch("range limits",
               fmt(expected_.range_min_m) + ".." + fmt(expected_.range_max_m) + " m",
               fmt(params_.dmin_mm * 1e-3) + ".." + fmt(params_.dmax_mm * 1e-3) + " m");
    }
    const double rate = params_.scan_rpm / 60.0;
    if (std::fabs(rate - expected_.scan_rate_hz) > 0.01 * expected_.scan_rate_hz) {
      mismatch("scan rate", fmt(expected_.scan_rate_hz) + " Hz", fmt(rate) + " Hz");
    }
  }

  void reply(const scip::Reply& r, int64_t arrival, std::vector<std::string>* errors) {
    if (r.command == "PP" && r.ok) {
      try {
        params_ = scip::parseParams(r.params);
      } catch (const std::exception& e) {
        errors->push_back(at(r.offset) + e.what());
      }
    } else if (r.command == "TM" && r.time_ms) {
      clock_.anchor(*r.time_ms, arrival, arrival);  // a capture: no send time
    } else if (!r.ok) {
      errors->push_back(at(r.offset) + "SCIP " + r.echo + ": status " + r.status + " (" +
                        scip::statusText(r.command, r.status) + ")");
    }
  }

  void scan(const scip::ScanData& d, int64_t arrival, std::vector<Scan2D>* scans,
            std::vector<std::string>* errors) {
    if (d.start_step < params_.amin || d.end_step > params_.amax) {
      errors->push_back(at(d.offset) + "SCIP " + d.command + " scan of steps " +
                        std::to_string(d.start_step) + ".." + std::to_string(d.end_step) +
                        " outside the sensor's " + std::to_string(params_.amin) + ".." +
                        std::to_string(params_.amax));
      return;
    }
    Scan2D s = scip::toScan2D(d, params_);
    s.seq = seq_++;
    const double ray_s = 60.0 / params_.scan_rpm / params_.ares;
    s.time_increment_ns = static_cast<int64_t>(std::llround(ray_s * d.cluster * 1e9));
    if (options_.time == ScanTime::kArrival && arrival >= 0) {
      s.utime = clock_.observe(d.time_ms, arrival);
    } else {
      // No receive times: the device's own clock, unwrapped (ms -> us).
      const int64_t modulus = int64_t{1} << 24;
      if (have_raw_)
        unwrapped_ += ((int64_t{d.time_ms} - last_raw_) % modulus + modulus) % modulus;
      else
        unwrapped_ = d.time_ms;
      have_raw_ = true;
      last_raw_ = d.time_ms;
      s.utime = unwrapped_ * 1000;
    }
    scans->push_back(std::move(s));
  }

  LidarConfig expected_;
  SessionOptions options_;
  scip::Decoder decoder_;
  scip::Params params_;
  DeviceClockSync clock_;
  std::vector<scip::Event> pending_;
  std::string identity_ = "SCIP sensor";
  int64_t seq_ = 0;
  bool have_raw_ = false;
  int64_t last_raw_ = 0, unwrapped_ = 0;
};

}  // namespace

std::unique_ptr<LidarSession> makeLidarSession(DeviceProtocol protocol, const LidarConfig& expected,
                                               const SessionOptions& options) {
  switch (protocol) {
    case DeviceProtocol::kScip:
      return std::make_unique<ScipSession>(expected, options);
    case DeviceProtocol::kYdlidarX4:
    case DeviceProtocol::kRplidar:
      throw std::invalid_argument(std::string(protocolName(protocol)) + ": driver not built yet");
    case DeviceProtocol::kSim:
      break;
  }
  throw std::invalid_argument("no driver session for the simulated lidar");
}

std::unique_ptr<RealLidar> makeRealLidar(const DeviceUri& uri, const LidarConfig& expected,
                                         const RealLidarOptions& options,
                                         std::function<int64_t()> now) {
  return std::make_unique<RealLidar>(
      uri, makeLidarSession(uri.protocol, expected, SessionOptions{}), options, std::move(now));
}

}  // namespace sweepmap
