// `sweepmap record`: lcm-logger with what a field recording needs around it.
//
// Presets: `raw` records only what replay needs — the devices' raw channels (LIDAR_SCAN,
// MOTOR_STATE, MOTOR_SWITCH, SCAN_WINDOW, WHEEL_TICKS, IMU, WHEEL_CMD), the processes'
// STATUS_* and a simulator's TRUTH_* — so everything derived can be recomputed offline;
// `all` records every channel. `split_mb` > 0 starts a new file (run.00, run.01, ...) every
// that many MB. The disk is watched: when the free space on the output's file system falls
// below `min_free_mb`, lcm-logger is stopped (SIGINT: it writes what it holds and closes the
// file), so a log is never cut inside an event by a full disk; the reason is printed and the
// exit status is 4. SIGINT/SIGTERM stop it cleanly too.
#pragma once

#include <string>

namespace sweepmap {

struct RecordOptions {
  std::string out;  // directory, created if needed
  std::string name = "run";
  std::string preset = "raw";  // raw | all
  double split_mb = 0.0;
  double min_free_mb = 100.0;
  std::string lcm_url;
  double duration_s = 0.0;  // 0: until SIGINT/SIGTERM
};

// The lcm-logger channel regex of a preset; throws std::invalid_argument for an unknown one.
std::string recordChannels(const std::string& preset);

// Free space [MB] on the file system holding `path`, or -1 if it cannot be read.
double freeMb(const std::string& path);

// Returns 0 after a clean stop (signal or duration), 2 for bad options or when lcm-logger
// cannot start, 4 when the disk ran low or lcm-logger failed.
int runRecord(const RecordOptions& options);

}  // namespace sweepmap
