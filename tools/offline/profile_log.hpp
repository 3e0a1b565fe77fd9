// Reading rig C's logs: the PROFILE messages of each turntable sweep as the points of one
// plate pose (calib/axis_offset.hpp), and the simulator's truth where the log has it.
#pragma once

#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "calib/axis_offset.hpp"
#include "sim/profiler.hpp"

namespace sweepmap {

// A log that cannot serve: no profiles, a malformed or non-finite profile, a corrupt event.
// The message names the log and, where there is one, the byte offset of the event.
class ProfileLogError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct ProfileLogTruth {
  ProfileGeometry geometry;  // true M, N, tilt, encoder zero
  std::string scene;
};

// The simulated test piece's truth (TRUTH_TEST_PIECE): its true sizes (distance_mm unused)
// and its frame in O_r (u along the line, v along the scan, w up; origin at the top face's
// centre).
struct TestPieceTruth {
  int32_t sweep_id = 0;
  TestPieceConfig sizes;
  Eigen::Vector3d origin, u, v, w;
};

struct ProfileLog {
  std::vector<PlanePoints> sweeps;  // one per sweep id, in order of first appearance
  std::optional<ProfileLogTruth> truth;
  std::optional<TestPieceTruth> test_piece;  // the first TRUTH_TEST_PIECE, if any
  int64_t profiles = 0;
};

// Every PROFILE of the log, grouped by sweep (sources "LOG sweep K"). Throws
// ProfileLogError as above.
ProfileLog readProfileLog(const std::string& path);

}  // namespace sweepmap
