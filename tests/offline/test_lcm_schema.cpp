// The LCM schema read at run time: every type parsed from the embedded .lcm files has
// lcm-gen's fingerprint (the generated getHash()); messages decode field by field; hostile
// counts and truncation are errors with offsets; `dump` prints logs in both forms.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <set>
#include <sstream>

#include "core/event_log.hpp"
#include "core/lcm_schema.hpp"
#include "processes/node.hpp"
#include "sweepmap/cloud_chunk_t.hpp"
#include "sweepmap/imu_t.hpp"
#include "sweepmap/lidar_scan_t.hpp"
#include "sweepmap/map_save_t.hpp"
#include "sweepmap/map_stats_t.hpp"
#include "sweepmap/map_update_t.hpp"
#include "sweepmap/motor_state_t.hpp"
#include "sweepmap/pose2d_t.hpp"
#include "sweepmap/process_status_t.hpp"
#include "sweepmap/profile_t.hpp"
#include "sweepmap/scan_window_t.hpp"
#include "sweepmap/sweep_status_t.hpp"
#include "sweepmap/switch_event_t.hpp"
#include "sweepmap/truth_mobile_rig_t.hpp"
#include "sweepmap/truth_mounting_t.hpp"
#include "sweepmap/truth_profile_rig_t.hpp"
#include "sweepmap/truth_rig_errors_t.hpp"
#include "sweepmap/truth_rig_t.hpp"
#include "sweepmap/truth_shaft_t.hpp"
#include "sweepmap/truth_sweep_t.hpp"
#include "sweepmap/truth_test_piece_t.hpp"
#include "sweepmap/wheel_cmd_t.hpp"
#include "sweepmap/wheel_ticks_t.hpp"
#include "tools/offline/dump.hpp"
#include "tools/offline/runs.hpp"

