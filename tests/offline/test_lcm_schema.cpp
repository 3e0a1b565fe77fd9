// The LCM schema read at run time: every type parsed from the embedded .lcm files has
// lcm-gen's fingerprint (the generated getHash()); messages decode field by field; hostile
// counts and truncation are errors with offsets; `dump` prints logs in both forms.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <sstream>

#include "core/event_log.hpp"
#include "processes/node.hpp"
#include "sweepmap/cloud_chunk_t.hpp"
#include "sweepmap/imu_t.hpp"
#include "sweepmap/lidar_scan_t.hpp"
#include "sweepmap/map_save_t.hpp"
#include "sweepmap/map_stats_t.hpp"
#include "sweepmap/motor_state_t.hpp"
#include "sweepmap/pose2d_t.hpp"
#include "sweepmap/process_status_t.hpp"
#include "sweepmap/profile_t.hpp"
#include "sweepmap/scan_window_t.hpp"
#include "sweepmap/sweep_status_t.hpp"
#include "sweepmap/switch_event_t.hpp"
#include "sweepmap/truth_mounting_t.hpp"
#include "sweepmap/truth_profile_rig_t.hpp"
#include "sweepmap/truth_rig_t.hpp"
#include "sweepmap/truth_shaft_t.hpp"
#include "sweepmap/truth_sweep_t.hpp"
#include "sweepmap/truth_test_piece_t.hpp"
#include "sweepmap/wheel_cmd_t.hpp"
#include "sweepmap/wheel_ticks_t.hpp"
#include "tools/offline/dump.hpp"
#include "tools/offline/lcm_schema.hpp"

