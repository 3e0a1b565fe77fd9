// `sweepmap capture` and `sweepmap decode`: raw device bytes to a file, and back to scans
// (tools/devices/capture.hpp).
#include <iostream>

#include "core/command_line.hpp"
#include "core/config.hpp"
#include "core/device_uri.hpp"
#include "core/lidar_models.hpp"
#include "rigs/rig_file.hpp"
#include "tools/cli/commands.hpp"
#include "tools/devices/capture.hpp"

namespace sweepmap {
namespace {

// The lidar the bytes should come from: the rig file's lidar section.
LidarConfig expectedLidar(const std::string& rig, const std::vector<std::string>& sets) {
  return loadRig(rig, sets).lidar();
}

// The lidar `decode PROTOCOL` decodes as: the rig's, or with `--lidar-model` the model's whole
// field of view. Its model must speak `protocol` (else a ConfigError naming both).
LidarConfig decodeLidar(const std::string& protocol, const std::string& model,
                        const std::string& rig, const std::vector<std::string>& sets) {
  const LidarConfig l = model.empty() ? expectedLidar(rig, sets) : LidarConfig{};
  const std::string name = model.empty() ? l.model : model;
  const LidarModel* m = findLidarModel(name);
  if (m == nullptr) {
    throw ConfigError("--lidar-model: '" + name + "' is not one of " + lidarModelNames());
  }
  const DeviceProtocol want = protocol == "scip" ? DeviceProtocol::kScip
                              : protocol == "x4" ? DeviceProtocol::kYdlidarX4
                                                 : DeviceProtocol::kRplidar;
  if (m->protocol != want) {
    throw ConfigError((model.empty() ? "the rig's lidar.model: " : "--lidar-model: ") + name +
                      " speaks " + protocolName(m->protocol) + ", not " + protocol);
  }
  return model.empty() ? l : fullFieldOf(*m);
}

}  // namespace

Runner addCaptureCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "capture",
      "Record a real lidar's raw byte stream with host receive times: connects as "
      "sweepmap-lidar does (identifies the device and checks it against the rig file, starts "
      "streaming) and writes every byte received, the start-up exchange included, to a "
      "capture file for `sweepmap decode` (format: drivers/io/capture_file.hpp).");
  auto o = std::make_shared<CaptureOptions>();
  auto rig = std::make_shared<std::string>();
  auto sets = std::make_shared<std::vector<std::string>>();
  cmd->add_option("uri", o->uri,
                  "scip://HOST[:PORT] | ydlidar:///dev/PORT | rplidar:///dev/PORT[?baud=N]")
      ->required();
  cmd->add_option("--seconds", o->seconds, "how long to record after the first byte")
      ->capture_default_str()
      ->check(greaterThan(0));
  cmd->add_option("--out", o->out, "capture file")->required();
  cmd->add_option("--rig", *rig,
                  "rig file or name whose lidar section the device must match (default: rig_a "
                  "for scip, rig_b otherwise)");
  cmd->add_option("--set", *sets, "override a rig key: key=value (repeatable)");
  cmd->footer(
      "Exit status: 0 captured; 2 bad option, URI or rig; 4 the device sent nothing or the "
      "capture file cannot be written.");
  return [o, rig, sets]() -> int {
    try {
      if (parseDeviceUri(o->uri).protocol == DeviceProtocol::kSim) {
        throw ConfigError("capture needs a real device's URI, not sim");
      }
    } catch (const std::invalid_argument& e) {
      throw ConfigError(e.what());
    }
    checkOutputFile(o->out);
    const std::string r =
        !rig->empty() ? *rig : (o->uri.rfind("scip:", 0) == 0 ? "rig_a" : "rig_b");
    // runCapture's 1: nothing received, or the file could not be written.
    return runCapture(*o, expectedLidar(r, *sets), std::cout) == 0 ? kExitOk : kExitDeviceIo;
  };
}

Runner addDecodeCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "decode",
      "Turn a capture (sweepmap capture) or any file of raw protocol bytes into LIDAR_SCAN "
      "messages in an LCM log (HI219 bytes into IMU, wheel board bytes into WHEEL_TICKS), with "
      "the driver's own decoder: every checksum error, resync "
      "and bad reply is reported with its byte offset in the device's stream. Captures keep "
      "their receive times; raw SCIP bytes are timed by the device's stamps, raw serial bytes "
      "by their time on the line at the baud rate.");
  auto o = std::make_shared<DecodeOptions>();
  auto rig = std::make_shared<std::string>();
  auto sets = std::make_shared<std::vector<std::string>>();
  cmd->add_option("protocol", o->protocol,
                  "scip | x4 | rplidar (LIDAR_SCAN) | hi219 (IMU) | wheelboard (WHEEL_TICKS)")
      ->required()
      ->check(CLI::IsMember({"scip", "x4", "rplidar", "hi219", "wheelboard"}));
  cmd->add_option("file", o->in, "capture or raw bytes")->required()->check(CLI::ExistingFile);
  cmd->add_option("--out", o->out, "LCM log to write")->required();
  auto* rig_opt = cmd->add_option("--rig", *rig,
                                  "rig file or name of the lidar (model, field of view, range "
                                  "limits; default: rig_a for scip, rig_b for x4, "
                                  "--lidar-model RPLIDAR-A1 for rplidar, rig_b otherwise)");
  auto* set_opt = cmd->add_option("--set", *sets, "override a rig key: key=value (repeatable)");
  auto model = std::make_shared<std::string>();
  cmd->add_option("--lidar-model", *model,
                  "decode as this lidar model, its whole field of view and range limits, "
                  "instead of a rig's lidar (core/lidar_models.hpp): " +
                      lidarModelNames())
      ->excludes(rig_opt)
      ->excludes(set_opt);
  cmd->add_option("--baud", o->baud, "raw serial bytes: the line rate (default: the device's)");
  cmd->footer(
      "Exit status: 0 decoded; 1 the file is corrupt (a capture's bad record: what came before "
      "is kept) or holds nothing of the protocol; 2 bad option or rig, or a missing input file; 4 "
      "the log cannot be written.");
  return [o, rig, sets, model]() -> int {
    checkOutputFile(o->out, {o->in});
    const std::string r = !rig->empty() ? *rig : (o->protocol == "scip" ? "rig_a" : "rig_b");
    const bool lidar = o->protocol == "scip" || o->protocol == "x4" || o->protocol == "rplidar";
    // rig_b's lidar is an X4: RPLIDAR bytes without a rig are an A1's.
    const bool a1 = o->protocol == "rplidar" && rig->empty() && sets->empty();
    const std::string m = model->empty() && a1 ? "RPLIDAR-A1" : *model;
    const LidarConfig expected =
        lidar ? decodeLidar(o->protocol, m, r, *sets) : expectedLidar(r, *sets);
    const DecodeResult res = runDecode(*o, expected, std::cout);
    if (res.scans == 0) {
      std::cerr << "decode: nothing decoded: " << o->in << " holds no " << o->protocol
                << " message (" << res.bytes << " bytes)\n";
      return kExitBadInput;
    }
    return res.file_error.empty() ? kExitOk : kExitBadInput;
  };
}

}  // namespace sweepmap
