#include <gtest/gtest.h>
#include <pcl/io/ply_io.h>
#include <pcl/point_types.h>

#include <cmath>
#include <cstring>
#include <fstream>

#include "mapping/cloud_io.hpp"
#include "mapping/las_io.hpp"
#include "mapping/synthetic_room.hpp"
#include "mapping_test_util.hpp"

namespace sweepmap {
namespace {

using testing_util::fileBytes;
using testing_util::filesIn;
using testing_util::freshTestDir;

std::vector<Eigen::Vector3f> samplePoints() {
  RoomSweepSpec spec;
  spec.scans = 40;
  spec.beams = 101;
  spec.range_noise_sigma_m = 0.012;
  auto points = syntheticRoomSweep(spec);
  points.push_back({-1.5e-7f, 123456.78f, -0.0f});  // awkward floats survive bit-exactly
  return points;
}

TEST(CloudIo, PcdRoundTripIsExactAndBytesRepeat) {
  const auto dir = freshTestDir();
  const auto points = samplePoints();
  writePcdBinary((dir / "a.pcd").string(), points);
  writePcdBinary((dir / "b.pcd").string(), points);
  EXPECT_EQ(fileBytes(dir / "a.pcd"), fileBytes(dir / "b.pcd"));
  EXPECT_EQ(filesIn(dir), (std::vector<std::string>{"a.pcd", "b.pcd"}));

  const auto back = readPcd((dir / "a.pcd").string());
  ASSERT_EQ(back.size(), points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    ASSERT_EQ(back[i], points[i]) << "point " << i;
  }
  const std::string head = fileBytes(dir / "a.pcd").substr(0, 300);
  EXPECT_NE(head.find("FIELDS x y z"), std::string::npos) << head;
  EXPECT_NE(head.find("DATA binary"), std::string::npos) << head;
}

TEST(CloudIo, PcdOverwriteAndEmptyCloud) {
  const auto dir = freshTestDir();
  const auto path = (dir / "c.pcd").string();
  writePcdBinary(path, samplePoints());
  writePcdBinary(path, {{1.0f, 2.0f, 3.0f}});
  EXPECT_EQ(readPcd(path), (std::vector<Eigen::Vector3f>{{1.0f, 2.0f, 3.0f}}));
  writePcdBinary(path, {});
  EXPECT_TRUE(readPcd(path).empty());
  EXPECT_EQ(filesIn(dir), std::vector<std::string>{"c.pcd"});
}

TEST(CloudIo, PlyHasAHeaderAndBytesRepeat) {
  const auto dir = freshTestDir();
  const auto points = samplePoints();
  writePlyBinary((dir / "a.ply").string(), points);
  writePlyBinary((dir / "b.ply").string(), points);
  const std::string bytes = fileBytes(dir / "a.ply");
  EXPECT_EQ(bytes, fileBytes(dir / "b.ply"));
  EXPECT_EQ(filesIn(dir), (std::vector<std::string>{"a.ply", "b.ply"}));

  const auto end = bytes.find("end_header\n");
  ASSERT_NE(end, std::string::npos);
  const std::string header = bytes.substr(0, end);
  EXPECT_EQ(header.rfind("ply\nformat binary_little_endian 1.0\n", 0), 0u) << header;
  EXPECT_NE(header.find("element vertex " + std::to_string(points.size()) + "\n"),
            std::string::npos)
      << header;
  EXPECT_NE(header.find("property float x\nproperty float y\nproperty float z\n"),
            std::string::npos)
      << header;
  // One element, the vertices (no camera element, which CloudCompare would ask about): 3
  // float32 per point, little-endian, right after the header and nothing after them.
  EXPECT_EQ(header.find("camera"), std::string::npos) << header;
  size_t elements = 0;
  for (size_t at = 0; (at = header.find("element ", at)) != std::string::npos; ++at) ++elements;
  EXPECT_EQ(elements, 1u) << header;
  ASSERT_EQ(bytes.size() - (end + 11), points.size() * 12);
  for (size_t i = 0; i < points.size(); ++i) {
    float xyz[3];
    std::memcpy(xyz, bytes.data() + end + 11 + 12 * i, 12);
    EXPECT_EQ(Eigen::Vector3f(xyz[0], xyz[1], xyz[2]), points[i]) << i;
  }
}

// pcl_viewer reads PLY through pcl::io::loadPLYFile: it must get the same points back.
TEST(CloudIo, PclsPlyReaderReadsOurPlyBack) {
  const auto dir = freshTestDir();
  const auto points = samplePoints();
  writePlyBinary((dir / "a.ply").string(), points);
  pcl::PointCloud<pcl::PointXYZ> cloud;
  ASSERT_EQ(pcl::io::loadPLYFile((dir / "a.ply").string(), cloud), 0);
  ASSERT_EQ(cloud.size(), points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    ASSERT_EQ(Eigen::Vector3f(cloud[i].x, cloud[i].y, cloud[i].z), points[i]) << i;
  }
}

// With intensities the PLY gains a float `intensity` property after z: PCL's reader (pcl_viewer)
// gets the points and intensities back, sweepmap's LAS input reader too (rounded to LAS's
// uint16, mapping/las_io.hpp), and a wrong count is refused.
TEST(CloudIo, PlyCarriesIntensityThatPclAndTheLasReaderRead) {
  const auto dir = freshTestDir();
  const auto points = samplePoints();
  std::vector<float> intensity;
  for (size_t i = 0; i < points.size(); ++i) intensity.push_back(0.75f * float(i % 4000));
  const auto path = (dir / "i.ply").string();
  writePlyBinary(path, points, intensity);
  const std::string bytes = fileBytes(dir / "i.ply");
  EXPECT_NE(bytes.find("property float z\nproperty float intensity\nend_header\n"),
            std::string::npos);
  pcl::PointCloud<pcl::PointXYZI> cloud;
  ASSERT_EQ(pcl::io::loadPLYFile(path, cloud), 0);
  ASSERT_EQ(cloud.size(), points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    ASSERT_EQ(Eigen::Vector3f(cloud[i].x, cloud[i].y, cloud[i].z), points[i]) << i;
    ASSERT_EQ(cloud[i].intensity, intensity[i]) << i;
  }
  const auto las = readPlyVertices(path);
  ASSERT_EQ(las.size(), points.size());
  EXPECT_EQ(las[3].intensity, 2);  // 2.25
  EXPECT_EQ(las[2].intensity, 2);  // 1.5: halves away from zero
  EXPECT_EQ(las[5].intensity, 4);  // 3.75
  EXPECT_EQ(lasIntensity(70000.0), 65535);
  EXPECT_EQ(lasIntensity(-3.0), 0);
  EXPECT_EQ(lasIntensity(std::nan("")), 0);
  intensity.pop_back();
  EXPECT_THROW(writePlyBinary(path, points, intensity), std::runtime_error);
}

TEST(CloudIo, PcdAndPlyWrittenTogether) {
  const auto dir = freshTestDir();
  writePcdAndPly((dir / "cloud").string(), samplePoints());
  EXPECT_EQ(filesIn(dir), (std::vector<std::string>{"cloud.pcd", "cloud.ply"}));
  EXPECT_EQ(readPlyVertices((dir / "cloud.ply").string()).size(), samplePoints().size());
}

TEST(LasIo, HeaderFieldsOfLas14Format6) {
  const auto dir = freshTestDir();
  const std::vector<LasPoint> points = {{1.0, -2.0, 0.5, 100.25, 7}, {3.0, 4.0, -1.5, 101.5, 9}};
  const LasSummary s = writeLas14((dir / "a.las").string(), points);
  const std::string b = fileBytes(dir / "a.las");
  ASSERT_EQ(b.size(), 375u + 2 * 30u);
  EXPECT_EQ(s.bytes, b.size());
  auto at = [&](size_t off, auto v) {
    std::memcpy(&v, b.data() + off, sizeof v);
    return v;
  };
  EXPECT_EQ(b.substr(0, 4), "LASF");
  EXPECT_EQ(b[24], 1);
  EXPECT_EQ(b[25], 4);
  EXPECT_EQ(at(94, uint16_t{}), 375);
  EXPECT_EQ(at(96, uint32_t{}), 375u);
  EXPECT_EQ(b[104], 6);
  EXPECT_EQ(at(105, uint16_t{}), 30);
  EXPECT_EQ(at(107, uint32_t{}), 0u);  // legacy count: 0 for format 6
  EXPECT_EQ(at(247, uint64_t{}), 2u);
  EXPECT_EQ(at(255, uint64_t{}), 2u);  // return 1
  EXPECT_EQ(at(179, double{}), 3.0);   // max x
  EXPECT_EQ(at(187, double{}), 1.0);   // min x
  EXPECT_EQ(at(219, double{}), -1.5);  // min z
  const double scale = at(131, double{}), offset_x = at(155, double{});
  EXPECT_NEAR(at(375 + 30, int32_t{}) * scale + offset_x, 3.0, scale / 2);
  EXPECT_EQ(at(375 + 12, uint16_t{}), 7);
  EXPECT_EQ(b[375 + 14], 0x11);  // return 1 of 1
  EXPECT_EQ(at(375 + 30 + 22, double{}), 101.5);
  EXPECT_THROW(writeLas14((dir / "b.las").string(), {{NAN, 0, 0, 0, 0}}), std::runtime_error);
}

TEST(LasIo, PlyReaderRefusesWhatItCannotRead) {
  const auto dir = freshTestDir();
  const std::string ascii = (dir / "ascii.ply").string();
  {
    std::ofstream out(ascii);
    out << "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
           "property float z\nend_header\n1 2 3\n";
  }
  EXPECT_THROW(readPlyVertices(ascii), std::runtime_error);
  const std::string cut = (dir / "cut.ply").string();
  {
    std::ofstream out(cut, std::ios::binary);
    out << "ply\nformat binary_little_endian 1.0\nelement vertex 1000000000\nproperty float x\n"
           "property float y\nproperty float z\nend_header\n";
  }
  EXPECT_THROW(readPlyVertices(cut), std::runtime_error);
}

TEST(CloudIo, FailuresNameThePath) {
  const auto dir = freshTestDir();
  const std::string missing = (dir / "missing.pcd").string();
  try {
    readPcd(missing);
    FAIL() << "reading a missing file must throw";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(missing), std::string::npos) << e.what();
  }
  const std::string bad = (dir / "nope" / "x.ply").string();
  try {
    writePlyBinary(bad, {{1.0f, 2.0f, 3.0f}});
    FAIL() << "writing into a missing folder must throw";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(bad), std::string::npos) << e.what();
  }
  EXPECT_THROW(writePcdBinary((dir / "nope" / "x.pcd").string(), {{1.0f, 2.0f, 3.0f}}),
               std::runtime_error);

  // A valid PCD file without coordinates.
  const auto no_xyz = dir / "intensity.pcd";
  std::ofstream(no_xyz) << "VERSION 0.7\nFIELDS intensity\nSIZE 4\nTYPE F\nCOUNT 1\n"
                           "WIDTH 2\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\nDATA ascii\n"
                           "1.0\n2.0\n";
  try {
    readPcd(no_xyz.string());
    FAIL() << "a PCD file without x must be refused";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("no field 'x'"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace sweepmap
