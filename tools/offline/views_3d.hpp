// The report's 3D pictures of a run (replay and eval): DIR/cloud_3d.png, the final cloud, and
// DIR/map_3d.png, the map's occupied voxels, each in perspective and shaded by height, the
// ceiling left out (it would hide the room seen from above; wallBand())
// (mapping/plot.hpp's plotPerspective, drawn off-screen by gnuplot, a fixed number of points).
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <string>
#include <vector>

namespace sweepmap {

// `what` names the run in the titles ("rig B replay"), `frame` the points' frame ("world");
// `room`: the points are a room's, whose ceiling is left out.
// A picture that cannot be drawn is reported on stderr ("<tool>: ... not drawn: why"), never
// thrown: pictures never cost a run its other outputs. An empty cloud or map is not drawn.
void drawViews3d(const std::filesystem::path& out, const std::string& tool, const std::string& what,
                 const std::string& frame, const std::vector<Eigen::Vector3f>& cloud,
                 const std::vector<Eigen::Vector3f>& map_voxels, double voxel_m, bool room);

struct ZBand;
// Each picture alone, for a report that lists its figures (tools/eval): throws when it cannot
// be drawn. Points above `band.max` (a valid band: the ceiling) are left out.
void drawCloud3d(const std::string& png, const std::string& what, const std::string& frame,
                 const std::vector<Eigen::Vector3f>& cloud, const ZBand& band);
void drawMap3d(const std::string& png, const std::string& what,
               const std::vector<Eigen::Vector3f>& map_voxels, double voxel_m, const ZBand& band);

// The z band of a building's walls: above the floor and below the ceiling (the 2nd and 98th
// percentiles of z, moved `margin_m` inwards), so a top view shows walls, not the floor and
// ceiling that cover them. Unset when the cloud is too flat for such a band.
struct ZBand {
  double min = 0.0, max = 0.0;
  bool valid = false;
};
ZBand wallBand(const std::vector<Eigen::Vector3f>& cloud, double margin_m = 0.25);

}  // namespace sweepmap
