// The simulated room: a closed box room with a door recess, a table, a cabinet and the
// stand under the rig, all axis-aligned boxes, plus the rig's pose in it. Used by the
// simulated lidar to cast rays, and by evaluation as ground truth (wall planes, rig pose).
//
// Room frame: origin on the floor at the centre of the room, Z up, X along the room's
// length, Y along its width. Frame O (the rig frame of Yuan 2021): origin on the rotation
// axis at the height of the lidar centre, Z along the axis (up), X the rig's front.
#pragma once

#include <Eigen/Geometry>
#include <optional>
#include <string>
#include <vector>

#include "core/config.hpp"
#include "core/rig_components.hpp"

namespace sweepmap {

struct SceneConfig {
  std::string name = "conference_room";
  double room_length_m = 8.0;  // along X
  double room_width_m = 6.0;   // along Y
  double room_height_m = 3.0;
  // Door recess in the +Y wall (a closed door set back into the wall).
  double door_center_x_m = 2.5;
  double door_width_m = 1.0;
  double door_height_m = 2.1;
  double door_depth_m = 0.3;  // from the wall plane to the door leaf
  // Table: a top slab on four square legs flush with its corners.
  double table_center_x_m = -1.3;
  double table_center_y_m = -0.2;
  double table_length_m = 2.4;   // along X
  double table_width_m = 1.2;    // along Y
  double table_height_m = 0.74;  // top surface above the floor
  double table_top_thickness_m = 0.04;
  double table_leg_size_m = 0.06;
  // Cabinet: a box standing on the floor (against the -Y wall by default).
  double cabinet_center_x_m = 2.4;
  double cabinet_center_y_m = -2.775;
  double cabinet_length_m = 1.2;  // along X
  double cabinet_width_m = 0.45;  // along Y
  double cabinet_height_m = 0.9;
  // Rig pose: origin of frame O in the room, and the angle of O's X from the room's X.
  double rig_x_m = 1.2;
  double rig_y_m = 0.8;
  double rig_z_m = 1.0;
  double rig_yaw_deg = 0.0;
  // Calibration target (rig B, Miao 2022 section 4.2): a window recessed into a wall and a
  // thin board hung in front of it, centred on the window. Seen by a lidar, the board's
  // edges are range discontinuities against the recess behind it.
  bool target_enabled = false;
  std::string target_wall = "x_min";  // x_min, x_max or y_min (y_max holds the door)
  double target_position_m = 0.0;  // window centre along the wall (room Y for x walls, X for y_min)
  double target_window_width_m = 1.2;  // along the wall
  double target_window_height_m = 1.0;
  double target_window_sill_m = 0.6;   // floor to the window's bottom
  double target_window_depth_m = 0.3;  // wall plane to the back of the recess (the glass)
  double target_board_width_m = 0.6;   // along the wall
  double target_board_height_m = 0.5;
  double target_board_thickness_m = 0.02;
  double target_board_offset_m =
      0.1;  // wall plane to the board's front face, into the room (< 0: inside the recess)

  void declare(ConfigSchema& s, const std::string& prefix);
  // Throws ConfigError naming `source` and the offending key if the scene is not a closed
  // room with everything inside it and the rig's stand clear of the furniture.
  void validate(const std::string& source) const;
};

// Loads a scene file strictly, applies `key=value` overrides, validates.
SceneConfig loadScene(const std::string& path, const std::vector<std::string>& overrides = {});

// A wall's inner plane in the room frame: points p on it satisfy normal.dot(p) + offset = 0;
// the normal is a unit vector pointing into the room, so normal.dot(p) + offset is the
// distance of p in front of the wall.
struct WallPlane {
  std::string name;  // x_min, x_max, y_min, y_max
  Eigen::Vector3d normal;
  double offset;
};

struct SceneBox {
  std::string name;
  Eigen::AlignedBox3d box;  // room frame [m]
};

class Scene {
 public:
  // The stand's post reaches up to 10 mm below the plate (plate.height_mm, frame O).
  // Throws ConfigError if the configuration is invalid.
  Scene(const SceneConfig& config, const PlateConfig& plate);

  // Distance [m] along `unit_dir_room` from `origin_room` to the nearest surface within
  // (0, max_range_m]; nullopt if none. A box that contains the origin is not hit.
  std::optional<double> raycast(const Eigen::Vector3d& origin_room,
                                const Eigen::Vector3d& unit_dir_room, double max_range_m) const;
  // The same, and which box was hit (index into boxes()) through which face (the axis 0..2
  // of its normal), when there is a hit.
  struct Hit {
    size_t box = 0;
    int axis = 0;
  };
  std::optional<double> raycast(const Eigen::Vector3d& origin_room,
                                const Eigen::Vector3d& unit_dir_room, double max_range_m,
                                Hit* hit) const;

  // Pose of frame O in the room frame (truth).
  Eigen::Isometry3d T_room_rig() const { return T_room_rig_; }
  // The four walls' inner planes (truth); the +Y wall's plane ignores the door recess.
  const std::vector<WallPlane>& wallPlanes() const { return walls_; }
  const std::vector<SceneBox>& boxes() const { return boxes_; }
  // The target board (room frame) when target.enabled.
  std::optional<Eigen::AlignedBox3d> targetBoard() const;
  const SceneConfig& config() const { return config_; }

 private:
  SceneConfig config_;
  Eigen::Isometry3d T_room_rig_;
  std::vector<WallPlane> walls_;
  std::vector<SceneBox> boxes_;
  // The same boxes as plain numbers for the ray caster's inner loop (fast in debug builds).
  struct Slabs {
    double lo[3];
    double hi[3];
  };
  std::vector<Slabs> slabs_;
};

}  // namespace sweepmap
