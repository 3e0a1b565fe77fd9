#include "mapping/cloud_io.hpp"

#include <pcl/PCLPointCloud2.h>
#include <pcl/common/io.h>
#include <pcl/conversions.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <cstdio>
#include <cstring>
#include <stdexcept>

#include "core/atomic_file.hpp"

namespace sweepmap {
namespace {

pcl::PointCloud<pcl::PointXYZ> toPcl(const std::vector<Eigen::Vector3f>& points) {
  pcl::PointCloud<pcl::PointXYZ> cloud;
  cloud.resize(points.size());  // width = size, height = 1 (unorganised)
  bool dense = true;
  for (size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3f& p = points[i];
    cloud[i] = pcl::PointXYZ(p.x(), p.y(), p.z());
    dense = dense && p.allFinite();
  }
  cloud.is_dense = dense;
  // sensor_origin_ / sensor_orientation_ stay zero / identity: the header's VIEWPOINT.
  return cloud;
}

// Runs `write(tmp)` (a PCL writer returning 0 on success, or throwing), then commits.
template <typename Write>
void saveAtomic(const std::string& path, const char* format, Write&& write) {
  const std::string tmp = tmpPathFor(path);
  int rc = -1;
  std::string why;
  try {
    rc = write(tmp);
  } catch (const std::exception& e) {
    why = e.what();
  }
  if (rc != 0) {
    std::remove(tmp.c_str());
    throw std::runtime_error("cannot save " + path + " (" + format + ")" +
                             (why.empty() ? std::string() : ": " + why));
  }
  commitTmpFile(tmp, path);
}

}  // namespace

void writePcdBinary(const std::string& path, const std::vector<Eigen::Vector3f>& points) {
  const auto cloud = toPcl(points);
  saveAtomic(path, "PCD", [&](const std::string& tmp) {
    pcl::PCDWriter writer;
    return writer.writeBinary(tmp, cloud);
  });
}

// Written here: PCL's PLY writer adds a `camera` element (or, without it, a range grid and a
// header full of obj_info lines) that CloudCompare asks about on import. This is the plain
// form every tool reads: one vertex element of three float32 (and a float32 intensity when
// given: CloudCompare makes it a scalar field), little-endian.
void writePlyBinary(const std::string& path, const std::vector<Eigen::Vector3f>& points,
                    const std::vector<float>& intensities) {
  const bool with_intensity = !intensities.empty();
  if (with_intensity && intensities.size() != points.size()) {
    throw std::runtime_error("cannot save " + path +
                             " (PLY): " + std::to_string(intensities.size()) + " intensities for " +
                             std::to_string(points.size()) + " points");
  }
  const size_t stride = with_intensity ? 16 : 12;
  std::string bytes = "ply\nformat binary_little_endian 1.0\ncomment sweepmap\nelement vertex " +
                      std::to_string(points.size()) +
                      "\nproperty float x\nproperty float y\nproperty float z\n" +
                      (with_intensity ? "property float intensity\n" : "") + "end_header\n";
  const size_t header = bytes.size();
  bytes.resize(header + points.size() * stride);
  static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "PLY body written as in memory");
  for (size_t i = 0; i < points.size(); ++i) {
    std::memcpy(&bytes[header + stride * i], points[i].data(), 12);
    if (with_intensity) std::memcpy(&bytes[header + stride * i + 12], &intensities[i], 4);
  }
  writeFileAtomic(path, bytes);
}

void writePcdAndPly(const std::string& stem, const std::vector<Eigen::Vector3f>& points,
                    const std::vector<float>& intensities) {
  writePcdBinary(stem + ".pcd", points);
  writePlyBinary(stem + ".ply", points, intensities);
}

std::vector<Eigen::Vector3f> readPcd(const std::string& path) {
  // Through the untyped blob first: to check the fields (PCL would fill missing ones with
  // zeros and only warn), and because PCL's conversion of an empty blob indexes an empty
  // vector.
  pcl::PCLPointCloud2 blob;
  int rc = -1;
  std::string why;
  try {
    rc = pcl::io::loadPCDFile(path, blob);
  } catch (const std::exception& e) {
    why = e.what();
  }
  if (rc != 0) {
    throw std::runtime_error("cannot read PCD file " + path +
                             (why.empty() ? std::string() : ": " + why));
  }
  for (const char* name : {"x", "y", "z"}) {
    if (pcl::getFieldIndex(blob, name) < 0) {
      throw std::runtime_error("PCD file " + path + " has no field '" + name + "'");
    }
  }
  std::vector<Eigen::Vector3f> points;
  if (static_cast<size_t>(blob.width) * blob.height == 0) return points;
  pcl::PointCloud<pcl::PointXYZ> cloud;
  pcl::fromPCLPointCloud2(blob, cloud);
  points.reserve(cloud.size());
  for (const pcl::PointXYZ& p : cloud) points.emplace_back(p.x, p.y, p.z);
  return points;
}

}  // namespace sweepmap