namespace sweepmap {
namespace {

template <class T>
void expectFingerprint(const char* name) {
  const LcmStruct* s = LcmSchema::builtIn().find(name);
  ASSERT_NE(s, nullptr) << name;
  EXPECT_EQ(s->fingerprint, T::getHash()) << name;
}

TEST(LcmSchema, EveryTypeHasLcmGensFingerprint) {
  EXPECT_EQ(LcmSchema::builtIn().structs().size(), 23u);
  expectFingerprint<cloud_chunk_t>("cloud_chunk_t");
  expectFingerprint<imu_t>("imu_t");
  expectFingerprint<lidar_scan_t>("lidar_scan_t");
  expectFingerprint<map_save_t>("map_save_t");
  expectFingerprint<map_stats_t>("map_stats_t");
  expectFingerprint<map_update_t>("map_update_t");
  expectFingerprint<motor_state_t>("motor_state_t");
  expectFingerprint<pose2d_t>("pose2d_t");
  expectFingerprint<process_status_t>("process_status_t");
  expectFingerprint<profile_t>("profile_t");
  expectFingerprint<scan_window_t>("scan_window_t");
  expectFingerprint<sweep_status_t>("sweep_status_t");
  expectFingerprint<switch_event_t>("switch_event_t");
  expectFingerprint<truth_mobile_rig_t>("truth_mobile_rig_t");
  expectFingerprint<truth_mounting_t>("truth_mounting_t");
  expectFingerprint<truth_profile_rig_t>("truth_profile_rig_t");
  expectFingerprint<truth_rig_errors_t>("truth_rig_errors_t");
  expectFingerprint<truth_rig_t>("truth_rig_t");
  expectFingerprint<truth_shaft_t>("truth_shaft_t");
  expectFingerprint<truth_sweep_t>("truth_sweep_t");
  expectFingerprint<truth_test_piece_t>("truth_test_piece_t");
  expectFingerprint<wheel_cmd_t>("wheel_cmd_t");
  expectFingerprint<wheel_ticks_t>("wheel_ticks_t");
}

template <class Msg>
std::vector<uint8_t> bytesOf(const Msg& m) {
  std::vector<uint8_t> b(static_cast<size_t>(m.getEncodedSize()));
  m.encode(b.data(), 0, static_cast<int>(b.size()));
  return b;
}

std::string validate(const std::vector<uint8_t>& b) {
  return LcmSchema::builtIn().validate(b.data(), b.size());
}

process_status_t aStatus() {
  process_status_t m{};
  m.utime = 5;
  m.process = "mapper";
  m.health = process_status_t::DEGRADED;
  m.detail = "fine: déjà vu";
  m.ncounters = 2;
  m.counter_names = {"a", "b"};
  m.counter_values = {1, 2};
  return m;
}

// Issue 21: the messages that killed or stalled the processes, and what must hold of any
// message before a node sees it.
TEST(LcmSchemaValidate, RealMessagesPassAndEveryKindOfDamageIsNamed) {
  EXPECT_EQ(validate(bytesOf(aStatus())), "");
  lidar_scan_t scan{};
  scan.nranges = 3;
  scan.ranges_m = {1.0f, 0.0f, 2.5f};
  EXPECT_EQ(validate(bytesOf(scan)), "");

  // A string length of INT32_MIN (a 22-byte MAP_SAVE).
  map_save_t save{};
  save.utime = 1;
  save.path = "x";
  std::vector<uint8_t> b = bytesOf(save);
  b[16] = 0x80, b[17] = b[18] = b[19] = 0;
  EXPECT_NE(validate(b).find("map_save_t.path at byte 16: string length -2147483648"),
            std::string::npos)
      << validate(b);
  // ncounters = 2^26 in 100 bytes.
  b = bytesOf(aStatus());
  const size_t n_at = 8 + 8 + 4 + 7 + 1 + 4 + 16;  // fingerprint, utime, process, health, detail
  b[n_at] = 0x04, b[n_at + 1] = b[n_at + 2] = b[n_at + 3] = 0;
  EXPECT_NE(validate(b).find("counter_names"), std::string::npos) << validate(b);
  EXPECT_NE(validate(b).find("do not fit"), std::string::npos) << validate(b);
  // Text that is not UTF-8, a health that is none of its constants.
  process_status_t bad_text = aStatus();
  bad_text.detail = "\xff\xfe";
  EXPECT_NE(validate(bytesOf(bad_text)).find("not UTF-8"), std::string::npos);
  process_status_t bad_enum = aStatus();
  bad_enum.health = 7;
  EXPECT_NE(validate(bytesOf(bad_enum)).find("health"), std::string::npos);
  // NaN only where the type says it may be.
  imu_t imu{};
  imu.rpy_rad[0] = std::nan("");
  EXPECT_EQ(validate(bytesOf(imu)), "");
  imu.gyro_rad_s[1] = std::numeric_limits<double>::infinity();
  EXPECT_NE(validate(bytesOf(imu)).find("imu_t.gyro_rad_s"), std::string::npos)
      << validate(bytesOf(imu));
  // Bytes left over, a cut message, an unknown type.
  b = bytesOf(aStatus());
  b.push_back(0);
  EXPECT_NE(validate(b).find("left over"), std::string::npos);
  b.resize(b.size() - 10);
  EXPECT_NE(validate(b), "");
  b = bytesOf(aStatus());
  b[0] ^= 1;
  EXPECT_NE(validate(b).find("unknown type"), std::string::npos);
}

// No message sweepmap itself makes is refused: every raw and truth message of a short
// simulation of each rig kind validates.
TEST(LcmSchemaValidate, EveryMessageOfEachRigsSimulationIsValid) {
  for (const char* rig : {"rig_a", "rig_b", "rig_c"}) {
    std::vector<std::string> overrides;
    if (std::string(rig) == "rig_b") overrides.push_back("sim.duration_s=3");
    const SimSetup setup = loadSimSetup(rig, "", overrides);
    SimRunOptions options;
    size_t messages = 0;
    simulateRig(setup, options, [&](const Message& m) {
      ++messages;
      const std::string why = LcmSchema::builtIn().validate(m.data.data(), m.data.size());
      ASSERT_EQ(why, "") << rig << " " << m.channel;
    });
    EXPECT_GT(messages, 100u) << rig;
  }
}

// Every prefix and every single-byte change of real messages: validate never crashes and
// refuses every prefix.
TEST(LcmSchemaValidate, DamagedMessagesNeverCrashIt) {
  for (const std::vector<uint8_t>& good : {bytesOf(aStatus()), bytesOf(map_save_t{})}) {
    for (size_t n = 0; n < good.size(); ++n) {
      EXPECT_NE(LcmSchema::builtIn().validate(good.data(), n), "") << n;
    }
    for (size_t i = 0; i < good.size(); ++i) {
      for (int v : {0x00, 0x7f, 0x80, 0xff}) {
        std::vector<uint8_t> b = good;
        b[i] = static_cast<uint8_t>(v);
        LcmSchema::builtIn().validate(b.data(), b.size());
      }
    }
  }
}

// The schema is every .lcm file of lcmtypes/, and fuzz_lcm_message reaches every type from its
// saved corpus: fuzz/corpus/lcm_message holds a valid message of each type the schema knows.
// A new .lcm file without a seed fails here (add one: fuzz/corpus/lcm_message/<type>).
TEST(LcmSchema, TheMessageFuzzCorpusHoldsAValidMessageOfEveryType) {
  namespace fs = std::filesystem;
  const LcmSchema& schema = LcmSchema::builtIn();
  size_t files = 0;
  for (const auto& f : fs::directory_iterator(SWEEPMAP_SOURCE_DIR "/lcmtypes")) {
    files += f.path().extension() == ".lcm";
  }
  EXPECT_EQ(lcmTypeSources().size(), files);
  EXPECT_EQ(schema.structs().size(), files);
  std::set<std::string> seeded;
  for (const auto& f : fs::directory_iterator(SWEEPMAP_SOURCE_DIR "/fuzz/corpus/lcm_message")) {
    std::ifstream in(f.path(), std::ios::binary);
    const std::vector<uint8_t> b((std::istreambuf_iterator<char>(in)),
                                 std::istreambuf_iterator<char>());
    if (!schema.validate(b.data(), b.size()).empty()) continue;
    int64_t fingerprint = 0;
    for (size_t k = 0; k < 8; ++k)
      fingerprint = static_cast<int64_t>((static_cast<uint64_t>(fingerprint) << 8) | b[k]);
    seeded.insert(schema.byFingerprint(fingerprint)->name);
  }
  for (const LcmStruct& t : schema.structs()) {
    EXPECT_TRUE(seeded.count(t.name)) << t.name << ": no valid message of it in "
                                      << "fuzz/corpus/lcm_message (fuzz_lcm_message's seeds)";
  }
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
  // The constants are kept; a member whose comment names none of them is no enum.
  ASSERT_EQ(o->constants.size(), 2u);
  EXPECT_EQ(o->constants[1].name, "B");
  EXPECT_EQ(o->constants[1].value, "2");
  EXPECT_TRUE(o->members[0].enum_names.empty());
}

// An integer member is an enum of the constants of its type that its comment names (or that
// it calls "the constants"); each declaration is its own group.
TEST(LcmSchema, MembersTakeTheConstantsTheirCommentNames) {
  using Sources = std::vector<std::pair<std::string, std::string>>;
  const LcmSchema schema(
      Sources{{"e.lcm",
               "struct e_t {\n  int8_t health; // OK or BAD\n  int8_t kind; // one of the "
               "constants below\n  int32_t mode; // OK? no: int32_t\n  int8_t other;\n"
               "  const int8_t OK = 0, BAD = 0x2;\n  const int8_t RED = -1, BLUE = 5;\n}\n"}});
  const LcmStruct* e = schema.find("e_t");
  ASSERT_NE(e, nullptr);
  EXPECT_EQ(e->members[0].enum_names, (std::map<int64_t, std::string>{{0, "OK"}, {2, "BAD"}}));
  EXPECT_EQ(e->members[1].enum_names, (std::map<int64_t, std::string>{{0, "OK"}, {2, "BAD"}}));
  EXPECT_TRUE(e->members[2].enum_names.empty());  // another type
  EXPECT_TRUE(e->members[3].enum_names.empty());  // no comment
  EXPECT_THROW(LcmSchema(Sources{{"c.lcm", "struct c_t { const int8_t A = x; }"}}), LcmSchemaError);
  // The shipped types: the motor's state, a status's health, a window's action sequence.
  const LcmSchema& built = LcmSchema::builtIn();
  EXPECT_EQ(built.find("motor_state_t")->members[1].enum_names.at(4), "SCANNING");
  EXPECT_EQ(built.find("process_status_t")->members[2].enum_names.at(1), "DEGRADED");
  for (const LcmMember& m : built.find("scan_window_t")->members) {
    EXPECT_EQ(m.enum_names.empty(), m.name != "action_sequence") << m.name;
  }
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
  // A channel the log does not have: a usage error that lists those it has.
  std::ostringstream none, none_err;
  EXPECT_EQ(runDump({path, "NOPE", false, false}, none, none_err), 2);
  EXPECT_EQ(none.str(), "");
  EXPECT_EQ(none_err.str(), "sweepmap dump: --channel NOPE: no such channel in " + path +
                                "; its channels (messages): LIDAR_SCAN (1) OTHER (1) "
                                "WHEEL_TICKS (1)\n");
  // Cut the log inside its last event: the ones before are printed, then the error.
  std::filesystem::resize_file(path, std::filesystem::file_size(path) - 2);
  std::ostringstream cut, cut_err;
  EXPECT_EQ(runDump({path, "", false, false}, cut, cut_err), 1);
  EXPECT_NE(cut.str().find("WHEEL_TICKS"), std::string::npos);
  EXPECT_NE(cut_err.str().find("byte"), std::string::npos) << cut_err.str();
}

// Enum members print as their constant's name beside the number (an unknown value as "?").
TEST(Dump, EnumsByName) {
  const std::string path =
      (std::filesystem::path(SWEEPMAP_BINARY_DIR) / "test_scratch" / "dump_enums.lcmlog").string();
  std::filesystem::create_directories(std::filesystem::path(path).parent_path());
  {
    EventLogWriter w(path);
    Outbox out;
    motor_state_t m{};
    m.state = motor_state_t::SCANNING;
    m.mode = 7;
    out.publish("MOTOR_STATE", 1, m);
    m.state = 42;
    out.publish("MOTOR_STATE", 2, m);
    process_status_t s{};
    s.health = process_status_t::DEGRADED;
    out.publish("STATUS_MOTOR", 3, s);
    for (const Message& msg : out.take()) w.write(msg.utime, msg.channel, msg.data);
    w.close();
  }
  std::ostringstream human, err;
  EXPECT_EQ(runDump({path, "", false, false}, human, err), 0) << err.str();
  const std::string h = human.str();
  EXPECT_NE(h.find("  state = 4 (SCANNING)\n"), std::string::npos) << h;
  EXPECT_NE(h.find("  state = 42 (?)\n"), std::string::npos) << h;
  EXPECT_NE(h.find("  mode = 7\n"), std::string::npos) << h;  // no constants: a number
  EXPECT_NE(h.find("  health = 1 (DEGRADED)\n"), std::string::npos) << h;
  // JSON keeps the numbers (the field's type).
  std::ostringstream json;
  EXPECT_EQ(runDump({path, "STATUS_MOTOR", true, false}, json, err), 0);
  EXPECT_NE(json.str().find("\"health\":1,"), std::string::npos) << json.str();
}

// A log without a message is an error that says so.
TEST(Dump, EmptyLogIsAnError) {
  const std::string path =
      (std::filesystem::path(SWEEPMAP_BINARY_DIR) / "test_scratch" / "dump_empty.lcmlog").string();
  std::filesystem::create_directories(std::filesystem::path(path).parent_path());
  { std::ofstream(path, std::ios::trunc); }
  std::ostringstream out, err;
  EXPECT_EQ(runDump({path, "", false, false}, out, err), 1);
  EXPECT_EQ(err.str(), "sweepmap dump: " + path + " holds no message\n");
}

}  // namespace
}  // namespace sweepmap