namespace sweepmap {
namespace {

template <class T>
void expectFingerprint(const char* name) {
  const LcmStruct* s = LcmSchema::builtIn().find(name);
  ASSERT_NE(s, nullptr) << name;
  EXPECT_EQ(s->fingerprint, T::getHash()) << name;
}

TEST(LcmSchema, EveryTypeHasLcmGensFingerprint) {
  EXPECT_EQ(LcmSchema::builtIn().structs().size(), 20u);
  expectFingerprint<cloud_chunk_t>("cloud_chunk_t");
  expectFingerprint<imu_t>("imu_t");
  expectFingerprint<lidar_scan_t>("lidar_scan_t");
  expectFingerprint<map_save_t>("map_save_t");
  expectFingerprint<map_stats_t>("map_stats_t");
  expectFingerprint<motor_state_t>("motor_state_t");
  expectFingerprint<pose2d_t>("pose2d_t");
  expectFingerprint<process_status_t>("process_status_t");
  expectFingerprint<profile_t>("profile_t");
  expectFingerprint<scan_window_t>("scan_window_t");
  expectFingerprint<sweep_status_t>("sweep_status_t");
  expectFingerprint<switch_event_t>("switch_event_t");
  expectFingerprint<truth_mounting_t>("truth_mounting_t");
  expectFingerprint<truth_profile_rig_t>("truth_profile_rig_t");
  expectFingerprint<truth_rig_t>("truth_rig_t");
  expectFingerprint<truth_shaft_t>("truth_shaft_t");
  expectFingerprint<truth_sweep_t>("truth_sweep_t");
  expectFingerprint<truth_test_piece_t>("truth_test_piece_t");
  expectFingerprint<wheel_cmd_t>("wheel_cmd_t");
  expectFingerprint<wheel_ticks_t>("wheel_ticks_t");
}

// Hand-written definitions: nested structs, fixed and variable multi-dimensional arrays,
// constants and comments.
TEST(LcmSchema, ParsesNestedArraysConstsAndComments) {
  using Sources = std::vector<std::pair<std::string, std::string>>;
  const LcmSchema schema(
      Sources{{"a.lcm",
               "package p; /* block\ncomment */\nstruct inner_t { int16_t k; }\n"
               "struct outer_t {\n  int8_t n; // count\n  const int32_t A = 1, B = 2;\n"
               "  inner_t in[2];\n  double m[n][3];\n  string s;\n  boolean b;\n}\n"}});
  const LcmStruct* o = schema.find("p.outer_t");
  ASSERT_NE(o, nullptr);
  ASSERT_EQ(o->members.size(), 5u);
  EXPECT_EQ(o->members[0].comment, "count");
  EXPECT_EQ(o->members[2].dims, (std::vector<std::string>{"n", "3"}));
  // Encode by hand: fingerprint, n = 1, in[2] (k = -2, 7), m[1][3], "hi", true.
  std::vector<uint8_t> b;
  const auto put = [&](uint64_t v, int n) {
    for (int i = n - 1; i >= 0; --i) b.push_back(static_cast<uint8_t>(v >> (8 * i)));
  };
  put(static_cast<uint64_t>(o->fingerprint), 8);
  put(1, 1);
  put(static_cast<uint16_t>(-2), 2);
  put(7, 2);
  for (double d : {1.5, -2.0, 3.25}) {
    uint64_t u;
    std::memcpy(&u, &d, 8);
    put(u, 8);
  }
  put(3, 4);
  b.insert(b.end(), {'h', 'i', 0});
  put(1, 1);
  LcmValue v;
  ASSERT_EQ(schema.decode(b.data(), b.size(), &v), o);
  EXPECT_EQ(v.fields[1].second.items[0].fields[0].second.i, -2);
  EXPECT_EQ(v.fields[2].second.items[0].items[2].d, 3.25);
  EXPECT_EQ(v.fields[3].second.s, "hi");
  EXPECT_EQ(v.fields[4].second.kind, LcmValue::Kind::kBool);
  // Truncated: an error naming the field and the offset.
  try {
    schema.decode(b.data(), b.size() - 3, &v);
    FAIL();
  } catch (const LcmSchemaError& e) {
    EXPECT_NE(std::string(e.what()).find("outer_t.s"), std::string::npos) << e.what();
  }
  EXPECT_THROW(LcmSchema(Sources{{"bad.lcm", "struct x_t { int32_t a[n]; }"}}), LcmSchemaError);
}

TEST(LcmSchema, HostileCountIsAnErrorNotAnAllocation) {
  lidar_scan_t s{};
  s.nranges = 2;
  s.ranges_m = {1.0f, 2.0f};
  std::vector<uint8_t> b(static_cast<size_t>(s.getEncodedSize()));
  s.encode(b.data(), 0, static_cast<int>(b.size()));
  b[44] = 0x7f;  // nranges = 2^31 - ...
  LcmValue v;
  try {
    LcmSchema::builtIn().decode(b.data(), b.size(), &v);
    FAIL();
  } catch (const LcmSchemaError& e) {
    EXPECT_NE(std::string(e.what()).find("lidar_scan_t.ranges_m at byte 48"), std::string::npos)
        << e.what();
  }
}

TEST(Dump, HumanAndJsonFormsAndATruncatedLog) {
  const std::string path =
      (std::filesystem::path(SWEEPMAP_BINARY_DIR) / "test_scratch" / "dump.lcmlog").string();
  std::filesystem::create_directories(std::filesystem::path(path).parent_path());
  {
    EventLogWriter w(path);
    Outbox out;
    lidar_scan_t s{};
    s.utime = 42;
    s.nranges = 10;
    s.ranges_m.assign(10, 1.25f);
    s.ranges_m[3] = std::nanf("");
    s.device_stamp = -1;
    out.publish("LIDAR_SCAN", 42, s);
    wheel_ticks_t t{};
    t.utime = 43;
    t.left_ticks = 7;
    out.publish("WHEEL_TICKS", 43, t);
    for (const Message& m : out.take()) w.write(m.utime, m.channel, m.data);
    w.write(44, "OTHER", std::vector<uint8_t>{1, 2, 3});
    w.close();
  }
  std::ostringstream human, json, err;
  EXPECT_EQ(runDump({path, "", false, false}, human, err), 0);
  EXPECT_NE(human.str().find("42 LIDAR_SCAN (sweepmap.lidar_scan_t"), std::string::npos)
      << human.str();
  EXPECT_NE(human.str().find("ranges_m[10] = 1.25 1.25 1.25 nan"), std::string::npos)
      << human.str();
  EXPECT_NE(human.str().find("(10 values; --full shows all)"), std::string::npos);
  EXPECT_NE(human.str().find("3 bytes: 010203)"), std::string::npos) << human.str();
  EXPECT_EQ(runDump({path, "WHEEL_TICKS", true, false}, json, err), 0);
  EXPECT_EQ(json.str(),
            "{\"channel\":\"WHEEL_TICKS\",\"log_utime\":43,\"type\":\"sweepmap.wheel_ticks_t\","
            "\"utime\":43,\"left_ticks\":7,\"right_ticks\":0}\n");
  std::ostringstream all;
  runDump({path, "", true, false}, all, err);
  EXPECT_NE(all.str().find("\"ranges_m\":[1.25,1.25,1.25,null,1.25"), std::string::npos)
      << all.str();
  // Cut the log inside its last event: the ones before are printed, then the error.
  std::filesystem::resize_file(path, std::filesystem::file_size(path) - 2);
  std::ostringstream cut, cut_err;
  EXPECT_EQ(runDump({path, "", false, false}, cut, cut_err), 1);
  EXPECT_NE(cut.str().find("WHEEL_TICKS"), std::string::npos);
  EXPECT_NE(cut_err.str().find("byte"), std::string::npos) << cut_err.str();
}

}  // namespace
}  // namespace sweepmap
