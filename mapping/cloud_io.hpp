// Point cloud files (XYZ, float32, metres, in whatever frame the caller's points are in).
//
// PCD (binary) is PCL's native format; PLY (binary little-endian, one vertex element, no
// camera element) opens in CloudCompare without an import dialog, and in MeshLab. Both writers are
// atomic (`path + ".tmp"`, then rename) and byte- deterministic: the same points give the same
// bytes (no timestamps in either header). PCL is kept out of this header.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

namespace sweepmap {

// Throw std::runtime_error naming `path` on failure. Non-finite points are written as
// they are.
void writePcdBinary(const std::string& path, const std::vector<Eigen::Vector3f>& points);
// `intensities`: empty (x, y, z only), or one per point: the PLY gets a float `intensity`
// property after z (the lidar's device units); any other count throws.
void writePlyBinary(const std::string& path, const std::vector<Eigen::Vector3f>& points,
                    const std::vector<float>& intensities = {});

// Both files of a cloud: `stem + ".pcd"` (PCL's tools; x, y, z) and `stem + ".ply"`
// (CloudCompare, MeshLab, and every reader without PCD support, such as Debian 12's
// CloudCompare; with `intensities` as writePlyBinary).
void writePcdAndPly(const std::string& stem, const std::vector<Eigen::Vector3f>& points,
                    const std::vector<float>& intensities = {});

// Reads the x, y, z fields of any PCD file (ASCII, binary or compressed). Throws
// std::runtime_error naming `path` on failure.
std::vector<Eigen::Vector3f> readPcd(const std::string& path);

}  // namespace sweepmap
