// The point-cloud density D of Miao 2022 Eq. 18-19: the mean, over every point, of the
// distance to its nearest other point (smaller: denser). PCL stays in the .cpp.
#pragma once

#include <Eigen/Core>
#include <vector>

namespace sweepmap {

// 0 for fewer than two points. Exact (k-d tree, PCL's KdTreeFLANN).
double meanNearestNeighbourDistance(const std::vector<Eigen::Vector3f>& cloud);

}  // namespace sweepmap
