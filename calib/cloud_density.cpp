#include "calib/cloud_density.hpp"

#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/point_types.h>

#include <cmath>

namespace sweepmap {

double meanNearestNeighbourDistance(const std::vector<Eigen::Vector3f>& cloud) {
  auto pc = pcl::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
  pc->reserve(cloud.size());
  for (const auto& p : cloud) {
    if (p.allFinite()) pc->push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
  }
  if (pc->size() < 2) return 0.0;
  pcl::KdTreeFLANN<pcl::PointXYZ> tree;
  tree.setInputCloud(pc);
  std::vector<int> idx(2);
  std::vector<float> d2(2);
  double sum = 0.0;
  for (size_t i = 0; i < pc->size(); ++i) {
    // The nearest hit is the point itself (or a duplicate at distance 0).
    if (tree.nearestKSearch((*pc)[i], 2, idx, d2) == 2)
      sum += std::sqrt(static_cast<double>(d2[1]));
  }
  return sum / static_cast<double>(pc->size());
}

}  // namespace sweepmap
