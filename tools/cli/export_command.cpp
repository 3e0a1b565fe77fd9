// `sweepmap export`: logs and clouds in other tools' formats (tools/export/).
#include <iostream>

#include "core/command_line.hpp"
#include "core/event_log.hpp"
#include "tools/cli/commands.hpp"
#include "tools/export/export_las.hpp"
#include "tools/export/export_mcap.hpp"

namespace sweepmap {
namespace {

void addMcap(CLI::App* parent, std::map<CLI::App*, Runner>* runners) {
  auto* cmd = parent->add_subcommand(
      "mcap",
      "LCM logs as one MCAP file (https://mcap.dev/spec) for Foxglove, Lichtblick and other MCAP "
      "readers: the logs merged in log-time order (give a raw log and a replay's "
      "derived.lcmlog to have both), every LCM channel raw (message and schema encoding "
      "\"lcm\", not a registered MCAP encoding: readers without LCM support skip them; the "
      "schema is the type's .lcm text), and the derived topics in the Foxglove schemas (JSON): "
      "/sweep_cloud (foxglove.PointCloud), /map (voxel centres), /pose, /wheel_odometry, "
      "/truth_pose (foxglove.PoseInFrame), /tf (foxglove.FrameTransform: the rig's frames), "
      "/lidar_scan (foxglove.LaserScan) or /lidar_points (a scan with per-ray angles), "
      "/profile, /status (foxglove.Log). Chunks zstd-compressed, with message indexes, chunk "
      "indexes and statistics so readers can seek. Corrupt log bytes are skipped as LCM's reader "
      "skips them (exit status 1, the file is still written)");
  cmd->footer(
      "Exit status: 0 exported; 1 a log held corrupt bytes (skipped; the file is written) or no "
      "event; 2 bad option, rig or a missing log; 4 the file cannot be written.");
  struct Opts {
    std::vector<std::string> logs, sets;
    std::string rig, out;
    bool no_raw = false, no_compression = false;
  };
  auto o = std::make_shared<Opts>();
  cmd->add_option("LOG", o->logs, "LCM logs (sweepmap sim, record, replay's derived.lcmlog)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--rig", o->rig, "rig file or name the logs were recorded with (its frames)")
      ->required();
  cmd->add_option("--set", o->sets, "override a rig config key: key=value (repeatable)");
  cmd->add_option("--out", o->out, "output .mcap file")->required();
  cmd->add_flag("--no-raw", o->no_raw, "leave the raw LCM channels out");
  cmd->add_flag("--no-compression", o->no_compression, "uncompressed chunks");
  (*runners)[cmd] = [o]() -> int {
    const Rig rig = loadRig(o->rig, o->sets);
    checkOutputFile(o->out, o->logs);
    ExportMcapOptions options{o->logs, o->out, !o->no_raw, !o->no_compression};
    ExportMcapResult r;
    try {
      r = exportMcap(rig, options);
    } catch (const LogError&) {
      throw;
    } catch (const std::runtime_error& e) {  // the MCAP file could not be written
      throw CommandError(kExitDeviceIo, e.what());
    }
    std::cerr << "export mcap: " << r.events << " LCM events -> " << r.messages << " messages on "
              << r.topics.size() << " topics, " << r.bytes << " bytes -> " << o->out << "\n";
    for (const auto& [channel, n] : r.rejected) {
      std::cerr << "export mcap: " << channel << ": " << n << " messages did not decode\n";
    }
    if (r.log_error) std::cerr << "export mcap: " << r.error << "\n";
    return r.log_error || r.events == 0 ? kExitBadInput : kExitOk;
  };
}

void addLas(CLI::App* parent, std::map<CLI::App*, Runner>* runners) {
  auto* cmd = parent->add_subcommand(
      "las",
      "Clouds as one LAS 1.4 file (ASPRS R15, point data format 6: scaled X, Y, Z at 0.1 mm, "
      "intensity, GPS time) from PLY files (replay's and eval's clouds) or LCM logs (every "
      "SWEEP_CLOUD point, its chunk's time as adjusted standard GPS time), in the order given. "
      "Intensity: the lidar's reading (device units) rounded and clipped to 0..65535, from a "
      "chunk's intensities or a PLY's intensity or scalar_intensity property; 0 where the "
      "lidar measures none (rig B's X4, rig C's profiler)");
  cmd->footer(
      "Exit status: 0 exported; 1 an input is not a readable PLY or log, a log held corrupt "
      "bytes (skipped; the file is written), or there is no point; 2 bad option or a missing "
      "input; 4 the file cannot be written.");
  struct Opts {
    std::vector<std::string> inputs;
    std::string out;
  };
  auto o = std::make_shared<Opts>();
  cmd->add_option("INPUT", o->inputs, "PLY files or LCM logs")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--out", o->out, "output .las file")->required();
  (*runners)[cmd] = [o]() -> int {
    checkOutputFile(o->out, o->inputs);
    const ExportLasResult r = exportLas({o->inputs, o->out});
    std::cerr << "export las: " << r.las.points << " points, " << r.las.bytes << " bytes -> "
              << o->out << "\n";
    if (r.chunks_rejected > 0) {
      std::cerr << "export las: " << r.chunks_rejected << " SWEEP_CLOUD chunks did not decode\n";
    }
    if (r.log_error) std::cerr << "export las: " << r.error << "\n";
    return r.log_error || r.las.points == 0 ? kExitBadInput : kExitOk;
  };
}

}  // namespace

Runner addExportCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "export", "Export logs and clouds to other tools' formats: MCAP (Foxglove), LAS 1.4");
  cmd->require_subcommand(1);
  auto runners = std::make_shared<std::map<CLI::App*, Runner>>();
  addMcap(cmd, runners.get());
  addLas(cmd, runners.get());
  return [runners]() -> int {
    for (auto& [sub, run] : *runners) {
      if (sub->parsed()) return run();
    }
    return kExitUsage;
  };
}

}  // namespace sweepmap
