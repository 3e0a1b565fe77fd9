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

// The room's length, width and height from its planes refined against the lidar's range noise
// (calib/room_planes.hpp refinedRoomDims, as calib rig measures them): each point's window and
// weight from its own sigma (range_sigma_fraction x its lidar origin's distance from the
// plane), not RANSAC's fixed window, which keeps part of a far wall's or the ceiling's start
// error. `cloud` is assembleWorld's with `scan_of_point`; points of a scan without a pose at
// its middle ray are left out.
RoomDims refinedRoomDims(const MobileLog& log, const PoseTrack& track,
                         const std::vector<Eigen::Vector3f>& cloud,
                         const std::vector<int>& scan_of_point, const LidarMounting& mounting,
                         const RoomPlanes& planes, double range_sigma_fraction);

// Where the drive comes back to a place it passed at least 30 s earlier (pose within 0.3 m
// and heading within 0.35 rad): the scans of both passes, and how far apart each pass puts
// the walls they both see there. A double wall is the ghost of Miao 2022 Fig. 11.
//
// The walls are the room's (`walls`: RoomMeasures' planes, found in the whole drive's cloud),
// each kept when both passes see it: 100 or more points of each pass within +-3 sigma of
// their range noise around that pass's copy (sigma = `range_sigma_fraction` x the distance of
// the point's lidar origin from the wall: the range noise along the wall's normal). Its
// ghost is the distance between the two copies, each the median offset of its pass's points
// along the wall's horizontal normal: the median, not a plane fitted per pass, so that a far
// wall's noise (+-45 mm at 4.5 m for 1 %) and RANSAC splitting it in two make no ghost, and
// neither do vertical slices of floor, ceiling or furniture that RANSAC takes for walls.
struct LoopClosure {
  std::vector<int> early, late;  // scan indices
  struct Plane {
    Eigen::Vector3d normal = Eigen::Vector3d::UnitX();  // horizontal, unit
    double offset_m = 0.0;  // normal . x + offset = 0: midway between the two passes' copies
    int early_points = 0;   // each pass's points in the band
    int late_points = 0;
    double range_m = 0.0;                              // from the early pass's mean lidar origin
    Eigen::Vector3d foot_m = Eigen::Vector3d::Zero();  // that origin's foot on the wall
    double distance_m = 0;                             // between the passes' medians
  };
  std::vector<Plane> planes;
  std::optional<double> ghost_m;  // the largest distance among the walls
  std::string reason;
};
LoopClosure loopClosure(const MobileLog& log, const PoseTrack& track,
                        const std::vector<Eigen::Vector3f>& cloud,
                        const std::vector<int>& scan_of_point, const LidarMounting& mounting,
                        const std::vector<WallPlaneFit>& walls, double range_sigma_fraction);

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
// calibration circle): the vertical planes of both halves' clouds, each half's copy of each
// measured as a pass's copy of a wall is for the loop's ghost (the median within +-3 sigma of
// the range noise, sigma = `range_sigma_fraction` x the point's lidar origin's distance from
// the wall), and the distance between the two copies along the wall's normal. With the right
// mounting the two coincide.
struct HalfScanGhost {
  std::vector<Eigen::Vector3f> left, right;
  DoubleWalls walls;
};
HalfScanGhost halfScanGhost(const MobileLog& log, const PoseTrack& track,
                            const LidarMounting& mounting, double range_sigma_fraction);

}  // namespace sweepmap::eval
