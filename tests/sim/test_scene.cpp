#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <fstream>
#include <iostream>
#include <random>
#include <sstream>

#include "hand_scene.hpp"
#include "sim/scene.hpp"

namespace sweepmap {
namespace {

const std::string kSceneFile =
    std::string(SWEEPMAP_SOURCE_DIR) + "/config/scene_conference_room.yaml";

class SceneTest : public ::testing::Test {
 protected:
  SceneTest() : scene_(testing_scene::handScene(), PlateConfig()) {}

  double range(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
               double max_range_m = 20.0) const {
    const auto hit = scene_.raycast(origin, dir.normalized(), max_range_m);
    EXPECT_TRUE(hit.has_value()) << "no hit from " << origin.transpose() << " along "
                                 << dir.transpose();
    return hit.value_or(-1.0);
  }

  Scene scene_;
};

TEST_F(SceneTest, FloorCeilingAndWalls) {
  const Eigen::Vector3d p(0.0, 0.0, 1.5);
  EXPECT_DOUBLE_EQ(range(p, -Eigen::Vector3d::UnitZ()), 1.5);
  EXPECT_DOUBLE_EQ(range(p, Eigen::Vector3d::UnitZ()), 1.5);
  EXPECT_DOUBLE_EQ(range(p, Eigen::Vector3d::UnitX()), 4.0);
  EXPECT_DOUBLE_EQ(range(p, -Eigen::Vector3d::UnitX()), 4.0);
  EXPECT_DOUBLE_EQ(range(p, Eigen::Vector3d::UnitY()), 3.0);
  EXPECT_DOUBLE_EQ(range(p, -Eigen::Vector3d::UnitY()), 3.0);
  // Oblique: reaches y = 3 at x = 1.5.
  EXPECT_NEAR(range(p, Eigen::Vector3d(1, 2, 0)), 1.5 * std::sqrt(5.0), 1e-12);
}

TEST_F(SceneTest, MaxRangeLimitsHits) {
  const Eigen::Vector3d p(0.0, 0.0, 1.5);
  EXPECT_FALSE(scene_.raycast(p, Eigen::Vector3d::UnitX(), 3.9).has_value());
  EXPECT_TRUE(scene_.raycast(p, Eigen::Vector3d::UnitX(), 4.0).has_value());
}

TEST_F(SceneTest, DoorRecess) {
  EXPECT_DOUBLE_EQ(range({2.5, 0.0, 1.0}, Eigen::Vector3d::UnitY()), 3.3);  // door leaf
  EXPECT_DOUBLE_EQ(range({2.5, 0.0, 2.5}, Eigen::Vector3d::UnitY()), 3.0);  // above the door
  EXPECT_DOUBLE_EQ(range({1.5, 0.0, 1.0}, Eigen::Vector3d::UnitY()), 3.0);  // beside it
  const Eigen::Vector3d in_recess(2.5, 3.15, 1.0);
  EXPECT_NEAR(range(in_recess, Eigen::Vector3d::UnitX()), 0.5, 1e-12);   // jamb
  EXPECT_NEAR(range(in_recess, -Eigen::Vector3d::UnitX()), 0.5, 1e-12);  // jamb
  EXPECT_NEAR(range(in_recess, Eigen::Vector3d::UnitZ()), 1.1, 1e-12);   // lintel
  EXPECT_NEAR(range(in_recess, -Eigen::Vector3d::UnitZ()), 1.0, 1e-12);  // floor
  EXPECT_NEAR(range(in_recess, Eigen::Vector3d::UnitY()), 0.15, 1e-12);  // leaf
}

TEST_F(SceneTest, TableCabinetAndStand) {
  EXPECT_NEAR(range({-1.3, -0.2, 2.0}, -Eigen::Vector3d::UnitZ()), 1.26, 1e-12);  // top
  EXPECT_NEAR(range({-1.3, -0.2, 0.5}, Eigen::Vector3d::UnitZ()), 0.2, 1e-12);    // underside
  EXPECT_NEAR(range({-3.5, -0.77, 0.3}, Eigen::Vector3d::UnitX()), 1.0, 1e-12);   // a leg
  EXPECT_NEAR(range({-3.5, -0.5, 0.3}, Eigen::Vector3d::UnitX()), 7.5, 1e-12);    // between legs
  EXPECT_NEAR(range({2.4, -2.775, 2.0}, -Eigen::Vector3d::UnitZ()), 1.1, 1e-12);  // cabinet
  // The post ends 10 mm below the plate (plate at -45 mm in frame O, rig at 1.0 m).
  EXPECT_NEAR(range({1.2, 0.8, 1.0}, -Eigen::Vector3d::UnitZ()), 0.055, 1e-12);
  EXPECT_NEAR(range({0.0, 0.8, 0.5}, Eigen::Vector3d::UnitX()), 1.17, 1e-12);
}

TEST_F(SceneTest, WallPlanesPointIntoTheRoom) {
  ASSERT_EQ(scene_.wallPlanes().size(), 4u);
  const Eigen::Vector3d p(0.5, 0.5, 2.5);  // above all furniture, away from the door
  for (const WallPlane& w : scene_.wallPlanes()) {
    EXPECT_NEAR(w.normal.norm(), 1.0, 1e-15) << w.name;
    const double distance = w.normal.dot(p) + w.offset;
    EXPECT_GT(distance, 0.0) << w.name;
    EXPECT_NEAR(range(p, -w.normal), distance, 1e-12) << w.name;
  }
}

TEST(Scene, RigPose) {
  SceneConfig c = testing_scene::handScene();
  c.rig_yaw_deg = 30.0;
  const Scene scene(c, PlateConfig());
  const Eigen::Isometry3d T = scene.T_room_rig();
  EXPECT_TRUE(T.translation().isApprox(Eigen::Vector3d(1.2, 0.8, 1.0)));
  EXPECT_TRUE((T.linear() * Eigen::Vector3d::UnitX())
                  .isApprox(Eigen::Vector3d(std::sqrt(3.0) / 2, 0.5, 0.0)));
  EXPECT_TRUE((T.linear() * Eigen::Vector3d::UnitZ()).isApprox(Eigen::Vector3d::UnitZ()));
}

TEST(Scene, RejectsAStandWithNoHeight) {
  SceneConfig c = testing_scene::handScene();
  c.rig_z_m = 0.05;  // plate at 5 mm above the floor
  EXPECT_THROW(Scene(c, PlateConfig()), ConfigError);
}

// Every ray from inside the closed room hits something; prints the ray caster's speed (a
// figure, not asserted: `make bench` measures speed).
TEST_F(SceneTest, ClosedRoomEveryRayHits) {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> n(0.0, 1.0);
  const Eigen::Vector3d origin = scene_.T_room_rig().translation();
  constexpr int kRays = 200'000;
  std::vector<Eigen::Vector3d> dirs(kRays);
  for (auto& d : dirs) d = Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized();
  int hits = 0;
  double sum_m = 0.0;
  const auto start = std::chrono::steady_clock::now();
  for (const auto& d : dirs) {
    if (const auto r = scene_.raycast(origin, d, 20.0)) {
      ++hits;
      sum_m += *r;
    }
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const double rays_per_s = kRays / seconds;
  std::cout << "[ raycast  ] " << scene_.boxes().size() << " boxes: " << rays_per_s / 1e6
            << " M rays/s (mean range " << sum_m / hits << " m)\n";
  EXPECT_EQ(hits, kRays);
}

class SceneFileTest : public ::testing::Test {
 protected:
  static std::string shippedText() {
    std::ifstream in(kSceneFile);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
  }
  static std::string writeTemp(const std::string& name, const std::string& text) {
    const std::string path = ::testing::TempDir() + name;
    std::ofstream(path) << text;
    return path;
  }
  static std::string loadError(const std::string& path,
                               const std::vector<std::string>& overrides = {}) {
    try {
      loadScene(path, overrides);
    } catch (const ConfigError& e) {
      return e.what();
    }
    return "";
  }
};

TEST_F(SceneFileTest, ShippedFileLoads) {
  const SceneConfig c = loadScene(kSceneFile);
  EXPECT_EQ(c.name, "conference_room");
  EXPECT_DOUBLE_EQ(c.room_length_m, 8.0);
  EXPECT_DOUBLE_EQ(c.rig_z_m, 1.0);
  const Scene scene(c, PlateConfig());
  EXPECT_EQ(scene.wallPlanes().size(), 4u);
  const SceneConfig moved = loadScene(kSceneFile, {"rig.yaw_deg=45"});
  EXPECT_DOUBLE_EQ(moved.rig_yaw_deg, 45.0);
}

TEST_F(SceneFileTest, RejectsMissingKeyNamingIt) {
  std::string text = shippedText();
  const std::string line = "  depth_m: 0.3\n";
  ASSERT_NE(text.find(line), std::string::npos);
  text.erase(text.find(line), line.size());
  const std::string error = loadError(writeTemp("scene_missing.yaml", text));
  EXPECT_NE(error.find("door.depth_m"), std::string::npos) << error;
  EXPECT_NE(error.find("scene_missing.yaml"), std::string::npos) << error;
}

TEST_F(SceneFileTest, RejectsUnknownKeyNamingIt) {
  std::string text = shippedText();
  const std::string anchor = "table:\n";
  ASSERT_NE(text.find(anchor), std::string::npos);
  text.insert(text.find(anchor) + anchor.size(), "  colour_m: 1\n");
  const std::string error = loadError(writeTemp("scene_unknown.yaml", text));
  EXPECT_NE(error.find("table.colour_m"), std::string::npos) << error;
}

TEST_F(SceneFileTest, RejectsImpossibleScenesNamingTheKey) {
  EXPECT_NE(loadError(kSceneFile, {"door.center_x_m=3.8"}).find("door.center_x_m"),
            std::string::npos);
  EXPECT_NE(loadError(kSceneFile, {"rig.x_m=-1.3", "rig.y_m=-0.2"}).find("rig.x_m"),
            std::string::npos);  // stand inside the table
  EXPECT_NE(loadError(kSceneFile, {"rig.z_m=3.5"}).find("rig.z_m"), std::string::npos);
  EXPECT_NE(loadError(kSceneFile, {"room.width_m=0"}).find("room.width_m"), std::string::npos);
}

// The lab's calibration target (config/scene_lab.yaml): a board 0.1 m in front of a window
// recessed 0.3 m into the -X wall.
TEST(SceneTarget, RaycastHitsTheBoardTheRecessAndTheWallAtAnalyticDistances) {
  const SceneConfig c = loadScene(std::string(SWEEPMAP_SOURCE_DIR) + "/config/scene_lab.yaml");
  ASSERT_TRUE(c.target_enabled);
  ASSERT_EQ(c.target_wall, "x_min");
  const Scene scene(c, PlateConfig());
  const double wall_x = -c.room_length_m / 2;
  const double window_mid_z = c.target_window_sill_m + c.target_window_height_m / 2;
  const Eigen::Vector3d toward(-1.0, 0.0, 0.0);
  const double x0 = -3.0;
  // Board: its front face is board_offset_m in front of the wall plane.
  const Eigen::Vector3d at_board(x0, c.target_position_m, window_mid_z);
  EXPECT_NEAR(*scene.raycast(at_board, toward, 20.0), x0 - wall_x - c.target_board_offset_m, 1e-12);
  // Inside the window, beside the board: the recess's back.
  const Eigen::Vector3d beside(
      x0, c.target_position_m + (c.target_board_width_m + c.target_window_width_m) / 4,
      window_mid_z);
  EXPECT_NEAR(*scene.raycast(beside, toward, 20.0), x0 - wall_x + c.target_window_depth_m, 1e-12);
  // Above the window: the wall.
  const Eigen::Vector3d above(x0, c.target_position_m,
                              c.target_window_sill_m + c.target_window_height_m + 0.1);
  EXPECT_NEAR(*scene.raycast(above, toward, 20.0), x0 - wall_x, 1e-12);
  // Below the window: the wall.
  const Eigen::Vector3d below(x0, c.target_position_m, c.target_window_sill_m - 0.1);
  EXPECT_NEAR(*scene.raycast(below, toward, 20.0), x0 - wall_x, 1e-12);
  // Slanted: a ray to the board's centre from elsewhere hits it at the distance to its face.
  const Eigen::Vector3d from(-2.0, 1.0, 0.3);
  const Eigen::Vector3d face_centre(wall_x + c.target_board_offset_m, c.target_position_m,
                                    window_mid_z);
  EXPECT_NEAR(*scene.raycast(from, (face_centre - from).normalized(), 20.0),
              (face_centre - from).norm(), 1e-9);
  const auto board = scene.targetBoard();
  ASSERT_TRUE(board.has_value());
  EXPECT_NEAR(board->max().x(), wall_x + c.target_board_offset_m, 1e-12);
  EXPECT_NEAR(board->sizes().y(), c.target_board_width_m, 1e-12);
  // Without the target the wall is whole.
  SceneConfig off = c;
  off.target_enabled = false;
  const Scene plain(off, PlateConfig());
  EXPECT_FALSE(plain.targetBoard().has_value());
  EXPECT_NEAR(*plain.raycast(at_board, toward, 20.0), x0 - wall_x, 1e-12);
}

TEST_F(SceneFileTest, RejectsABadTargetNamingTheKey) {
  const std::string lab = std::string(SWEEPMAP_SOURCE_DIR) + "/config/scene_lab.yaml";
  EXPECT_NE(loadError(lab, {"target.wall=y_max"}).find("target.wall"), std::string::npos);
  EXPECT_NE(loadError(lab, {"target.board_width_m=2"}).find("target.board_width_m"),
            std::string::npos);
  EXPECT_NE(loadError(lab, {"target.position_m=2.4"}).find("target.position_m"), std::string::npos);
  EXPECT_NE(loadError(lab, {"target.board_offset_m=-0.5"}).find("target.board_offset_m"),
            std::string::npos);
  EXPECT_NE(loadError(lab, {"target.window_height_m=2"}).find("target.window_height_m"),
            std::string::npos);
  const std::string error = loadError(lab, {"target.window_depth_m=0"});
  EXPECT_NE(error.find("target.window_depth_m"), std::string::npos) << error;
  EXPECT_NE(error.find("scene_lab.yaml"), std::string::npos) << error;
  // Disabled: the values are not checked (rig A's room carries them unused).
  EXPECT_EQ(loadError(kSceneFile, {"target.wall=y_max"}), "");
}

}  // namespace
}  // namespace sweepmap
