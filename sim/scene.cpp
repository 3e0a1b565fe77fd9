#include "sim/scene.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace sweepmap {
namespace {

constexpr double kWallThicknessM = 0.2;     // walls, floor and ceiling are solid slabs
constexpr double kPostSideM = 0.060;        // square post of the rig's stand
constexpr double kPostBelowPlateM = 0.010;  // gap between the post's top and the plate

Eigen::AlignedBox3d box(double x0, double x1, double y0, double y1, double z0, double z1) {
  return Eigen::AlignedBox3d(Eigen::Vector3d(x0, y0, z0), Eigen::Vector3d(x1, y1, z1));
}

// Footprints (XY rectangles) overlap with positive area.
bool footprintsOverlap(const Eigen::AlignedBox3d& a, const Eigen::AlignedBox3d& b) {
  return a.min().x() < b.max().x() && b.min().x() < a.max().x() && a.min().y() < b.max().y() &&
         b.min().y() < a.max().y();
}

}  // namespace

void SceneConfig::declare(ConfigSchema& s, const std::string& p) {
  s.add(p + "name", &name, "", "scene name");
  s.add(p + "room.length_m", &room_length_m, "m", "room extent along X");
  s.add(p + "room.width_m", &room_width_m, "m", "room extent along Y");
  s.add(p + "room.height_m", &room_height_m, "m", "floor to ceiling");
  s.add(p + "door.center_x_m", &door_center_x_m, "m", "door recess centre along the +Y wall");
  s.add(p + "door.width_m", &door_width_m, "m", "door recess width (along X)");
  s.add(p + "door.height_m", &door_height_m, "m", "door recess height");
  s.add(p + "door.depth_m", &door_depth_m, "m", "wall plane to door leaf");
  s.add(p + "table.center_x_m", &table_center_x_m, "m", "table centre X");
  s.add(p + "table.center_y_m", &table_center_y_m, "m", "table centre Y");
  s.add(p + "table.length_m", &table_length_m, "m", "table extent along X");
  s.add(p + "table.width_m", &table_width_m, "m", "table extent along Y");
  s.add(p + "table.height_m", &table_height_m, "m", "floor to the table's top surface");
  s.add(p + "table.top_thickness_m", &table_top_thickness_m, "m", "thickness of the top slab");
  s.add(p + "table.leg_size_m", &table_leg_size_m, "m", "side of the square legs");
  s.add(p + "cabinet.center_x_m", &cabinet_center_x_m, "m", "cabinet centre X");
  s.add(p + "cabinet.center_y_m", &cabinet_center_y_m, "m", "cabinet centre Y");
  s.add(p + "cabinet.length_m", &cabinet_length_m, "m", "cabinet extent along X");
  s.add(p + "cabinet.width_m", &cabinet_width_m, "m", "cabinet extent along Y");
  s.add(p + "cabinet.height_m", &cabinet_height_m, "m", "cabinet height");
  s.add(p + "rig.x_m", &rig_x_m, "m", "rotation axis X in the room");
  s.add(p + "rig.y_m", &rig_y_m, "m", "rotation axis Y in the room");
  s.add(p + "rig.z_m", &rig_z_m, "m", "height of the lidar centre (origin of frame O)");
  s.add(p + "rig.yaw_deg", &rig_yaw_deg, "deg", "frame O's X from the room's X, about Z");
  s.add(p + "target.enabled", &target_enabled, "",
        "calibration target: a board in front of a window");
  s.add(p + "target.wall", &target_wall, "", "wall of the window: x_min, x_max or y_min");
  s.add(p + "target.position_m", &target_position_m, "m",
        "window centre along the wall (room Y on x walls, room X on y_min)");
  s.add(p + "target.window_width_m", &target_window_width_m, "m", "window opening along the wall");
  s.add(p + "target.window_height_m", &target_window_height_m, "m", "window opening height");
  s.add(p + "target.window_sill_m", &target_window_sill_m, "m", "floor to the window's bottom");
  s.add(p + "target.window_depth_m", &target_window_depth_m, "m",
        "wall plane to the recess's back");
  s.add(p + "target.board_width_m", &target_board_width_m, "m", "board along the wall");
  s.add(p + "target.board_height_m", &target_board_height_m, "m",
        "board height (centred on the window)");
  s.add(p + "target.board_thickness_m", &target_board_thickness_m, "m", "board thickness");
  s.add(p + "target.board_offset_m", &target_board_offset_m, "m",
        "wall plane to the board's front face, into the room (negative: inside the recess)");
}

