// `sweepmap record`: our own LCM logger with presets, splitting and a disk guard
// (tools/ops/record.hpp).
#include <filesystem>
#include <memory>

#include "core/command_line.hpp"
#include "processes/channels.hpp"
#include "tools/cli/commands.hpp"
#include "tools/ops/record.hpp"

namespace sweepmap {

Runner addRecordCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "record",
      "Record the LCM bus into the LCM event log --out DIR/NAME (received through sweepmap's "
      "validating receive path, not liblcm's): --preset raw (what replay needs: "
      "LIDAR_SCAN, MOTOR_STATE, MOTOR_SWITCH, SCAN_WINDOW, WHEEL_TICKS, IMU, WHEEL_CMD, PROFILE, "
      "STATUS_*, TRUTH_*) or all; --split-mb N starts a new file (NAME.00, NAME.01, ...) every N "
      "MB; when the free space falls below --min-free-mb, or the disk refuses a write, the "
      "recording stops (the log ends with its last complete event; exit status 4). Stops at "
      "SIGINT/SIGTERM or after "
      "--duration seconds");
  cmd->footer(
      "Exit status: 0 recorded; 2 bad option, or --out DIR already holds a log named --name "
      "and --split-mb is 0 (see --force; split files take the next free number); 4 the socket "
      "or the file cannot be opened, or the disk is (nearly) full or refused a write.");
  auto o = std::make_shared<RecordOptions>();
  o->lcm_url = kDefaultLcmUrl;
  cmd->add_option("--out", o->out, "output folder (may hold other recordings)")->required();
  auto force = std::make_shared<bool>(false);
  cmd->add_flag("--force", *force,
                "overwrite a log of the same --name in --out (without --split-mb)");
  cmd->add_option("--name", o->name, "log file name in it")->capture_default_str();
  cmd->add_option("--preset", o->preset, "raw or all")
      ->capture_default_str()
      ->check(CLI::IsMember({"raw", "all"}));
  cmd->add_option("--split-mb", o->split_mb, "start a new file every N MB (0: one file)")
      ->capture_default_str()
      ->check(atLeast(0));
  cmd->add_option("--min-free-mb", o->min_free_mb,
                  "stop cleanly when the output's file system has less free")
      ->capture_default_str()
      ->check(atLeast(0));
  cmd->add_option("--lcm-url", o->lcm_url, "LCM URL to record")->capture_default_str();
  cmd->add_option("--duration", o->duration_s, "stop after [s] (0: at SIGINT/SIGTERM)")
      ->capture_default_str()
      ->check(atLeast(0));
  cmd->add_option("--allow-senders", o->allow_senders,
                  "record only what these IPv4 addresses send (comma-separated); default: any")
      ->delimiter(',');
  cmd->add_option("--key-file", o->key_file,
                  "shared key (chmod 600): record only messages signed with it (the log holds "
                  "them without their signature); default: no check");
  cmd->add_option("--max-mb", o->max_mb,
                  "stop cleanly (exit 0) before this recording's files together pass N MB "
                  "(0: only --min-free-mb bounds them)")
      ->capture_default_str()
      ->check(atLeast(0));
  cmd->add_option("--queue-capacity", o->queue_capacity,
                  "bound of the queue between the receiver and the writer [messages]; a message "
                  "that finds it full is dropped and counted")
      ->capture_default_str()
      ->check(atLeast(1));
  cmd->add_option("--queue-mib", o->queue_mib, "the same queue's bound in MiB")
      ->capture_default_str()
      ->check(atLeast(1));
  return [o, force]() -> int {
    namespace fs = std::filesystem;
    std::error_code ec;
    if (fs::exists(o->out, ec) && !fs::is_directory(o->out, ec)) {
      throw ConfigError("--out '" + o->out + "' is a file; give a folder");
    }
    // The folder keeps many recordings. Split files never overwrite one (lcm-logger -i picks the
    // next free NAME.NN: a restarted recorder goes on); a single file would (lcm-logger -f).
    const fs::path file = fs::path(o->out) / o->name;
    if (o->split_mb == 0 && !*force && fs::exists(file, ec)) {
      throw ConfigError(file.string() +
                        " exists: give another --name, or add --force to overwrite it");
    }
    return runRecord(*o);
  };
}

}  // namespace sweepmap
