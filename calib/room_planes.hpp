// A room's planes and dimensions in a world-frame cloud (Miao 2022 section 5): the four walls
// (calib/walls.hpp's RANSAC extraction, one thread), the floor and the ceiling, and the
// wall-to-wall distances. Used by rig B's evaluation (tools/eval) and by calib rig, which
// compares them with the scene's.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "calib/walls.hpp"

namespace sweepmap {

// The centroid of the points `idx` of `cloud` (zero without any).
Eigen::Vector3d inlierCentroid(const std::vector<Eigen::Vector3f>& cloud,
                               const std::vector<int>& idx);

double signedDistance(const WallPlaneFit& p, const Eigen::Vector3d& x);

// Distance of two near-parallel planes: the mean of each one's distance from the other's
// inlier centroid (symmetric; exact for parallel planes).
double planeDistance(const WallPlaneFit& a, const std::vector<Eigen::Vector3f>& cloud_a,
                     const WallPlaneFit& b, const std::vector<Eigen::Vector3f>& cloud_b);

// The room's planes found by RANSAC in a world-frame cloud.
struct RoomPlanes {
  std::vector<WallPlaneFit> walls;  // extractWalls' order: normals ~ +Y, +X, -Y, -X
  std::optional<WallPlaneFit> floor, ceiling;
  std::string reason;  // what is missing
};
RoomPlanes findRoomPlanes(const std::vector<Eigen::Vector3f>& cloud,
                          const WallExtractionOptions& walls = WallExtractionOptions{});

struct RoomDims {
  std::optional<double> L1, L2, L3;  // length, width (the longer and shorter wall spacing), height
};
RoomDims roomDims(const RoomPlanes& planes, const std::vector<Eigen::Vector3f>& cloud);

}  // namespace sweepmap