namespace {

// Throws ConfigError "SOURCE: key 'KEY' WHY" for the first check that fails.
class SceneChecks {
 public:
  explicit SceneChecks(const std::string& source) : source_(source) {}
  void require(bool ok, const std::string& key, const std::string& why) const {
    if (!ok) throw ConfigError(source_ + ": key '" + key + "' " + why);
  }
  void positive(double v, const std::string& key) const {
    require(v > 0.0, key, "must be positive");
  }

 private:
  const std::string& source_;
};

void checkSizes(const SceneConfig& c, const SceneChecks& check) {
  check.positive(c.room_length_m, "room.length_m");
  check.positive(c.room_width_m, "room.width_m");
  check.positive(c.room_height_m, "room.height_m");
  check.positive(c.door_width_m, "door.width_m");
  check.positive(c.door_height_m, "door.height_m");
  check.positive(c.door_depth_m, "door.depth_m");
  check.positive(c.table_length_m, "table.length_m");
  check.positive(c.table_width_m, "table.width_m");
  check.positive(c.table_height_m, "table.height_m");
  check.positive(c.table_top_thickness_m, "table.top_thickness_m");
  check.positive(c.table_leg_size_m, "table.leg_size_m");
  check.positive(c.cabinet_length_m, "cabinet.length_m");
  check.positive(c.cabinet_width_m, "cabinet.width_m");
  check.positive(c.cabinet_height_m, "cabinet.height_m");
}

// The door, the table and the cabinet inside the room.
void checkFurniture(const SceneConfig& c, const SceneChecks& check) {
  const double half_l = c.room_length_m / 2, half_w = c.room_width_m / 2;
  check.require(std::abs(c.door_center_x_m) + c.door_width_m / 2 < half_l, "door.center_x_m",
                "puts the door recess outside the +Y wall");
  check.require(c.door_height_m < c.room_height_m, "door.height_m", "must be below the ceiling");

  check.require(std::abs(c.table_center_x_m) + c.table_length_m / 2 <= half_l, "table.center_x_m",
                "puts the table outside the room");
  check.require(std::abs(c.table_center_y_m) + c.table_width_m / 2 <= half_w, "table.center_y_m",
                "puts the table outside the room");
  check.require(c.table_height_m <= c.room_height_m, "table.height_m", "must be below the ceiling");
  check.require(c.table_top_thickness_m < c.table_height_m, "table.top_thickness_m",
                "must be less than the table height");
  check.require(2 * c.table_leg_size_m <= std::min(c.table_length_m, c.table_width_m),
                "table.leg_size_m", "legs do not fit under the top");

  check.require(std::abs(c.cabinet_center_x_m) + c.cabinet_length_m / 2 <= half_l,
                "cabinet.center_x_m", "puts the cabinet outside the room");
  check.require(std::abs(c.cabinet_center_y_m) + c.cabinet_width_m / 2 <= half_w,
                "cabinet.center_y_m", "puts the cabinet outside the room");
  check.require(c.cabinet_height_m <= c.room_height_m, "cabinet.height_m",
                "must be below the ceiling");
}

// The calibration target: its window inside its wall, its board inside the window.
void checkTarget(const SceneConfig& c, const SceneChecks& check) {
  const double half_l = c.room_length_m / 2, half_w = c.room_width_m / 2;
  check.require(c.target_wall == "x_min" || c.target_wall == "x_max" || c.target_wall == "y_min",
                "target.wall", "must be x_min, x_max or y_min (y_max holds the door)");
  check.positive(c.target_window_width_m, "target.window_width_m");
  check.positive(c.target_window_height_m, "target.window_height_m");
  check.positive(c.target_window_depth_m, "target.window_depth_m");
  check.positive(c.target_board_width_m, "target.board_width_m");
  check.positive(c.target_board_height_m, "target.board_height_m");
  check.positive(c.target_board_thickness_m, "target.board_thickness_m");
  check.require(c.target_window_sill_m > 0.0, "target.window_sill_m", "must be positive");
  const double half_wall = c.target_wall == "y_min" ? half_l : half_w;
  check.require(std::abs(c.target_position_m) + c.target_window_width_m / 2 < half_wall,
                "target.position_m", "puts the window outside its wall");
  check.require(c.target_window_sill_m + c.target_window_height_m < c.room_height_m,
                "target.window_height_m", "puts the window's top above the ceiling");
  check.require(c.target_board_width_m <= c.target_window_width_m, "target.board_width_m",
                "must not exceed the window's width");
  check.require(c.target_board_height_m <= c.target_window_height_m, "target.board_height_m",
                "must not exceed the window's height");
  check.require(c.target_board_thickness_m - c.target_board_offset_m <= c.target_window_depth_m,
                "target.board_offset_m", "puts the board behind the window's back");
  check.require(c.target_board_offset_m < std::min(half_l, half_w), "target.board_offset_m",
                "puts the board across the room");
}

// The rig inside the room, its stand's post clear of the table and the cabinet.
void checkRig(const SceneConfig& c, const SceneChecks& check) {
  const double half_l = c.room_length_m / 2, half_w = c.room_width_m / 2;
  check.require(std::abs(c.rig_x_m) + kPostSideM / 2 < half_l, "rig.x_m",
                "puts the rig outside the room");
  check.require(std::abs(c.rig_y_m) + kPostSideM / 2 < half_w, "rig.y_m",
                "puts the rig outside the room");
  check.require(c.rig_z_m > 0.0 && c.rig_z_m < c.room_height_m, "rig.z_m",
                "must be between floor and ceiling");
  const double post = kPostSideM / 2;
  const auto post_box = box(c.rig_x_m - post, c.rig_x_m + post, c.rig_y_m - post, c.rig_y_m + post,
                            0, c.room_height_m);
  const auto table_box =
      box(c.table_center_x_m - c.table_length_m / 2, c.table_center_x_m + c.table_length_m / 2,
          c.table_center_y_m - c.table_width_m / 2, c.table_center_y_m + c.table_width_m / 2, 0,
          c.room_height_m);
  const auto cabinet_box = box(c.cabinet_center_x_m - c.cabinet_length_m / 2,
                               c.cabinet_center_x_m + c.cabinet_length_m / 2,
                               c.cabinet_center_y_m - c.cabinet_width_m / 2,
                               c.cabinet_center_y_m + c.cabinet_width_m / 2, 0, c.room_height_m);
  check.require(!footprintsOverlap(post_box, table_box), "rig.x_m",
                "puts the rig's stand in the table");
  check.require(!footprintsOverlap(post_box, cabinet_box), "rig.x_m",
                "puts the rig's stand in the cabinet");
}

}  // namespace

