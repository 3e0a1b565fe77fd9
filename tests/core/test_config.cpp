#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "core/config.hpp"
#include "rigs/rotating_lidar.hpp"

namespace sweepmap {
namespace {

struct Small {
  double a = 1.5;
  int b = 2;
  bool c = true;
  std::string d = "x";
  void declare(ConfigSchema& s) {
    s.add("grp.a", &a, "m", "a length");
    s.add("grp.b", &b, "", "a count");
    s.add("c", &c, "", "a flag");
    s.add("d", &d, "", "a name");
  }
};

TEST(ConfigSchema, LoadsEveryKey) {
  Small v;
  ConfigSchema s;
  v.declare(s);
  s.loadString("grp: {a: 2.5, b: 7}\nc: false\nd: hello\n", "mem.yaml");
  EXPECT_DOUBLE_EQ(v.a, 2.5);
  EXPECT_EQ(v.b, 7);
  EXPECT_FALSE(v.c);
  EXPECT_EQ(v.d, "hello");
}

// A value of the wrong type names the key, the file and line, and the type expected (not
// std::stol's bare "stol").
TEST(ConfigSchema, BadValueSaysWhatWasExpected) {
  Small v;
  ConfigSchema s;
  v.declare(s);
  try {
    s.loadString("grp: {a: 2.5, b: many}\nc: false\nd: hello\n", "mem.yaml");
    ADD_FAILURE() << "no error";
  } catch (const ConfigError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("mem.yaml:1: key 'grp.b': bad value 'many' (expected an integer)"),
              std::string::npos)
        << what;
    EXPECT_EQ(what.find("stol"), std::string::npos) << what;
  }
  EXPECT_THROW(s.set("grp.a=wide"), ConfigError);
  EXPECT_THROW(s.set("grp.b=99999999999999"), ConfigError);
}

TEST(ConfigSchema, RejectsUnknownKeyNamingFileAndKey) {
  Small v;
  ConfigSchema s;
  v.declare(s);
  try {
    s.loadString("grp: {a: 2.5, b: 7, zz: 1}\nc: false\nd: hello\n", "mem.yaml");
    FAIL() << "unknown key accepted";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("mem.yaml"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("grp.zz"), std::string::npos) << e.what();
  }
}

TEST(ConfigSchema, RejectsMissingKeyNamingFileAndKey) {
  Small v;
  ConfigSchema s;
  v.declare(s);
  try {
    s.loadString("grp: {a: 2.5}\nc: false\nd: hello\n", "mem.yaml");
    FAIL() << "missing key accepted";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("grp.b"), std::string::npos) << e.what();
  }
}

TEST(ConfigSchema, RejectsBadValues) {
  Small v;
  ConfigSchema s;
  v.declare(s);
  EXPECT_THROW(s.set("grp.a=abc"), ConfigError);
  EXPECT_THROW(s.set("grp.a=nan"), ConfigError);
  EXPECT_THROW(s.set("grp.b=1.5"), ConfigError);
  EXPECT_THROW(s.set("c=yes"), ConfigError);
  EXPECT_THROW(s.set("nokey=1"), ConfigError);
  EXPECT_THROW(s.set("novalue"), ConfigError);
  EXPECT_THROW(s.loadString("grp: [1, 2", "broken.yaml"), ConfigError);
  s.set("grp.a=0.125");
  EXPECT_DOUBLE_EQ(v.a, 0.125);
}

TEST(ConfigSchema, YamlRoundTrip) {
  Small v;
  ConfigSchema s;
  v.declare(s);
  v.a = 0.1;
  const std::string text = s.toYaml();
  Small w;
  ConfigSchema t;
  w.declare(t);
  t.loadString(text, "roundtrip");
  EXPECT_EQ(w.a, 0.1);
  EXPECT_EQ(w.b, v.b);
  std::ostringstream printed;
  s.print(printed);
  EXPECT_NE(printed.str().find("grp.a"), std::string::npos);
  EXPECT_NE(printed.str().find("[m]"), std::string::npos);
  EXPECT_NE(printed.str().find("(default: 1.5)"), std::string::npos) << printed.str();
}

TEST(RotatingLidarConfig, ShippedRigFilesLoad) {
  for (const char* name : {"rig_a.yaml"}) {
    const std::string path = std::string(SWEEPMAP_SOURCE_DIR) + "/config/" + name;
    EXPECT_NO_THROW(loadRotatingLidarConfig(path)) << path;
  }
}

TEST(RotatingLidarConfig, ScanModesMatchTable1) {
  for (int m = 1; m <= 7; ++m) {
    const ScanMode s = scanMode(m);
    const double n = 180.0 / s.gamma_deg;                      // Eq. 1
    EXPECT_NEAR(n / 40.0, s.period_s, 1e-12) << "mode " << m;  // Eq. 2 at 40 Hz
  }
  EXPECT_THROW(scanMode(0), std::out_of_range);
  EXPECT_THROW(scanMode(8), std::out_of_range);
}

}  // namespace
}  // namespace sweepmap
