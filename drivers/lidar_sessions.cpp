#include "drivers/lidar_sessions.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "core/lidar_models.hpp"
#include "drivers/clock_sync.hpp"
#include "drivers/line_clock.hpp"
#include "drivers/protocols/rplidar.hpp"
#include "drivers/protocols/scip.hpp"
#include "drivers/protocols/ydlidar.hpp"

namespace sweepmap {
namespace {

std::string fmt(double v, int precision = 3) {
  std::ostringstream s;
  s.precision(precision);
  s << v;
  return s.str();
}

std::string at(int64_t offset) { return "byte " + std::to_string(offset) + ": "; }

// The rig's lidar.model from the catalogue (core/lidar_models.hpp). Throws
// std::invalid_argument when it is not a model of `protocol`, or when the rig's lidar keys do
// not fit it (a rig file is checked on load; a LidarConfig made in code is checked here).
LidarModel catalogueModel(const LidarConfig& expected, DeviceProtocol protocol) {
  const LidarModel* m = findLidarModel(expected.model);
  if (m == nullptr || m->protocol != protocol) {
    throw std::invalid_argument("lidar.model '" + expected.model + "' is not a " +
                                protocolName(protocol) + " lidar (" + lidarModelNames() + ")");
  }
  if (protocol != DeviceProtocol::kScip) checkLidarFitsModel(expected, *m);
  return *m;
}

// ---- SCIP 2.0 (Hokuyo) ----------------------------------------------------------------

class ScipSession : public LidarSession {
 public:
  ScipSession(const LidarConfig& expected, const SessionOptions& options)
      : expected_(expected),
        options_(options),
        model_(catalogueModel(expected, DeviceProtocol::kScip)) {
    // Until the device's PP is seen (a raw file from the middle of a stream): the model's.
    params_.model = model_.name + " (lidar.model)";
    params_.dmin_mm = model_.pp.dmin_mm;
    params_.dmax_mm = model_.pp.dmax_mm;
    params_.ares = model_.pp.ares;
    params_.amin = model_.pp.amin;
    params_.amax = model_.pp.amax;
    params_.afrt = model_.pp.afrt;
    params_.scan_rpm = model_.pp.scan_rpm;
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
    const std::string modl = pp.params.count("MODL") ? pp.params.at("MODL") : "";
    identity_ = modl.empty() ? "SCIP sensor" : modl;
    if (vv.params.count("SERI")) identity_ += " serial " + vv.params.at("SERI");
    if (vv.params.count("FIRM")) identity_ += " firmware " + vv.params.at("FIRM");
    check(modl, vv.params.count("PROD") ? vv.params.at("PROD") : "");
    // The sensor's clock against ours: TM1 exchanges narrow the offset down to about a
    // round trip (DeviceClockSync::anchor).
    // (A client that left the sensor in adjust mode: TM0 answers 02 "already on".)
    const scip::Reply tm0 = exchange(stream, now, "TM0", false);
    if (!tm0.ok && tm0.status != "02") {
      throw StreamError("SCIP TM0: status " + tm0.status + " (" +
                        scip::statusText("TM", tm0.status) + ")");
    }
    for (int k = 0; k < 10; ++k) {
      const int64_t sent = now();
      const scip::Reply tm = exchange(stream, now, "TM1");
      const int64_t received = now();
      if (!tm.time_ms) throw StreamError("TM1 reply without a time");
      clock_.anchor(*tm.time_ms, sent, received);
    }
    exchange(stream, now, "TM2");
    // The rig's steps (its field of view; the device's PP is the model's, checked above):
    // ranges and intensities (ME) where the sensor has them, else ranges (MD).
    const ScipRequest q = scipRequestFor(expected_, model_);
    const auto command = [&](const char* c) {
      return scip::scanCommand(c, q.start_step, q.end_step, q.cluster, 0, 0);
    };
    scip::Reply r = exchange(stream, now, command("ME"), false);
    if (!r.ok) r = exchange(stream, now, command("MD"), false);
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

  // The device must be the lidar.model of the rig file: its name in PP's MODL (or VV's PROD),
  // PP's steps and rate the catalogue's, its range limits covering the rig's.
  void check(const std::string& modl, const std::string& prod) const {
    const auto mismatch = [&](const std::string& what, const std::string& rig,
                              const std::string& device) {
      throw IdentityMismatch(what + ": the rig file's lidar.model " + model_.name + " has " + rig +
                             ", the device (" + identity_ + ") reports " + device);
    };
    if (modl.find(model_.name) == std::string::npos &&
        prod.find(model_.name) == std::string::npos) {
      mismatch("model", "MODL " + model_.name, "MODL '" + modl + "'");
    }
    const ScipGeometry& want = model_.pp;
    const std::pair<const char*, std::pair<int, int>> keys[] = {
        {"ARES", {want.ares, params_.ares}},
        {"AMIN", {want.amin, params_.amin}},
        {"AMAX", {want.amax, params_.amax}},
        {"AFRT", {want.afrt, params_.afrt}},
        {"SCAN", {want.scan_rpm, params_.scan_rpm}}};
    for (const auto& [key, v] : keys) {
      if (v.first != v.second) {
        mismatch(key, std::string(key) + " " + std::to_string(v.first),
                 std::string(key) + " " + std::to_string(v.second));
      }
    }
    if (expected_.range_min_m < params_.dmin_mm * 1e-3 - 1e-9 ||
        expected_.range_max_m > params_.dmax_mm * 1e-3 + 1e-9) {
      mismatch(
          "range limits",
          "the rig's " + fmt(expected_.range_min_m) + ".." + fmt(expected_.range_max_m) + " m",
          "DMIN..DMAX " + fmt(params_.dmin_mm * 1e-3) + ".." + fmt(params_.dmax_mm * 1e-3) + " m");
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
    // The rig file's limits where they are narrower than the sensor's (a UST-10LX reports
    // echoes to 30 m but is specified to 10 m), as the simulated lidar publishes them.
    s.range_min_m = std::max(s.range_min_m, expected_.range_min_m);
    s.range_max_m = std::min(s.range_max_m, expected_.range_max_m);
    // (In float, as the ranges are: 20 mm is not below a 0.02 m limit.)
    const auto lo = static_cast<float>(s.range_min_m), hi = static_cast<float>(s.range_max_m);
    for (float& r : s.ranges_m) {
      if (r < lo || r > hi) r = 0.0f;
    }
    s.seq = seq_++;
    s.time_increment_ns =
        static_cast<int64_t>(std::llround(params_.stepPeriodS() * d.cluster * 1e9));
    // The stamp is the scan's step 0; ray 0 came firstRayDelayS later.
    const auto delay_us =
        static_cast<int64_t>(std::llround(scip::firstRayDelayS(d, params_) * 1e6));
    if (options_.time == ScanTime::kArrival && arrival >= 0) {
      s.utime = clock_.observe(d.time_ms, arrival) + delay_us;
    } else {
      // No receive times: the device's own clock, unwrapped (ms -> us).
      const int64_t modulus = int64_t{1} << 24;
      if (have_raw_)
        unwrapped_ += ((int64_t{d.time_ms} - last_raw_) % modulus + modulus) % modulus;
      else
        unwrapped_ = d.time_ms;
      have_raw_ = true;
      last_raw_ = d.time_ms;
      s.utime = unwrapped_ * 1000 + delay_us;
    }
    scans->push_back(std::move(s));
  }

  LidarConfig expected_;
  SessionOptions options_;
  LidarModel model_;
  scip::Decoder decoder_;
  scip::Params params_;
  DeviceClockSync clock_;
  std::vector<scip::Event> pending_;
  std::string identity_ = "SCIP sensor";
  int64_t seq_ = 0;
  bool have_raw_ = false;
  int64_t last_raw_ = 0, unwrapped_ = 0;
};

// ---- 360° serial lidars (YDLIDAR X4, RPLIDAR) -------------------------------------------

// One sample of a 360° lidar, as the session hands it to the RevolutionAssembler.
struct TurnSample {
  double device_deg = 0.0;   // its angle, [0, 360)
  double travel_deg = 0.0;   // the angle the device's motion is followed by (X4: the raw one)
  double distance_mm = 0.0;  // 0: no return
  float intensity = 0.0f;
  int64_t utime = 0;
  bool ring_start = false;  // the first sample of a turn (X4 zero packet, RPLIDAR S flag)
};

// Samples into revolutions. A LIDAR_SCAN is one turn of the device, from one ring start (the
// X4's zero packet, the RPLIDAR's S flag) to the next, the ring start's sample first: every
// sample of the turn, in time order, at its own angle (angles_rad: the device angle wrapped to
// [-180, 180) deg, the lidar frame) and time (utime of the first, time_increment_ns the mean
// step to the last), its range 0 for no return or outside the rig's limits. Nothing is binned
// onto a grid. The turn the stream starts in has no ring start before it: dropped (counted),
// as is a turn that travels on past 1.5 revolutions (its closing ring start was lost in a bad
// packet): never a scan of two turns.
class RevolutionAssembler {
 public:
  struct Counters {
    int64_t samples = 0;        // samples fed
    int64_t turns = 0;          // complete turns emitted
    int64_t partial_turns = 0;  // the turn a stream starts in, dropped
    int64_t broken_turns = 0;   // more than a revolution without a ring start, dropped
  };
  explicit RevolutionAssembler(const LidarConfig& rig) : rig_(rig) {}
  void clear() {
    current_.clear();
    state_ = kBeforeFirst;
    seen_before_first_ = false;
    rate_hz_ = 0.0;
  }
  void add(const TurnSample& x, bool has_intensity, std::vector<Scan2D>* out) {
    ++counters_.samples;
    double theta = x.device_deg * M_PI / 180.0;
    if (theta >= M_PI) theta -= 2.0 * M_PI;
    if (x.ring_start) {
      if (state_ == kInTurn && travel_deg_ > kMaxTurnDeg) ++counters_.broken_turns;
      if (state_ == kInTurn && travel_deg_ <= kMaxTurnDeg) finish(x.utime, out);
      if (state_ == kBeforeFirst && seen_before_first_) ++counters_.partial_turns;
      current_.clear();
      state_ = kInTurn;
      travel_deg_ = 0.0;
    } else if (state_ == kInTurn) {
      travel_deg_ += std::remainder(x.travel_deg - last_travel_deg_, 360.0);
      const auto max_samples = static_cast<size_t>(kMaxTurnsOfSamples) *
                               static_cast<size_t>(std::max(1, rig_.steps_per_revolution));
      if (travel_deg_ > kMaxTravelDeg || current_.size() >= max_samples) {
        ++counters_.broken_turns;  // no ring start for far too long: wait for the next
        current_.clear();
        state_ = kLost;
      }
    }
    last_travel_deg_ = x.travel_deg;
    if (state_ != kInTurn) {
      seen_before_first_ = seen_before_first_ || state_ == kBeforeFirst;
      return;
    }
    current_.push_back({theta, x.distance_mm * 1e-3, x.intensity, x.utime});
    has_intensity_ = has_intensity;
  }
  const Counters& counters() const { return counters_; }
  // Turns per second of the last complete turn, from its first sample to the next ring start;
  // 0 until one is timed.
  double turnRateHz() const { return rate_hz_; }

 private:
  // A turn travels 360 deg (on the X4's raw angles, which its range-dependent correction does
  // not shake) give or take a packet: one closed after more than kMaxTurnDeg lost a ring start
  // in between; one that runs on past kMaxTravelDeg, or holds kMaxTurnsOfSamples times the
  // rig's samples per turn, is given up at once (memory stays bounded whatever comes).
  static constexpr double kMaxTurnDeg = 540.0;
  static constexpr double kMaxTravelDeg = 900.0;
  static constexpr int kMaxTurnsOfSamples = 4;
  struct Entry {
    double theta, range_m;
    float intensity;
    int64_t utime;
  };
  // The turn in current_, closed by a ring start at `next_utime`.
  void finish(int64_t next_utime, std::vector<Scan2D>* out) {
    const size_t n = current_.size();
    Scan2D s;
    s.seq = seq_++;
    s.utime = current_.front().utime;
    s.angle_min_rad = current_.front().theta;
    s.angle_increment_rad = 2.0 * M_PI / static_cast<double>(n);
    s.range_min_m = rig_.range_min_m;
    s.range_max_m = rig_.range_max_m;
    const int64_t span_us = current_.back().utime - current_.front().utime;
    s.time_increment_ns = n > 1 && span_us > 0
                              ? span_us * 1000 / static_cast<int64_t>(n - 1)
                              : static_cast<int64_t>(std::llround(rig_.rayPeriodS() * 1e9));
    s.ranges_m.resize(n);
    s.angles_rad.resize(n);
    if (has_intensity_) s.intensities.resize(n);
    for (size_t i = 0; i < n; ++i) {
      const Entry& e = current_[i];
      const bool valid = e.range_m >= rig_.range_min_m && e.range_m <= rig_.range_max_m;
      s.ranges_m[i] = valid ? static_cast<float>(e.range_m) : 0.0f;
      s.angles_rad[i] = static_cast<float>(e.theta);
      if (has_intensity_) s.intensities[i] = e.intensity;
    }
    rate_hz_ = next_utime > s.utime ? 1e6 / static_cast<double>(next_utime - s.utime) : 0.0;
    ++counters_.turns;
    out->push_back(std::move(s));
  }

  enum State { kBeforeFirst, kInTurn, kLost };
  LidarConfig rig_;
  std::vector<Entry> current_;
  State state_ = kBeforeFirst;
  bool seen_before_first_ = false, has_intensity_ = false;
  double travel_deg_ = 0.0, last_travel_deg_ = 0.0, rate_hz_ = 0.0;
  int64_t seq_ = 0;
  Counters counters_;
};

// A motor far from the rig's rate means another device or setting. One turn's rate is timed
// by the arrival of its bytes, and a host that stalls, then reads a backlog at once, makes one
// turn look fast: so the rate must be off for kOffTurns turns in a row, after the first few.
class TurnRateCheck {
 public:
  static constexpr int kOffTurns = 5;
  void reset() { turns_ = 0, off_in_a_row_ = 0; }
  // `turns`: complete turns so far; `rate_hz`: the last one's (0: not timed).
  void update(const LidarConfig& expected, const std::string& model, double rate_hz,
              int64_t turns) {
    if (turns == turns_ || !(rate_hz > 0)) return;  // no new turn, or one not timed
    turns_ = turns;
    const bool off =
        turns >= 5 && std::fabs(rate_hz - expected.scan_rate_hz) > 0.25 * expected.scan_rate_hz;
    off_in_a_row_ = off ? off_in_a_row_ + 1 : 0;
    if (off_in_a_row_ >= kOffTurns) {
      throw IdentityMismatch("scan rate: the rig file says " + fmt(expected.scan_rate_hz) +
                             " Hz, the " + model + " turns at " + fmt(rate_hz) + " Hz");
    }
  }

 private:
  int64_t turns_ = 0;
  int off_in_a_row_ = 0;
};

// Reads until `pred` accepts an event or 1 s passes; events after it are kept in *rest.
template <class Decoder, class Event, class Pred>
void awaitEvent(ByteStream& stream, const std::function<int64_t()>& now, Decoder& decoder,
                std::vector<Event>* rest, const std::string& what, Pred pred) {
  const int64_t deadline = now() + 1000000;
  uint8_t buffer[4096];
  while (now() < deadline) {
    const size_t n = stream.read(buffer, sizeof buffer, 50);
    std::vector<Event> events;
    decoder.feed(buffer, n, &events);
    for (size_t i = 0; i < events.size(); ++i) {
      if (!pred(events[i])) continue;
      rest->assign(events.begin() + static_cast<std::ptrdiff_t>(i) + 1, events.end());
      return;
    }
  }
  throw StreamError("no " + what + " within 1 s");
}

void drainQuiet(ByteStream& stream, const std::function<int64_t()>& now) {
  uint8_t buffer[4096];
  const int64_t deadline = now() + 2000000;
  while (stream.read(buffer, sizeof buffer, 100) > 0) {
    if (now() > deadline) throw StreamError("the device does not stop sending");
  }
}

LidarSession::Counters turnCounters(const RevolutionAssembler::Counters& c) {
  return {{"samples", c.samples},
          {"turns", c.turns},
          {"partial_turns", c.partial_turns},
          {"broken_turns", c.broken_turns}};
}

class X4Session : public LidarSession {
 public:
  X4Session(const LidarConfig& expected, const SessionOptions& options)
      : expected_(expected),
        model_(catalogueModel(expected, DeviceProtocol::kYdlidarX4)),
        line_(options.baud > 0 ? options.baud : kX4DefaultBaud, options.time != ScanTime::kStream),
        turns_(expected) {}

  void start(ByteStream& stream, const std::function<int64_t()>& now) override {
    stream.setDtr(true);                       // M_EN: motor on
    stream.write(std::string("\xA5\x65", 2));  // stop a scan left running (no reply)
    drainQuiet(stream, now);
    decoder_.reset();
    turns_.clear();
    pending_.clear();
    rate_check_.reset();
    ydlidar::DeviceInfo info;
    stream.write(std::string("\xA5\x90", 2));
    awaitEvent(stream, now, decoder_, &pending_, "X4 device info", [&](const ydlidar::Event& e) {
      if (const auto* i = std::get_if<ydlidar::DeviceInfo>(&e)) info = *i;
      return std::holds_alternative<ydlidar::DeviceInfo>(e);
    });
    identity_ = "YDLIDAR model " + std::to_string(info.model) + " serial " + info.serial +
                " firmware " + std::to_string(info.firmware_major) + "." +
                std::to_string(info.firmware_minor);
    if (info.model != model_.model_code) {
      throw IdentityMismatch("model: the rig file's lidar.model " + model_.name +
                             " has model code " + std::to_string(model_.model_code) +
                             ", the device reports model " + std::to_string(info.model));
    }
    identity_ = "X4 serial " + info.serial;
    int status = 0, code = 0;
    stream.write(std::string("\xA5\x91", 2));
    awaitEvent(stream, now, decoder_, &pending_, "X4 health", [&](const ydlidar::Event& e) {
      if (const auto* h = std::get_if<ydlidar::Health>(&e)) {
        status = h->status;
        code = h->error_code;
        return true;
      }
      return false;
    });
    if (status == 2) throw StreamError("X4 health: error code " + std::to_string(code));
    stream.write(std::string("\xA5\x60", 2));
    awaitEvent(stream, now, decoder_, &pending_, "X4 scan start", [](const ydlidar::Event& e) {
      return std::holds_alternative<ydlidar::ScanStart>(e);
    });
  }

  void onBytes(const uint8_t* data, size_t size, int64_t arrival, std::vector<Scan2D>* scans,
               std::vector<std::string>* errors) override {
    std::vector<ydlidar::Event> events;
    events.swap(pending_);
    decoder_.feed(data, size, &events);
    line_.chunk(arrival, decoder_.counters().bytes);
    handle(events, scans, errors);
  }

  void finish(std::vector<Scan2D>* scans, std::vector<std::string>* errors) override {
    std::vector<ydlidar::Event> events;
    events.swap(pending_);
    decoder_.finish(&events);
    handle(events, scans, errors);
  }
  void stop(ByteStream& stream) override {
    stream.write(std::string("\xA5\x65", 2), 200);
    stream.setDtr(false);
  }
  DecoderCounters decoderCounters() const override { return decoder_.counters(); }
  Counters sessionCounters() const override { return turnCounters(turns_.counters()); }
  std::string identity() const override { return identity_; }

 private:
  // Each packet's samples into turns. A packet leaves the device when its last sample has been
  // measured, and the X4 measures at its model's steady rate: sample i of n at
  // sent - (n - 1 - i) dt.
  void handle(const std::vector<ydlidar::Event>& events, std::vector<Scan2D>* scans,
              std::vector<std::string>* errors) {
    const double dt_us = 1e6 / model_.sample_rate_hz;
    for (const ydlidar::Event& e : events) {
      if (const auto* d = std::get_if<DecodeError>(&e)) {
        errors->push_back(at(d->offset) + d->what);
      } else if (const auto* h = std::get_if<ydlidar::Health>(&e)) {
        if (h->status != 0) {
          errors->push_back(at(h->offset) + "X4 health: status " + std::to_string(h->status) +
                            ", error code " + std::to_string(h->error_code));
        }
      } else if (const auto* p = std::get_if<ydlidar::Packet>(&e)) {
        const int64_t sent = line_.at(p->offset);
        const size_t n = p->samples.size();
        for (size_t i = 0; i < n; ++i) {
          const auto t = sent - static_cast<int64_t>(std::llround((n - 1 - i) * dt_us));
          const ydlidar::Sample& s = p->samples[i];
          turns_.add(
              {s.angle_deg, s.raw_angle_deg, s.distance_mm, 0.0f, t, p->ring_start && i == 0},
              false, scans);
        }
      }
    }
    rate_check_.update(expected_, model_.name, turns_.turnRateHz(), turns_.counters().turns);
  }

  LidarConfig expected_;
  LidarModel model_;
  LineClock line_;
  RevolutionAssembler turns_;
  ydlidar::Decoder decoder_;
  std::vector<ydlidar::Event> pending_;
  std::string identity_ = "YDLIDAR";
  TurnRateCheck rate_check_;
};

class RplidarSession : public LidarSession {
 public:
  RplidarSession(const LidarConfig& expected, const SessionOptions& options)
      : expected_(expected),
        model_(catalogueModel(expected, DeviceProtocol::kRplidar)),
        line_(options.baud > 0 ? options.baud : kRplidarDefaultBaud,
              options.time != ScanTime::kStream),
        turns_(expected) {}

  void start(ByteStream& stream, const std::function<int64_t()>& now) override {
    stream.setDtr(false);  // the A1 adapter's MOTOCTL: DTR low runs the motor
    stream.write(rplidar::request(rplidar::kCmdStop));
    drainQuiet(stream, now);
    decoder_.reset();
    turns_.clear();
    pending_.clear();
    rate_check_.reset();
    rplidar::DeviceInfo info;
    stream.write(rplidar::request(rplidar::kCmdInfo));
    awaitEvent(stream, now, decoder_, &pending_, "RPLIDAR info", [&](const rplidar::Event& e) {
      if (const auto* i = std::get_if<rplidar::DeviceInfo>(&e)) info = *i;
      return std::holds_alternative<rplidar::DeviceInfo>(e);
    });
    const int family = info.model >> 4;  // 1: A1, 2: A2, 3: A3
    const std::string name = family >= 1 && family <= 3 ? "A" + std::to_string(family) : "?";
    identity_ = "RPLIDAR " + name + " (model " + std::to_string(info.model) + ") serial " +
                info.serial + " firmware " + std::to_string(info.firmware_major) + "." +
                std::to_string(info.firmware_minor);
    if (family != model_.model_code) {
      throw IdentityMismatch("model: the rig file's lidar.model " + model_.name + " is family " +
                             std::to_string(model_.model_code) + ", the device (" + identity_ +
                             ") reports model " + std::to_string(info.model) + ", family " +
                             std::to_string(family));
    }
    int status = 0, code = 0;
    stream.write(rplidar::request(rplidar::kCmdHealth));
    awaitEvent(stream, now, decoder_, &pending_, "RPLIDAR health", [&](const rplidar::Event& e) {
      if (const auto* h = std::get_if<rplidar::Health>(&e)) {
        status = h->status;
        code = h->error_code;
        return true;
      }
      return false;
    });
    if (status == 2) {
      // A protection stop: RESET clears it; the next connection tries again.
      stream.write(rplidar::request(rplidar::kCmdReset));
      throw StreamError("RPLIDAR health: error code " + std::to_string(code) + " (reset sent)");
    }
    stream.write(rplidar::request(rplidar::kCmdScan));
    awaitEvent(stream, now, decoder_, &pending_, "RPLIDAR scan start", [](const rplidar::Event& e) {
      return std::holds_alternative<rplidar::ScanStart>(e);
    });
  }

  void onBytes(const uint8_t* data, size_t size, int64_t arrival, std::vector<Scan2D>* scans,
               std::vector<std::string>* errors) override {
    std::vector<rplidar::Event> events;
    events.swap(pending_);
    decoder_.feed(data, size, &events);
    line_.chunk(arrival, decoder_.counters().bytes);
    handle(events, scans, errors);
  }

  void finish(std::vector<Scan2D>* scans, std::vector<std::string>* errors) override {
    std::vector<rplidar::Event> events;
    events.swap(pending_);
    decoder_.finish(&events);
    handle(events, scans, errors);
  }

  void stop(ByteStream& stream) override {
    stream.write(rplidar::request(rplidar::kCmdStop), 200);
    stream.setDtr(true);  // motor off
  }
  DecoderCounters decoderCounters() const override { return decoder_.counters(); }
  Counters sessionCounters() const override { return turnCounters(turns_.counters()); }
  std::string identity() const override { return identity_; }

 private:
  // Samples into turns, each sample sent as soon as measured: its time is when its first byte
  // left the device; S = 1 starts a turn.
  void handle(const std::vector<rplidar::Event>& events, std::vector<Scan2D>* scans,
              std::vector<std::string>* errors) {
    const auto sample_us = static_cast<int64_t>(std::llround(5 * line_.byteUs()));
    for (const rplidar::Event& e : events) {
      if (const auto* d = std::get_if<DecodeError>(&e)) {
        errors->push_back(at(d->offset) + d->what);
      } else if (const auto* batch = std::get_if<rplidar::Samples>(&e)) {
        for (const rplidar::Sample& s : batch->samples) {
          turns_.add({s.angle_deg, s.angle_deg, s.distance_mm, static_cast<float>(s.quality),
                      line_.at(s.end_offset) - sample_us, s.start},
                     true, scans);
        }
      }
    }
    rate_check_.update(expected_, model_.name, turns_.turnRateHz(), turns_.counters().turns);
  }

  LidarConfig expected_;
  LidarModel model_;
  LineClock line_;
  RevolutionAssembler turns_;
  rplidar::Decoder decoder_;
  std::vector<rplidar::Event> pending_;
  std::string identity_ = "RPLIDAR";
  TurnRateCheck rate_check_;
};

}  // namespace

std::unique_ptr<LidarSession> makeLidarSession(DeviceProtocol protocol, const LidarConfig& expected,
                                               const SessionOptions& options) {
  switch (protocol) {
    case DeviceProtocol::kScip:
      return std::make_unique<ScipSession>(expected, options);
    case DeviceProtocol::kYdlidarX4:
      return std::make_unique<X4Session>(expected, options);
    case DeviceProtocol::kRplidar:
      return std::make_unique<RplidarSession>(expected, options);
    case DeviceProtocol::kSim:
    case DeviceProtocol::kHi219:
    case DeviceProtocol::kWheelBoard:
    case DeviceProtocol::kGpiod:
      break;
  }
  throw std::invalid_argument(std::string("no lidar driver session for a ") +
                              protocolName(protocol) + " device");
}

std::unique_ptr<RealLidar> makeRealLidar(const DeviceUri& uri, const LidarConfig& expected,
                                         const RealLidarOptions& options,
                                         std::function<int64_t()> now) {
  return std::make_unique<RealLidar>(
      uri, makeLidarSession(uri.protocol, expected, SessionOptions{}), options, std::move(now));
}

}  // namespace sweepmap
