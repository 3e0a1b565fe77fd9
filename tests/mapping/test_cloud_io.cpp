#include <gtest/gtest.h>

#include <cstring>

#include "mapping/cloud_io.hpp"
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
