// A room's planes and dimensions: see calib/room_planes.hpp.
#include "calib/room_planes.hpp"

#include <algorithm>
#include <cmath>

namespace sweepmap {

Eigen::Vector3d inlierCentroid(const std::vector<Eigen::Vector3f>& cloud,
                               const std::vector<int>& idx) {
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (int i : idx) c += cloud[static_cast<size_t>(i)].cast<double>();
  return idx.empty() ? c : Eigen::Vector3d(c / static_cast<double>(idx.size()));
}

double signedDistance(const WallPlaneFit& p, const Eigen::Vector3d& x) {
  return p.normal.dot(x) + p.offset;
}

// Distance of two near-parallel planes: the mean of each one's distance from the other's
// inlier centroid (symmetric; exact for parallel planes).
double planeDistance(const WallPlaneFit& a, const std::vector<Eigen::Vector3f>& cloud_a,
                     const WallPlaneFit& b, const std::vector<Eigen::Vector3f>& cloud_b) {
  return 0.5 * (std::abs(signedDistance(a, inlierCentroid(cloud_b, b.inlier_indices))) +
                std::abs(signedDistance(b, inlierCentroid(cloud_a, a.inlier_indices))));
}

RoomPlanes findRoomPlanes(const std::vector<Eigen::Vector3f>& cloud,
                          const WallExtractionOptions& wo) {
  RoomPlanes r;
  const WallExtraction walls = extractWalls(cloud, wo);
  r.walls = walls.walls;
  if (r.walls.empty()) r.reason = "walls: " + walls.reason;
  PlaneExtractionOptions ho;
  ho.orientation = PlaneExtractionOptions::Orientation::kHorizontal;
  ho.max_planes = 4;
  const auto horizontal = extractPlanes(cloud, ho);
  // Height of a horizontal plane: z where it crosses the vertical through its centroid.
  const auto height = [&](const WallPlaneFit& p) {
    return inlierCentroid(cloud, p.inlier_indices).z();
  };
  for (const WallPlaneFit& p : horizontal) {
    if (!r.floor || height(p) < height(*r.floor)) r.floor = p;
    if (!r.ceiling || height(p) > height(*r.ceiling)) r.ceiling = p;
  }
  if (horizontal.size() < 2) {
    r.floor.reset();
    r.ceiling.reset();
    r.reason += (r.reason.empty() ? "" : "; ") + std::string("fewer than two horizontal planes");
  }
  return r;
}

RoomDims roomDims(const RoomPlanes& p, const std::vector<Eigen::Vector3f>& cloud) {
  RoomDims d;
  if (p.walls.size() == 4) {
    const double y = planeDistance(p.walls[0], cloud, p.walls[2], cloud);
    const double x = planeDistance(p.walls[1], cloud, p.walls[3], cloud);
    d.L1 = std::max(x, y);
    d.L2 = std::min(x, y);
  }
  if (p.floor && p.ceiling) d.L3 = planeDistance(*p.floor, cloud, *p.ceiling, cloud);
  return d;
}

}  // namespace sweepmap
