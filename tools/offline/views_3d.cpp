#include "tools/offline/views_3d.hpp"

#include <algorithm>
#include <cstdio>
#include <functional>
#include <iostream>

#include "mapping/plot.hpp"

namespace sweepmap {

namespace {

Layer belowCeiling(const std::string& title, const std::vector<Eigen::Vector3f>& points,
                   const ZBand& band) {
  Layer layer{title, "", {}, true};
  for (const auto& p : points) {
    if (!band.valid || p.z() <= band.max) layer.points.push_back(p);
  }
  return layer;
}

}  // namespace

void drawCloud3d(const std::string& png, const std::string& what, const std::string& frame,
                 const std::vector<Eigen::Vector3f>& cloud, const ZBand& band) {
  PerspectiveOptions o;
  o.title = what + ": the cloud in perspective (frame " + frame + "), shaded by height" +
            (band.valid ? ", ceiling left out" : "");
  plotPerspective(png, {belowCeiling("cloud", cloud, band)}, o);
}

void drawMap3d(const std::string& png, const std::string& what,
               const std::vector<Eigen::Vector3f>& map_voxels, double voxel_m, const ZBand& band) {
  PerspectiveOptions o;
  char res[32];
  std::snprintf(res, sizeof res, "%.0f mm", voxel_m * 1000.0);
  o.title = what + ": the map's occupied " + res + " voxels in perspective, shaded by height" +
            (band.valid ? ", ceiling left out" : "");
  o.point_size = 0.45;
  plotPerspective(png, {belowCeiling("occupied voxels", map_voxels, band)}, o);
}

void drawViews3d(const std::filesystem::path& out, const std::string& tool, const std::string& what,
                 const std::string& frame, const std::vector<Eigen::Vector3f>& cloud,
                 const std::vector<Eigen::Vector3f>& map_voxels, double voxel_m, bool room) {
  const auto draw = [&](const std::string& file, const std::vector<Eigen::Vector3f>& points,
                        const std::function<void(const std::string&)>& plot) {
    if (points.empty()) return;
    try {
      plot((out / file).string());
    } catch (const std::exception& e) {
      std::cerr << tool << ": " << file << " not drawn: " << e.what() << "\n";
    }
  };
  // Seen from above, a room's ceiling hides everything under it: leave it out.
  const ZBand band = room ? wallBand(cloud) : ZBand{};
  draw("cloud_3d.png", cloud,
       [&](const std::string& png) { drawCloud3d(png, what, frame, cloud, band); });
  draw("map_3d.png", map_voxels,
       [&](const std::string& png) { drawMap3d(png, what, map_voxels, voxel_m, band); });
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
