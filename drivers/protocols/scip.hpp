// SCIP 2.0, the protocol of Hokuyo's URG / UTM / UST lidars (UST-10LX, UST-20LX over TCP),
// from Hokuyo's "URG Series Communication Protocol Specification SCIP-Version 2.0".
//
// A command is a line: two letters, parameters, an optional string ";tag" (at most 16
// characters), then LF (CR or CR LF accepted). Every reply is lines ending with LF:
//   the echo of the command | the status: two characters and their checksum |
//   data lines, each followed by its checksum | an empty line (the reply ends with LF LF).
// Checksum: the low 6 bits of the sum of the line's bytes, plus 0x30 ("00" -> 'P').
// Numbers are sent 6 bits per character, each plus 0x30, most significant first, in 2, 3 or
// 4 characters ("CB" = 1234, "1Dh" = 5432: the specification's examples). Range data are
// split into blocks of 64 characters each with its own checksum; a value may straddle two
// blocks. Streams (MD/MS/ME) answer "00" once, then each scan with status "99", the echo's
// last two digits counting the scans left. VV/PP/II lines are "KEY:value;" and a checksum of
// the characters before the ';' ("PROT:SCIP 2.0;N").
//
// Time stamps: the sensor's millisecond counter, 24 bits (wraps every 4.66 h), sent in 4
// characters with each scan and by TM1. A scan's stamp is the counter at the scan's step 0
// ("Time stamp is a timer value at 0th step of every scan", SCIP2.0 specification
// C-42-03320B, §7), whatever steps were requested: ray 0 of a reply from step s was measured
// s steps later (firstRayDelayS); the emulator stamps so.
//
// Angles (core/lidar_models.hpp): step s at (s - AFRT) * 2 pi / ARES; a cluster of c steps,
// which sends the smallest of its values, at its middle step s + (c - 1) / 2.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "core/scan.hpp"
#include "drivers/protocols/decoder.hpp"

namespace sweepmap {
namespace scip {

// value -> `chars` characters (chars 2..4); values that do not fit are clamped.
std::string encodeValue(uint32_t value, int chars);
// characters -> value; nullopt for a character outside 0x30..0x6F or a length outside 1..4.
std::optional<uint32_t> decodeValue(std::string_view chars);
char checksum(std::string_view bytes);
// "00P": a status (or any data) with its checksum.
std::string withChecksum(std::string_view data);

// The meaning of `status` in a reply to `command` ("MD", "BM", ...), as the specification
// lists it; "unknown status" for a code it does not define.
std::string statusText(const std::string& command, const std::string& status);

// A reply that is not range data (VV, PP, II, BM, QT, RS, RT, RB, TM, SS, CR, HS, the
// acknowledgement "00" of MD/MS/ME, an error status of any command).
struct Reply {
  std::string command;                        // the two letters
  std::string echo;                           // the whole echo line
  std::string status;                         // two characters
  bool ok = false;                            // "00" (or "99"; "02" for BM: already on)
  std::map<std::string, std::string> params;  // VV/PP/II: KEY -> value
  std::optional<uint32_t> time_ms;            // TM1
  int64_t offset = 0;                         // of the echo's first byte in the stream
};

// One scan of MD/MS/ME (streamed) or GD/GS/GE.
struct ScanData {
  std::string command;
  int start_step = 0, end_step = 0, cluster = 1;
  int remaining = 0;                  // streams: scans still to come (0 with an unlimited stream)
  uint32_t time_ms = 0;               // 24-bit stamp
  std::vector<uint32_t> ranges_mm;    // one per cluster; < DMIN: the sensor's error codes
  std::vector<uint32_t> intensities;  // ME/GE, else empty
  int64_t offset = 0;
};

using Event = std::variant<Reply, ScanData, DecodeError>;

class Decoder {
 public:
  void feed(const uint8_t* data, size_t size, std::vector<Event>* out);
  const DecoderCounters& counters() const { return counters_; }
  void reset();

 private:
  enum class State { kEcho, kStatus, kBody };
  void line(std::string_view text, int64_t offset, std::vector<Event>* out);
  bool startReply(std::string_view echo, int64_t offset, std::vector<Event>* out);
  void finishReply(std::vector<Event>* out);
  bool bodyChecksumsOk(const std::string& command, const std::string& where,
                       std::vector<Event>* out);
  void emitScan(const std::string& command, const std::string& where, std::vector<Event>* out);
  bool decodeScanValues(const std::string& where, ScanData* s, std::vector<Event>* out);
  void emitReply(const std::string& command, const std::string& where, std::vector<Event>* out);
  void discard(int64_t offset, size_t bytes, const std::string& why, std::vector<Event>* out);
  void flushGarbage(std::vector<Event>* out);

  DecoderCounters counters_;
  std::string partial_;         // bytes of the current line
  int64_t partial_offset_ = 0;  // stream offset of partial_[0]
  bool partial_too_long_ = false;
  State state_ = State::kEcho;
  std::string echo_, status_;
  int64_t reply_offset_ = 0;
  std::vector<std::pair<std::string, int64_t>> body_;  // lines with their offsets
  int64_t garbage_offset_ = 0, garbage_bytes_ = 0;     // the run of skipped bytes being counted
  std::string garbage_why_;
};

// The sensor's parameters from PP.
struct Params {
  std::string model;
  int dmin_mm = 0, dmax_mm = 0, ares = 0, amin = 0, amax = 0, afrt = 0, scan_rpm = 0;
  double stepRad() const;
  double angleRad(double step) const;  // from the front step, counter-clockwise positive
  double stepPeriodS() const { return 60.0 / scan_rpm / ares; }
};
// Throws std::runtime_error naming a missing or insane key.
Params parseParams(const std::map<std::string, std::string>& pp);

// A scan as sweepmap's Scan2D, angles and ranges only: ray i at the middle of its cluster,
// step start + i*cluster + (cluster - 1) / 2 (a last cluster cut short by the end step at its
// own middle: then angles_rad holds every ray's angle), ranges mm -> m with the sensor's
// error codes (< DMIN) and anything beyond DMAX as 0 (no return), intensities as sent,
// device_stamp = the 24-bit stamp. utime and time_increment_ns are the driver's (host clock).
Scan2D toScan2D(const ScanData& scan, const Params& pp);
// From the scan's stamp (its step 0) to its ray 0's middle step [s].
double firstRayDelayS(const ScanData& scan, const Params& pp);

// Command lines (host -> sensor): "MD0000108000000\n" and so on.
std::string scanCommand(const std::string& command, int start, int end, int cluster, int skip,
                        int scans);

}  // namespace scip
}  // namespace sweepmap
