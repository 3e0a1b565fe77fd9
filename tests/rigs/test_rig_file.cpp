// Rig kinds: the kind read from the file, its schema applied strictly, names resolved in
// the install tree, and clear errors for a file of the wrong or no kind.
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <iterator>
#include <type_traits>

#include "core/calibration_file.hpp"
#include "core/config.hpp"
#include "rigs/rig_file.hpp"

namespace sweepmap {
namespace {

namespace fs = std::filesystem;

const std::string kRigA = std::string(SWEEPMAP_SOURCE_DIR) + "/config/rig_a.yaml";
const std::string kRigB = std::string(SWEEPMAP_SOURCE_DIR) + "/config/rig_b.yaml";

// The message of the ConfigError `f` throws ("" when it throws none).
template <class F>
std::string configError(F f) {
  try {
    f();
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

fs::path scratch(const std::string& name) {
  const fs::path d = fs::path(SWEEPMAP_BINARY_DIR) / "test_scratch" / name;
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

TEST(RigFile, KindComesFromTheFile) {
  EXPECT_EQ(readRigKind(kRigA), RigKind::kRotatingLidar);
  EXPECT_EQ(readRigKind(kRigB), RigKind::kMobileLidar);
  const Rig a = loadRig(kRigA);
  EXPECT_EQ(a.kind(), RigKind::kRotatingLidar);
  EXPECT_EQ(a.kindName(), "rotating_lidar");
  EXPECT_EQ(std::get<RotatingLidarConfig>(a.config).lidar.beam_count, 1081);
  const Rig b = loadRig(kRigB, {"mapper.batch_s=2"});
  EXPECT_EQ(b.kind(), RigKind::kMobileLidar);
  EXPECT_DOUBLE_EQ(std::get<MobileLidarConfig>(b.config).mapper.batch_s, 2.0);
}

TEST(RigFile, EveryShippedRigFileLoads) {
  for (const char* name :
       {"rig_a", "rig_b", "rig_b_mines_rover", "rig_a_ust10lx", "rig_b_x4", "rig_c"}) {
    EXPECT_NO_THROW(loadRig(name)) << name;
  }
}

// Every bound of a live process is a config key of every rig kind (network.*, the mapper's),
// its shipped value the former hard-coded one, and a bound that is not positive is an error
// naming the file and the key.
TEST(RigFile, EveryBoundIsAConfigKeyOfEveryKind) {
  for (const char* name : {"rig_a", "rig_b", "rig_c"}) {
    const Rig rig = loadRig(name);
    std::visit(
        [&](const auto& c) {
          EXPECT_EQ(c.network.queue_messages, NetworkConfig{}.queue_messages) << name;
          EXPECT_EQ(c.network.max_senders, NetworkConfig{}.max_senders) << name;
          EXPECT_EQ(c.network.fragment_timeout_s, NetworkConfig{}.fragment_timeout_s) << name;
          EXPECT_EQ(c.mapper.max_pending_sweeps, MapperConfig{}.max_pending_sweeps) << name;
          EXPECT_EQ(c.mapper.max_requested_files, MapperConfig{}.max_requested_files) << name;
        },
        rig.config);
    for (const char* key :
         {"network.max_senders", "network.queue_mib", "network.fragment_timeout_s",
          "mapper.max_pending_sweeps", "mapper.save_interval_s"}) {
      try {
        loadRig(name, {std::string(key) + "=0"});
        ADD_FAILURE() << name << " " << key << "=0 accepted";
      } catch (const ConfigError& e) {
        EXPECT_NE(std::string(e.what()).find(std::string("key '") + key + "' must be > 0"),
                  std::string::npos)
            << e.what();
      }
    }
  }
}

TEST(RigFile, RigCIsARotatingProfileWithoutALidar) {
  const Rig c = loadRig("rotating_profile");  // the kind's name stands for rig_c
  EXPECT_EQ(c.kind(), RigKind::kRotatingProfile);
  const auto& config = std::get<RotatingProfileConfig>(c.config);
  EXPECT_EQ(config.profiler.column_count, 1280);
  EXPECT_DOUBLE_EQ(config.sim.offset_m_mm, 123.0);  // Zhao 2021 Table 1
  EXPECT_DOUBLE_EQ(config.sim.offset_n_mm, 409.0);
  EXPECT_NE(config.geometry.offset_m_mm, config.sim.offset_m_mm);  // nominal, a few mm off
  const std::string e = configError([&] { c.lidar(); });
  EXPECT_NE(e.find("has no 2D lidar"), std::string::npos) << e;
  const std::string scene = configError([] { loadRig("rig_c", {"sim.scene=room"}); });
  EXPECT_NE(scene.find("sim.scene"), std::string::npos) << scene;
  // The reference face's normal must lean (a level face has no azimuth), its sigma be >= 0.
  for (const char* bad :
       {"turntable.reference.normal_tilt_deg=0", "turntable.reference.normal_tilt_deg=80",
        "turntable.reference.azimuth_sigma_deg=-1"}) {
    const std::string e = configError([&] { loadRig("rig_c", {bad}); });
    const std::string key = std::string(bad).substr(0, std::string(bad).find('='));
    EXPECT_NE(e.find(key), std::string::npos) << bad << ": " << e;
  }
}

TEST(RigFile, RigCReadsItsAxisOffsetCalibrationFile) {
  const fs::path dir = scratch("rig_c_calibration");
  AxisOffsetCalibration c;
  c.m_mm = 123.02;
  c.n_mm = 408.97;
  c.laser_tilt_deg = 0.21;
  c.encoder_zero_deg = 0.0;
  c.source["tool"] = "test";
  c.logs = {"plates.lcmlog"};
  writeAxisOffsetCalibration((dir / "axis_offset.yaml").string(), c);
  EXPECT_FALSE(fs::exists(dir / "axis_offset.yaml.tmp"));
  const AxisOffsetCalibration back = loadAxisOffsetCalibration((dir / "axis_offset.yaml").string());
  EXPECT_DOUBLE_EQ(back.n_mm, 408.97);
  EXPECT_EQ(back.logs, c.logs);
  fs::copy_file(fs::path(SWEEPMAP_SOURCE_DIR) / "config" / "rig_c.yaml", dir / "rig.yaml");
  const auto rig = std::get<RotatingProfileConfig>(
      loadRig((dir / "rig.yaml").string(), {"geometry.calibration_file=axis_offset.yaml"}).config);
  EXPECT_DOUBLE_EQ(rig.geometry.offset_m_mm, 123.02);
  EXPECT_DOUBLE_EQ(rig.geometry.offset_n_mm, 408.97);
  EXPECT_DOUBLE_EQ(rig.geometry.laser_tilt_deg, 0.21);
  std::ofstream(dir / "bad.yaml") << "axis_offset:\n  m_mm: 1\n";
  const std::string e =
      configError([&] { loadAxisOffsetCalibration((dir / "bad.yaml").string()); });
  EXPECT_NE(e.find("axis_offset.n_mm"), std::string::npos) << e;
}

TEST(RigFile, RigAReadsItsLidarOffsetCalibrationFile) {
  // What sweepmap calib axis-offset --rig rig_a writes; every rig-A load (live assembler,
  // replay, eval) then places the points with it.
  const fs::path dir = scratch("rig_a_offset_calibration");
  LidarOffsetCalibration c;
  c.lidar_offset_x_mm = 15.97;
  c.source["tool"] = "test";
  c.logs = {"room.lcmlog"};
  writeLidarOffsetCalibration((dir / "offset.yaml").string(), c);
  EXPECT_FALSE(fs::exists(dir / "offset.yaml.tmp"));
  EXPECT_DOUBLE_EQ(loadLidarOffsetCalibration((dir / "offset.yaml").string()).lidar_offset_x_mm,
                   15.97);
  fs::copy_file(fs::path(SWEEPMAP_SOURCE_DIR) / "config" / "rig_a.yaml", dir / "rig.yaml");
  const auto nominal = std::get<RotatingLidarConfig>(loadRig((dir / "rig.yaml").string()).config);
  EXPECT_DOUBLE_EQ(nominal.geometry.lidar_offset_x_mm, 13.9);
  const auto rig = std::get<RotatingLidarConfig>(
      loadRig((dir / "rig.yaml").string(), {"geometry.calibration_file=offset.yaml"}).config);
  EXPECT_DOUBLE_EQ(rig.geometry.lidar_offset_x_mm, 15.97);
  // Another kind's file, or a missing one, names the file and the key.
  std::ofstream(dir / "bad.yaml") << "geometry:\n  lidar_offset_mm: 16\n";
  const std::string e = configError(
      [&] { loadRig((dir / "rig.yaml").string(), {"geometry.calibration_file=bad.yaml"}); });
  EXPECT_NE(e.find("geometry.lidar_offset_x_mm"), std::string::npos) << e;
  EXPECT_NE(e.find("bad.yaml"), std::string::npos) << e;
  EXPECT_FALSE(configError([&] {
                 loadRig((dir / "rig.yaml").string(), {"geometry.calibration_file=none.yaml"});
               }).empty());
}

// The build tree's config folder is a copy of config/ (not a link into the checkout that built
// it): a name resolves to the build tree's copy, which holds the same bytes.
TEST(RigFile, NamesResolveInTheInstallTreeFromAnyDirectory) {
  const auto sameFile = [](const fs::path& resolved, const fs::path& source) {
    std::ifstream a(resolved, std::ios::binary), b(source, std::ios::binary);
    const std::string x(std::istreambuf_iterator<char>(a), {}),
        y(std::istreambuf_iterator<char>(b), {});
    return resolved.filename() == source.filename() && !x.empty() && x == y;
  };
  const fs::path here = fs::current_path();
  fs::current_path(scratch("names"));
  const Rig b = loadRig("rig_b");
  EXPECT_EQ(b.kind(), RigKind::kMobileLidar);
  EXPECT_TRUE(sameFile(b.path, kRigB)) << b.path;
  EXPECT_TRUE(sameFile(loadRig("rig_a.yaml").path, kRigA));
  // A kind's name stands for its reference rig.
  EXPECT_TRUE(sameFile(resolveRigFile("rotating_lidar"), kRigA));
  EXPECT_TRUE(sameFile(resolveConfigFile("scene_lab"),
                       fs::path(SWEEPMAP_SOURCE_DIR) / "config" / "scene_lab.yaml"));
  const std::string missing = configError([] { resolveRigFile("rig_z"); });
  EXPECT_NE(missing.find("rig_z.yaml"), std::string::npos) << missing;
  // The fix: the rigs there are, and the kinds' names.
  EXPECT_NE(missing.find("the rigs there are: rig_a, "), std::string::npos) << missing;
  EXPECT_NE(missing.find("rig_c"), std::string::npos) << missing;
  EXPECT_NE(missing.find("rotating_profile"), std::string::npos) << missing;
  const std::string scene = configError([] { resolveSceneFile("scene_z"); });
  EXPECT_NE(scene.find("the scenes there are: scene_conference_room, scene_lab"), std::string::npos)
      << scene;
  fs::current_path(here);
}

TEST(RigFile, ConfigDirCanBeOverridden) {
  const fs::path dir = scratch("config_dir");
  fs::copy_file(kRigA, dir / "my_rig.yaml");
  setenv("SWEEPMAP_CONFIG_DIR", dir.c_str(), 1);
  EXPECT_EQ(loadRig("my_rig").kind(), RigKind::kRotatingLidar);
  EXPECT_NE(configError([] { resolveRigFile("rig_b"); }).find("rig_b"), std::string::npos);
  unsetenv("SWEEPMAP_CONFIG_DIR");
  EXPECT_NO_THROW(resolveRigFile("rig_b"));
}

TEST(RigFile, MissingOrUnknownKindIsAClearError) {
  const fs::path dir = scratch("kinds");
  std::ofstream(dir / "none.yaml") << "lidar:\n  beam_count: 10\n";
  const std::string none = configError([&] { loadRig((dir / "none.yaml").string()); });
  EXPECT_NE(none.find("none.yaml"), std::string::npos) << none;
  EXPECT_NE(none.find("missing key 'rig'"), std::string::npos) << none;
  EXPECT_NE(none.find("rotating_lidar"), std::string::npos) << none;

  std::ofstream(dir / "bad.yaml") << "rig: spinning_lidar\n";
  const std::string bad = configError([&] { loadRig((dir / "bad.yaml").string()); });
  EXPECT_NE(bad.find("'spinning_lidar'"), std::string::npos) << bad;
  EXPECT_NE(bad.find("mobile_lidar"), std::string::npos) << bad;
}

TEST(RigFile, AFileOfOneKindIsNotLoadedAsAnother) {
  const std::string as_b = configError([] { loadMobileLidarConfig(kRigA); });
  EXPECT_NE(as_b.find("rig_a.yaml"), std::string::npos) << as_b;
  EXPECT_FALSE(as_b.empty());
  const std::string as_a = configError([] { loadRotatingLidarConfig(kRigB); });
  EXPECT_FALSE(as_a.empty());
  // Overriding the kind is caught as well.
  const std::string set = configError([] { loadRotatingLidarConfig(kRigA, {"rig=mobile_lidar"}); });
  EXPECT_NE(set.find("expected 'rotating_lidar'"), std::string::npos) << set;
}

TEST(RigFile, RequireKindNamesBothKinds) {
  const Rig a = loadRig(kRigA);
  EXPECT_NO_THROW(requireKind<RotatingLidarConfig>(a, "sweepmap-motor"));
  const std::string e =
      configError([&] { requireKind<MobileLidarConfig>(a, "sweepmap-odometry"); });
  EXPECT_NE(e.find("is a rotating_lidar rig"), std::string::npos) << e;
  EXPECT_NE(e.find("sweepmap-odometry needs a mobile_lidar rig"), std::string::npos) << e;
}

// The real-device examples are their simulated rig with other devices, nothing else.
TEST(RigFile, RealDeviceExamplesDifferOnlyInTheDevice) {
  const auto yamlWithDevice = [](const std::string& name, const std::string& device) {
    Rig rig = loadRig(name);
    return std::visit(
        [&](auto c) {
          if constexpr (std::is_same_v<decltype(c), RotatingProfileConfig>) {
            c.profiler.device = device;
          } else {
            c.lidar.device = device;
          }
          if constexpr (std::is_same_v<decltype(c), MobileLidarConfig>) {
            c.imu_device = device;
            c.wheels_device = device;
          }
          ConfigSchema s;
          c.declare(s);
          return s.toYaml();
        },
        rig.config);
  };
  EXPECT_EQ(loadRig("rig_a_ust10lx").lidar().device, "scip://192.168.0.10:10940");
  EXPECT_EQ(loadRig("rig_b_x4").lidar().device, "ydlidar:///dev/ttyUSB0");
  const auto b = std::get<MobileLidarConfig>(loadRig("rig_b_x4").config);
  EXPECT_EQ(b.imu_device, "hi219:///dev/ttyUSB1");
  EXPECT_EQ(b.wheels_device, "wheelboard:///dev/ttyACM0");
  EXPECT_EQ(yamlWithDevice("rig_a_ust10lx", "x"), yamlWithDevice("rig_a", "x"));
  EXPECT_EQ(yamlWithDevice("rig_b_x4", "x"), yamlWithDevice("rig_b", "x"));
}

// A device URI that cannot be opened is a config error naming the key, and --set when the
// value came from an override (not the rig file, which holds a good one).
TEST(RigFile, BadDeviceUriIsAConfigError) {
  const std::string e = configError([] { loadRig(kRigA, {"lidar.device=usb0"}); });
  EXPECT_NE(e.find("--set lidar.device=usb0: key 'lidar.device': device 'usb0': expected sim"),
            std::string::npos)
      << e;
  EXPECT_NE(e.find("(rig file "), std::string::npos) << e;
}

// A value an override sets that the kind's checks reject names --set and the key.
TEST(RigFile, ABadOverrideNamesSetNotTheFile) {
  const std::string e = configError([] { loadRig(kRigA, {"motor.mode=9"}); });
  EXPECT_EQ(e.rfind("--set motor.mode=9: ", 0), 0u) << e;
  EXPECT_NE(e.find("motor.mode"), std::string::npos) << e;
}

// A calibration file named relative to the rig file: the error says relative to what.
TEST(RigFile, RelativePathsSayWhatTheyAreRelativeTo) {
  const fs::path dir = scratch("relative");
  fs::copy_file(kRigA, dir / "rig.yaml");
  const std::string e =
      configError([&] { loadRig((dir / "rig.yaml").string(), {"plate.calibration_file=c.yaml"}); });
  EXPECT_NE(e.find("relative to the rig file's folder " + dir.string()), std::string::npos) << e;
  EXPECT_NE(e.find("plate.calibration_file"), std::string::npos) << e;
}

// Each device key takes its own kind of device.
TEST(RigFile, DeviceOfTheWrongKindIsAConfigError) {
  const std::string imu =
      configError([] { loadRig("rig_b", {"imu.device=ydlidar:///dev/ttyUSB0"}); });
  EXPECT_NE(imu.find("key 'imu.device': device 'ydlidar:///dev/ttyUSB0': a ydlidar device does "
                     "not belong here (this key takes sim, hi219)"),
            std::string::npos)
      << imu;
  const std::string wheels =
      configError([] { loadRig("rig_b", {"wheels.device=hi219:///dev/ttyUSB1"}); });
  EXPECT_NE(wheels.find("key 'wheels.device'"), std::string::npos) << wheels;
  const std::string lidar =
      configError([] { loadRig("rig_b", {"lidar.device=hi219:///dev/ttyUSB1"}); });
  EXPECT_NE(lidar.find("key 'lidar.device'"), std::string::npos) << lidar;
  EXPECT_NO_THROW(loadRig("rig_b", {"wheels.device=wheelboard:///dev/ttyACM1?baud=230400"}));
}

}  // namespace
}  // namespace sweepmap
