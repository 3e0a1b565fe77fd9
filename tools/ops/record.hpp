// `sweepmap record`: an LCM logger of our own, on sweepmap's validating receive path
// (net/udpm_receiver.hpp; lcm-logger runs liblcm 1.3.1's receive code, which one malformed
// datagram crashes, and a crashed recorder loses the run). The files are LCM event logs, as
// lcm-logger writes them.
//
// Presets: `raw` records only what replay needs — the devices' raw channels (LIDAR_SCAN,
// MOTOR_STATE, MOTOR_SWITCH, SCAN_WINDOW, WHEEL_TICKS, IMU, WHEEL_CMD), the processes'
// STATUS_* and a simulator's TRUTH_* — so everything derived can be recomputed offline;
// `all` records every channel. `split_mb` > 0 starts a new file (run.00, run.01, ...) every
// that many MB. The disk is watched: when the free space on the output's file system falls
// below `min_free_mb`, the recording stops; a write the disk refuses first cuts the file back
// to its last complete event. Either way the log never ends inside an event; the reason is
// printed and the exit status is 4 (I/O failure, core/exit_codes.hpp). SIGINT/SIGTERM stop
// it cleanly too.
#pragma once

#include <string>
#include <vector>

namespace sweepmap {

struct RecordOptions {
  std::string out;  // directory, created if needed
  std::string name = "run";
  std::string preset = "raw";  // raw | all
  double split_mb = 0.0;
  double min_free_mb = 100.0;
  std::string lcm_url;
  double duration_s = 0.0;                 // 0: until SIGINT/SIGTERM
  std::vector<std::string> allow_senders;  // IPv4 addresses; empty: any sender
  std::string key_file;                    // set: only messages signed with this key
  // Bounds: the queue between the receive thread and the writer (a message that finds it full
  // is dropped and counted), and what the files of this recording may hold together (0: only
  // min_free_mb bounds it; reached: the recording stops, the log ends at an event, exit 0).
  size_t queue_capacity = 10000;  // messages
  double queue_mib = 64.0;
  double max_mb = 0.0;
};

// The channel regex of a preset; throws std::invalid_argument for an unknown one.
std::string recordChannels(const std::string& preset);

// Free space [MB] on the file system holding `path`, or -1 if it cannot be read.
double freeMb(const std::string& path);

// Returns 0 after a clean stop (signal, duration or max_mb), 2 for bad options, 4 when the disk ran
// low or refused a write, or the socket or file could not be opened.
int runRecord(const RecordOptions& options);

}  // namespace sweepmap
