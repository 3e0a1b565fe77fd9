// A scene with round numbers for tests whose expected ranges are worked out by hand.
// Room 8 x 6 x 3 m centred on the origin; walls at x = +-4, y = +-3, ceiling at z = 3.
#pragma once

#include "sim/scene.hpp"

namespace sweepmap {
namespace testing_scene {

inline SceneConfig handScene() {
  SceneConfig c;
  c.name = "hand";
  c.room_length_m = 8.0;
  c.room_width_m = 6.0;
  c.room_height_m = 3.0;
  c.door_center_x_m = 2.5;  // recess x in [2, 3], y in [3, 3.3], z in [0, 2.1]
  c.door_width_m = 1.0;
  c.door_height_m = 2.1;
  c.door_depth_m = 0.3;
  c.table_center_x_m = -1.3;  // top x in [-2.5, -0.1], y in [-0.8, 0.4], z in [0.7, 0.74]
  c.table_center_y_m = -0.2;
  c.table_length_m = 2.4;
  c.table_width_m = 1.2;
  c.table_height_m = 0.74;
  c.table_top_thickness_m = 0.04;
  c.table_leg_size_m = 0.06;
  c.cabinet_center_x_m = 2.4;  // x in [1.8, 3.0], y in [-3.0, -2.55], z in [0, 0.9]
  c.cabinet_center_y_m = -2.775;
  c.cabinet_length_m = 1.2;
  c.cabinet_width_m = 0.45;
  c.cabinet_height_m = 0.9;
  c.rig_x_m = 1.2;
  c.rig_y_m = 0.8;
  c.rig_z_m = 1.0;
  c.rig_yaw_deg = 0.0;
  return c;
}

}  // namespace testing_scene
}  // namespace sweepmap