void SceneConfig::validate(const std::string& source) const {
  const SceneChecks check(source);
  checkSizes(*this, check);
  checkFurniture(*this, check);
  if (target_enabled) checkTarget(*this, check);
  checkRig(*this, check);
}

SceneConfig loadScene(const std::string& path, const std::vector<std::string>& overrides) {
  SceneConfig scene;
  ConfigSchema schema;
  scene.declare(schema, "");
  schema.loadFile(path);
  for (const auto& o : overrides) schema.set(o);
  scene.validate(path);
  return scene;
}

namespace {

// The shell: floor, ceiling and walls. The +Y wall is door.depth_m thicker so the recess has
// a back (the door leaf); the floor runs under the recess.
std::vector<SceneBox> shellBoxes(const SceneConfig& c) {
  const double l = c.room_length_m / 2, w = c.room_width_m / 2, h = c.room_height_m;
  const double t = kWallThicknessM;
  const double y_outer = w + c.door_depth_m + t;
  const double door_x0 = c.door_center_x_m - c.door_width_m / 2;
  const double door_x1 = c.door_center_x_m + c.door_width_m / 2;
  return {
      {"floor", box(-l - t, l + t, -w - t, y_outer, -t, 0)},
      {"ceiling", box(-l - t, l + t, -w - t, y_outer, h, h + t)},
      {"wall_x_min", box(-l - t, -l, -w - t, y_outer, 0, h)},
      {"wall_x_max", box(l, l + t, -w - t, y_outer, 0, h)},
      {"wall_y_min", box(-l, l, -w - t, -w, 0, h)},
      {"wall_y_max_left", box(-l, door_x0, w, y_outer, 0, h)},
      {"wall_y_max_right", box(door_x1, l, w, y_outer, 0, h)},
      {"door_lintel", box(door_x0, door_x1, w, y_outer, c.door_height_m, h)},
      {"door_leaf", box(door_x0, door_x1, w + c.door_depth_m, y_outer, 0, c.door_height_m)},
  };
}

// The calibration target: the target's wall slab rebuilt around the window opening, the
// window's back and the board in front of it.
void addTarget(const SceneConfig& c, std::vector<SceneBox>* boxes) {
  const double l = c.room_length_m / 2, w = c.room_width_m / 2, h = c.room_height_m;
  const double t = kWallThicknessM;
  const double y_outer = w + c.door_depth_m + t;
  // A box in the wall's own coordinates: u along the wall, z up, depth behind the wall
  // plane (negative: in the room).
  const auto wallBox = [&](double u0, double u1, double z0, double z1, double d0, double d1) {
    if (c.target_wall == "x_min") return box(-l - d1, -l - d0, u0, u1, z0, z1);
    if (c.target_wall == "x_max") return box(l + d0, l + d1, u0, u1, z0, z1);
    return box(u0, u1, -w - d1, -w - d0, z0, z1);  // y_min
  };
  const std::string wall_name = "wall_" + c.target_wall;
  double u_lo, u_hi;
  if (c.target_wall == "y_min") {
    u_lo = -l;
    u_hi = l;
  } else {
    u_lo = -w - t;
    u_hi = y_outer;
  }
  boxes->erase(std::remove_if(boxes->begin(), boxes->end(),
                              [&](const SceneBox& b) { return b.name == wall_name; }),
               boxes->end());
  const double wu0 = c.target_position_m - c.target_window_width_m / 2;
  const double wu1 = c.target_position_m + c.target_window_width_m / 2;
  const double wz0 = c.target_window_sill_m, wz1 = wz0 + c.target_window_height_m;
  boxes->push_back({wall_name + "_below_window", wallBox(u_lo, u_hi, 0, wz0, 0, t)});
  boxes->push_back({wall_name + "_above_window", wallBox(u_lo, u_hi, wz1, h, 0, t)});
  boxes->push_back({wall_name + "_left_of_window", wallBox(u_lo, wu0, wz0, wz1, 0, t)});
  boxes->push_back({wall_name + "_right_of_window", wallBox(wu1, u_hi, wz0, wz1, 0, t)});
  boxes->push_back({"window_back", wallBox(wu0, wu1, wz0, wz1, c.target_window_depth_m,
                                           c.target_window_depth_m + t)});
  const double bz = 0.5 * (wz0 + wz1);
  const double d0 = -c.target_board_offset_m;
  boxes->push_back(
      {"target_board",
       wallBox(c.target_position_m - c.target_board_width_m / 2,
               c.target_position_m + c.target_board_width_m / 2, bz - c.target_board_height_m / 2,
               bz + c.target_board_height_m / 2, d0, d0 + c.target_board_thickness_m)});
}

// The table (a top on four legs flush with its corners) and the cabinet.
void addFurniture(const SceneConfig& c, std::vector<SceneBox>* boxes) {
  const double tx0 = c.table_center_x_m - c.table_length_m / 2;
  const double tx1 = c.table_center_x_m + c.table_length_m / 2;
  const double ty0 = c.table_center_y_m - c.table_width_m / 2;
  const double ty1 = c.table_center_y_m + c.table_width_m / 2;
  const double leg_top = c.table_height_m - c.table_top_thickness_m;
  const double s = c.table_leg_size_m;
  boxes->push_back({"table_top", box(tx0, tx1, ty0, ty1, leg_top, c.table_height_m)});
  boxes->push_back({"table_leg_1", box(tx0, tx0 + s, ty0, ty0 + s, 0, leg_top)});
  boxes->push_back({"table_leg_2", box(tx1 - s, tx1, ty0, ty0 + s, 0, leg_top)});
  boxes->push_back({"table_leg_3", box(tx0, tx0 + s, ty1 - s, ty1, 0, leg_top)});
  boxes->push_back({"table_leg_4", box(tx1 - s, tx1, ty1 - s, ty1, 0, leg_top)});

  boxes->push_back(
      {"cabinet", box(c.cabinet_center_x_m - c.cabinet_length_m / 2,
                      c.cabinet_center_x_m + c.cabinet_length_m / 2,
                      c.cabinet_center_y_m - c.cabinet_width_m / 2,
                      c.cabinet_center_y_m + c.cabinet_width_m / 2, 0, c.cabinet_height_m)});
}

}  // namespace

