// Rig B's measures (Miao 2022 section 5): trajectory errors against the truth, the room's
// RANSAC planes with its dimensions L1-L3 and the deviations of Fig. 9, the double wall
// ("ghost") where a drive comes back to a place (Fig. 11) and the double walls the two halves
// of the scans see on the calibration circle (Fig. 6-7). Internal to tools/eval.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "calib/room_planes.hpp"
#include "calib/walls.hpp"
#include "calib/world_assembly.hpp"
#include "tools/eval/metrics.hpp"
#include "tools/offline/mobile_log.hpp"

namespace sweepmap::eval {

// Position error of `estimate` against `truth` at each estimate's time.
struct TrajectoryErrors {
  std::vector<double> t_s, error_m, heading_error_rad;
  std::optional<double> rmse_m, final_m, max_m, heading_rmse_rad, heading_max_rad;
};
TrajectoryErrors trajectoryErrors(const PoseTrack& estimate, const PoseTrack& truth);

// The room's planes and dimensions (calib/room_planes.hpp).
using sweepmap::inlierCentroid;
using sweepmap::planeDistance;
using sweepmap::RoomDims;
using sweepmap::RoomPlanes;
using sweepmap::signedDistance;

// What the room's planes say of one world-frame cloud: the planes, L1-L3, the deviations
// of the ceiling and wall points (Fig. 9) and the ceiling's upward normal.
struct RoomMeasures {
  RoomPlanes planes;
  RoomDims dims;
  DeviationStats ceiling{1.0, 50.0}, walls{1.0, 50.0};
  std::optional<Eigen::Vector3d> ceiling_up;
};
RoomMeasures measureRoom(const std::vector<Eigen::Vector3f>& cloud);

// Where the drive comes back to a place it passed at least 30 s earlier (pose within 0.3 m
// and heading within 0.35 rad): the scans of both passes, and the distance between the
// planes each pass sees there. A double wall is the ghost of Miao 2022 Fig. 11.
struct LoopClosure {
  std::vector<int> early, late;  // scan indices
  struct Plane {
    WallPlaneFit early, late;
    double distance_m = 0;
  };
  std::vector<Plane> planes;
  std::vector<Eigen::Vector3f> early_points;  // the points the early planes index
  std::optional<double> ghost_m;              // the largest distance among vertical planes
  std::string reason;
};
LoopClosure loopClosure(const MobileLog& log, const PoseTrack& track,
                        const std::vector<Eigen::Vector3f>& cloud,
                        const std::vector<int>& scan_of_point);

// The points of `cloud` from the scans `scans` (ascending), in cloud order.
std::vector<Eigen::Vector3f> pointsOfScans(const std::vector<Eigen::Vector3f>& cloud,
                                           const std::vector<int>& scan_of_point,
                                           const std::vector<int>& scans, size_t scan_count);

// The distances between the two copies of each wall seen twice.
struct DoubleWalls {
  std::vector<double> wall_distance_m;  // per wall found in both copies
  std::optional<double> max_m;
  std::string reason;  // why there is no distance
};

// The double walls of a drive that sees each place with both halves of its scan (the
// calibration circle): every wall fitted in the left halves' cloud and in the right halves',
// and the distance between the two copies along the wall's normal. With the right mounting
// the two coincide.
struct HalfScanGhost {
  std::vector<Eigen::Vector3f> left, right;
  DoubleWalls walls;
};
HalfScanGhost halfScanGhost(const MobileLog& log, const PoseTrack& track,
                            const LidarMounting& mounting);

}  // namespace sweepmap::eval
