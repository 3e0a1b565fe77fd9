// Helpers for the end-to-end tests: paths, running the tool, reading files and logs.
#pragma once

#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/rig_components.hpp"
#include "core/set_arguments.hpp"
#include "processes/node.hpp"
#include "sweepmap/pose2d_t.hpp"

namespace sweepmap {
namespace test {

namespace fs = std::filesystem;

std::string sourcePath(const std::string& rel);  // in the source tree
std::string binPath(const std::string& name);    // build/bin/<name>
fs::path scratchDir(const std::string& name);    // fresh, under the build tree

// Runs build/bin/sweepmap with `args`; returns the exit status. Output goes to
// `dir/<label>.txt` if `dir` is set.
int sweepmap(const std::vector<std::string>& args, const fs::path& out_file = {});
// The same, run from the working directory `cwd`.
int sweepmapIn(const fs::path& cwd, const std::vector<std::string>& args,
               const fs::path& out_file = {});
// Any executable of build/bin (sweepmap, sweepmap-motor, ...), run from `cwd` ("" = here).
int runIn(const fs::path& cwd, const std::string& exe, const std::vector<std::string>& args,
          const fs::path& out_file = {});

std::string readFile(const fs::path& p);
nlohmann::json readJson(const fs::path& p);
// Every message of `channel` in the log, in log order.
std::vector<Message> readChannel(const std::string& log, const std::string& channel);

// Rig B's tracks: the poses of a channel (TRUTH_POSE, ODOMETRY_POSE, WHEEL_ODOMETRY) in a log.
std::vector<pose2d_t> poses(const std::string& log, const std::string& channel);
double pathLength(const std::vector<pose2d_t>& p);
// A track against the truth interpolated at each pose's time (poses outside the truth's span
// are skipped): position errors [m].
struct TrackError {
  size_t compared = 0;
  double max_m = 0.0;
  double rms_m = 0.0;
  double final_m = 0.0;  // at the last compared pose
};
TrackError trackError(const std::vector<pose2d_t>& track, const std::vector<pose2d_t>& truth);
// The largest distance [m] of a track's positions from the truth's path near them (its segments
// within +-window_us of each pose's time): the cross-track error, blind to a pose stamped late
// along the path (a live host's scheduling), which trackError() counts as error.
double pathErrorMax(const std::vector<pose2d_t>& track, const std::vector<pose2d_t>& truth,
                    int64_t window_us);

// Rig C: the RMS distance [mm] of a sweep's cloud (a PCD in metres, frame O_r) from the plate's
// true plane in the log's TRUTH_PROFILE_RIG of that sweep; -1 if the log has none.
double rmsToTruePlane(const std::string& log, const fs::path& pcd, int sweep);

}  // namespace test
}  // namespace sweepmap

namespace sweepmap {
namespace test {

// A simulated log shared by the tests of one build: made once (under a file lock, so
// parallel CTest processes wait for one another) with `sweepmap sim <args> --out LOG` (any
// rig kind: the args name the rig), and remade when the sweepmap binary changes.
std::string cachedSimLog(const std::string& name, const std::vector<std::string>& sim_args);

// `--set key=0` for each rig-A error and scene artefact the paper's model lacks
// (SimRigConfig::paperSettings): appended by the tests of the paper's methods.
inline std::vector<std::string> paperModelArgs() {
  return setArguments(SimRigConfig::paperSettings());
}
// `sweepmap <args> --out DIR` run once per build (as above) for every test process that asks:
// DIR, the exit status and the command's output (stdout and stderr).
struct CachedRun {
  fs::path out;
  int status;
  fs::path output;
};
CachedRun cachedRun(const std::string& name, const std::vector<std::string>& args);
// Same for a replay of a cached log into a directory.
fs::path cachedReplay(const std::string& name, const std::string& log,
                      const std::vector<std::string>& extra_args);

}  // namespace test
}  // namespace sweepmap