Scene::Scene(const SceneConfig& config, const PlateConfig& plate) : config_(config) {
  const SceneConfig& c = config_;
  c.validate("scene '" + c.name + "'");
  const double post_top_m = c.rig_z_m + plate.height_mm / 1000.0 - kPostBelowPlateM;
  if (post_top_m <= 0.0) {
    throw ConfigError("scene '" + c.name +
                      "': key 'rig.z_m' leaves no room for the stand below the plate");
  }

  T_room_rig_ = Eigen::Translation3d(c.rig_x_m, c.rig_y_m, c.rig_z_m) *
                Eigen::AngleAxisd(c.rig_yaw_deg * M_PI / 180.0, Eigen::Vector3d::UnitZ());

  const double l = c.room_length_m / 2, w = c.room_width_m / 2;
  walls_ = {{"x_min", Eigen::Vector3d::UnitX(), l},
            {"x_max", -Eigen::Vector3d::UnitX(), l},
            {"y_min", Eigen::Vector3d::UnitY(), w},
            {"y_max", -Eigen::Vector3d::UnitY(), w}};

  boxes_ = shellBoxes(c);
  if (c.target_enabled) addTarget(c, &boxes_);
  addFurniture(c, &boxes_);
  // The stand's post, axis-aligned in the room frame whatever the rig's yaw.
  const double p = kPostSideM / 2;
  boxes_.push_back({"stand_post", box(c.rig_x_m - p, c.rig_x_m + p, c.rig_y_m - p, c.rig_y_m + p, 0,
                                      post_top_m)});

  for (const SceneBox& b : boxes_) {
    slabs_.push_back({{b.box.min().x(), b.box.min().y(), b.box.min().z()},
                      {b.box.max().x(), b.box.max().y(), b.box.max().z()}});
  }
}

