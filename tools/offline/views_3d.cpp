#include "tools/offline/views_3d.hpp"

#include <algorithm>
#include <iostream>

#include "mapping/plot.hpp"

namespace sweepmap {

void drawViews3d(const std::filesystem::path& out, const std::string& tool, const std::string& what,
                 const std::string& frame, const std::vector<Eigen::Vector3f>& cloud,
                 const std::vector<Eigen::Vector3f>& map_voxels, double voxel_m) {
  PerspectiveOptions o;
  const auto draw = [&](const std::string& file, const Layer& layer) {
    if (layer.points.empty()) return;
    try {
      plotPerspective((out / file).string(), {layer}, o);
    } catch (const std::exception& e) {
      std::cerr << tool << ": " << file << " not drawn: " << e.what() << "\n";
    }
  };
  o.title = what + ": the cloud in perspective (frame " + frame + "), shaded by height";
  draw("cloud_3d.png", Layer{"cloud", "", cloud, true});
  char res[32];
  std::snprintf(res, sizeof res, "%.0f mm", voxel_m * 1000.0);
  o.title = what + ": the map's occupied " + res + " voxels in perspective, shaded by height";
  o.point_size = 0.45;
  draw("map_3d.png", Layer{"occupied voxels", "", map_voxels, true});
}

ZBand wallBand(const std::vector<Eigen::Vector3f>& cloud, double margin_m) {
  ZBand band;
  if (cloud.size() < 100) return band;
  std::vector<float> z;
  const size_t stride = std::max<size_t>(1, cloud.size() / 100000);  // a sample is enough
  for (size_t i = 0; i < cloud.size(); i += stride) {
    if (cloud[i].allFinite()) z.push_back(cloud[i].z());
  }
  if (z.size() < 100) return band;
  const size_t lo = z.size() * 2 / 100, hi = z.size() * 98 / 100;
  std::nth_element(z.begin(), z.begin() + lo, z.end());
  const double floor_z = z[lo];
  std::nth_element(z.begin(), z.begin() + hi, z.end());
  const double ceiling_z = z[hi];
  band.min = floor_z + margin_m;
  band.max = ceiling_z - margin_m;
  band.valid = band.max - band.min > 0.2;
  return band;
}

}  // namespace sweepmap
