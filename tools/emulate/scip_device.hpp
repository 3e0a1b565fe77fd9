// An emulated Hokuyo UST-10LX speaking SCIP 2.0 (drivers/protocols/scip.hpp) as the
// specification describes, fed by a simulated world's scans.
//
// Commands: VV, PP, II (identity; values of a UST-10LX: PP as Hokuyo's UST-10LX manual gives
// them, DMAX 30000 mm, ARES 1440, AMIN 0, AMAX 1080, AFRT 540, SCAN 2400 rpm), BM, QT, RS,
// RT, TM0/TM1/TM2, MD/MS/ME (streams: start/end step, cluster, skip, count; 0 = unlimited),
// GD/GS/GE (the latest scan) and every malformed or out-of-range form with the status the
// specification gives it; an unknown command answers "0E".
// Data: a source scan's ray i is step i (the source must have the sensor's 1081 rays at
// AMIN..AMAX); ranges rounded to mm; no return is error code 1 (below DMIN); ME's intensity
// is a model of a matt wall's echo: 20000 / (1 + r[m]) (the real unit is not published).
// The time stamp of a scan is the sensor's counter (EmulatedClock) at its first requested
// step's measurement (the source's first-ray time + (start - AMIN) ray periods).
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "core/scan.hpp"
#include "tools/emulate/devices.hpp"
#include "tools/emulate/emulated_lidar.hpp"

namespace sweepmap {

class ScipDevice : public EmulatedLidar {
 public:
  ScipDevice(ScanSource source, const EmulatedClock& clock, int64_t power_on_us);
  void receive(const uint8_t* data, size_t size, int64_t now_us, std::string* out) override;
  void advance(int64_t now_us, std::string* out) override;
  void reset(int64_t now_us) override;

 private:
  void command(const std::string& line, int64_t now_us, std::string* out);
  struct Request {
    std::string command;
    int start, end, cluster;
  };
  struct Reply {
    std::string status, body;
  };
  // The steps of command(); each returns the status it answers ("" for none yet).
  std::string identityBody(const std::string& cmd, int64_t now_us) const;  // VV, PP, II
  std::string laserCommand(const std::string& cmd);                        // BM, QT, RS, RT
  Reply timeAdjustCommand(const std::string& params, int64_t now_us);      // TM0/1/2
  // Start, end and cluster of MD/MS/ME (`stream`) or GD/GS/GE.
  std::string parseRange(const std::string& params, bool stream, Request* r) const;
  void startStream(const Request& r, int skip, int count, const std::string& tag);
  // `head`: the echo and "99" status of a streamed scan (empty for GD/GS/GE).
  void scanReply(const Scan2D& scan, const Request& r, const std::string& head, std::string* out);
  uint32_t counterAt(int64_t t_us) const;

  ScanSource source_;
  EmulatedClock clock_;
  int64_t power_on_us_;
  std::string line_;
  bool laser_on_ = false;
  bool adjust_mode_ = false;
  std::optional<Scan2D> latest_;
  // The stream in progress.
  bool streaming_ = false;
  std::string stream_command_, stream_tag_;
  int start_ = 0, end_ = 0, cluster_ = 1, skip_ = 0, remaining_ = 0, skipped_ = 0;
  bool unlimited_ = false;
};

}  // namespace sweepmap