std::optional<Eigen::AlignedBox3d> Scene::targetBoard() const {
  for (const SceneBox& b : boxes_) {
    if (b.name == "target_board") return b.box;
  }
  return std::nullopt;
}

std::optional<double> Scene::raycast(const Eigen::Vector3d& origin_room,
                                     const Eigen::Vector3d& unit_dir_room,
                                     double max_range_m) const {
  return raycast(origin_room, unit_dir_room, max_range_m, nullptr);
}

std::optional<double> Scene::raycast(const Eigen::Vector3d& origin_room,
                                     const Eigen::Vector3d& unit_dir_room, double max_range_m,
                                     Hit* hit_info) const {
  const double o[3] = {origin_room.x(), origin_room.y(), origin_room.z()};
  const double d[3] = {unit_dir_room.x(), unit_dir_room.y(), unit_dir_room.z()};
  const double inv[3] = {1.0 / d[0], 1.0 / d[1], 1.0 / d[2]};
  double best = max_range_m;
  bool hit = false;
  for (size_t index = 0; index < slabs_.size(); ++index) {
    const Slabs& b = slabs_[index];
    // Slab test: the ray is inside the box for t in [t_enter, t_exit].
    double t_enter = -std::numeric_limits<double>::infinity();
    double t_exit = best;
    int enter_axis = 0;
    bool miss = false;
    for (int k = 0; k < 3 && !miss; ++k) {
      if (d[k] == 0.0) {
        miss = o[k] < b.lo[k] || o[k] > b.hi[k];
        continue;
      }
      double t0 = (b.lo[k] - o[k]) * inv[k];
      double t1 = (b.hi[k] - o[k]) * inv[k];
      if (t0 > t1) std::swap(t0, t1);
      if (t0 > t_enter) enter_axis = k;
      t_enter = std::max(t_enter, t0);
      t_exit = std::min(t_exit, t1);
      miss = t_enter > t_exit;
    }
    if (!miss && t_enter > 0.0) {
      best = t_enter;
      hit = true;
      if (hit_info) *hit_info = {index, enter_axis};
    }
  }
  if (!hit) return std::nullopt;
  return best;
}

}  // namespace sweepmap
