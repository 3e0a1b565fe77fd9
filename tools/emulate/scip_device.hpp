// An emulated Hokuyo SCIP 2.0 sensor (drivers/protocols/scip.hpp) of any SCIP model of the
// catalogue (core/lidar_models.hpp: UST-10LX, UST-20LX, UTM-30LX, URG-04LX, URG-04LX-UG01), as
// the specification describes it, fed by a simulated world's scans.
//
// Commands: VV, PP, II (identity: PP the model's catalogue values, MODL its name), BM, QT,
// RS, RT, TM0/TM1/TM2, MD/MS/ME (streams: any start/end step within AMIN..AMAX, cluster
// 0..99, skip 0..9, count; 0 = unlimited), GD/GS/GE (the latest scan) and every malformed or
// out-of-range form with the status the specification gives it; an unknown command answers
// "0E". The framing is the same on every model (the URG-04LX's USB port carries the same
// lines; a serial line's baud rate does not change them).
// Data: step s reports the source scan's ray nearest its direction ((s - AFRT) * 2 pi / ARES),
// so a source on any grid serves any sub-range; a cluster reports its nearest valid range
// (the specification's grouping rule); ranges rounded to mm; no return, or a range outside
// DMIN..DMAX, is the model's error code (UST/UTM 1, URG-04LX 0: core/lidar_models.cpp);
// ME's intensity is a model of a matt wall's echo: 20000 / (1 + r[m]) (the real unit is not
// published). The time stamp of a scan is the sensor's counter (EmulatedClock) at the scan's
// step 0, as the specification defines it, whatever steps were requested.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "core/lidar_models.hpp"
#include "core/scan.hpp"
#include "tools/emulate/devices.hpp"
#include "tools/emulate/emulated_lidar.hpp"

namespace sweepmap {

class ScipDevice : public EmulatedLidar {
 public:
  // `model`: a SCIP model of the catalogue (std::invalid_argument otherwise).
  ScipDevice(ScanSource source, const EmulatedClock& clock, int64_t power_on_us,
             const std::string& model = "UST-10LX");
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
  // When `scan` (on its own grid) looked at `step`, and which of its rays did (-1: none).
  int64_t stepUtime(const Scan2D& scan, double step) const;
  int rayAt(const Scan2D& scan, int step) const;
  std::string dataOf(const Scan2D& scan, const Request& r) const;

  ScanSource source_;
  LidarModel model_;
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
