// The exit-status convention (core/exit_codes.hpp) held by every `sweepmap` subcommand and every
// process executable: each case a new user runs into (a bad option, a missing file, a log of
// another rig kind, an empty log, an --out already taken, --force) is provoked and its status
// asserted. The statuses make a table, committed in docs/reference/exit-codes.md between its
// markers: the test fails when the two differ, and rewrites the doc's table instead with
// SWEEPMAP_UPDATE_DOCS=1. All files live in a temporary folder outside the checkout.
#include <gtest/gtest.h>
#include <stdlib.h>

#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>

#include "tests/e2e/test_support.hpp"

namespace sweepmap {
namespace test {
namespace {

// The table's columns, in order.
const std::vector<std::string> kColumns = {"--help",    "bad option",  "missing file", "wrong kind",
                                           "empty log", "--out taken", "--force"};

constexpr int kNotOurs = -100;  // recorded in the table, asserted by the command's owner

struct Case {
  std::string column;
  std::vector<std::string> args;  // after the executable (and the subcommand)
  int expected;
};

struct Row {
  std::string exe;                   // sweepmap, sweepmap-motor, ...
  std::vector<std::string> command;  // the subcommand words ({} for a process)
  std::vector<Case> cases;
};

class ExitCodes : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    char pattern[] = "/tmp/sweepmap_exit_codes_XXXXXX";
    ASSERT_NE(::mkdtemp(pattern), nullptr);
    dir_ = pattern;
    // Short logs of each kind, made once: one mode-1 sweep, a 2 s drive, rig C's plates.
    ASSERT_EQ(sweepmap({"sim", "--rig", "rig_a", "--mode", "1", "--sweeps", "1", "--out",
                        path("a.lcmlog")},
                       dir_ / "sim_a.txt"),
              0)
        << readFile(dir_ / "sim_a.txt");
    ASSERT_EQ(
        sweepmap({"sim", "--rig", "rig_b", "--set", "sim.duration_s=2", "--out", path("b.lcmlog")},
                 dir_ / "sim_b.txt"),
        0)
        << readFile(dir_ / "sim_b.txt");
    std::ofstream(dir_ / "empty.lcmlog").close();
    std::ofstream(dir_ / "empty.dat").close();
    std::ofstream(dir_ / "deploy.yaml").close();
    fs::create_directories(dir_ / "records");
    std::ofstream(dir_ / "records" / "taken.lcmlog") << "an earlier recording";
  }
  static void TearDownTestSuite() {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }

  static std::string path(const std::string& name) { return (dir_ / name).string(); }
  static std::string missing() { return path("no_such_file.yaml"); }
  // A folder holding an earlier run's file, one per case (--force empties it).
  static std::string taken(const std::string& name) {
    const fs::path p = dir_ / ("taken_" + name);
    fs::create_directories(p);
    std::ofstream(p / "earlier_run.txt") << "left by an earlier run";
    return p.string();
  }

  static fs::path dir_;
};

fs::path ExitCodes::dir_;

std::vector<std::string> cat(std::vector<std::string> a, const std::vector<std::string>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

// What the rows' cases name: the logs made once, a missing file, fresh taken folders.
struct Inputs {
  std::function<std::string(const std::string&)> path;
  std::string missing;
  std::function<std::string(const std::string&)> taken;
  std::string a, b, empty;  // a rig A log, a rig B log, an empty one
  Case help{"--help", {"--help"}, 0};
  Case bad{"bad option", {"--no-such-option"}, 2};
};

// sim, replay, demo, spy, bench, export.
std::vector<Row> offlineRows(const Inputs& in) {
  const auto& [path, missing, taken, a, b, empty, help, bad] = in;
  return {
      {"sweepmap",
       {"sim"},
       {help,
        bad,
        {"missing file", {"--rig", missing, "--out", path("s.lcmlog")}, 2},
        {"--out taken", {"--rig", "rig_a", "--mode", "1", "--out", taken("sim")}, 2}}},
      {"sweepmap",
       {"replay"},
       {help,
        bad,
        {"missing file", {path("nope.lcmlog"), "--rig", "rig_a", "--out", path("r1")}, 2},
        {"wrong kind", {b, "--rig", "rig_a", "--out", path("r2")}, 1},
        {"empty log", {empty, "--rig", "rig_a", "--out", path("r3")}, 1},
        {"--out taken", {a, "--rig", "rig_a", "--out", taken("replay")}, 2},
        {"--force",
         {a, "--rig", "rig_a", "--no-plots", "--force", "--out", taken("replay_f")},
         0}}},
      {"sweepmap",
       {"demo"},
       {help,
        bad,
        {"missing file", {"--rig", missing, "--out", path("d1")}, 2},
        {"--out taken", {"--out", taken("demo")}, 2}}},
      {"sweepmap", {"spy"}, {help, bad}},
      {"sweepmap", {"bench"}, {help, bad, {"missing file", {"--rig", missing}, 2}}},
      {"sweepmap",
       {"export", "mcap"},
       {help,
        bad,
        {"missing file", {path("nope.lcmlog"), "--rig", "rig_a", "--out", path("x.mcap")}, 2},
        {"empty log", {empty, "--rig", "rig_a", "--out", path("e.mcap")}, 1},
        {"--out taken", {a, "--rig", "rig_a", "--out", taken("export_mcap")}, 2}}},
      {"sweepmap",
       {"export", "las"},
       {help,
        bad,
        {"missing file", {path("nope.ply"), "--out", path("x.las")}, 2},
        {"empty log", {empty, "--out", path("e.las")}, 1},
        {"--out taken", {a, "--out", taken("export_las")}, 2}}},
  };
}

// calib (each kind) and eval.
std::vector<Row> calibEvalRows(const Inputs& in) {
  const auto& [path, missing, taken, a, b, empty, help, bad] = in;
  return {
      {"sweepmap",
       {"calib", "plate-angle"},
       {help,
        bad,
        {"missing file",
         {"--logs", path("nope.lcmlog"), "--rig", "rig_a", "--out", path("p.yaml")},
         2},
        {"wrong kind", {"--logs", b, "--rig", "rig_a", "--out", path("p.yaml")}, 1},
        {"empty log", {"--logs", empty, "--rig", "rig_a", "--out", path("p.yaml")}, 1},
        {"--out taken", {"--logs", a, "--rig", "rig_a", "--out", taken("plate")}, 2}}},
      {"sweepmap",
       {"calib", "mounting"},
       {help,
        bad,
        {"missing file",
         {"--logs", path("nope.lcmlog"), "--rig", "rig_b", "--out", path("m.yaml")},
         2},
        {"wrong kind", {"--logs", a, "--rig", "rig_b", "--out", path("m.yaml")}, 1},
        {"empty log", {"--logs", empty, "--rig", "rig_b", "--out", path("m.yaml")}, 1},
        {"--out taken", {"--logs", b, "--rig", "rig_b", "--out", taken("mounting")}, 2}}},
      {"sweepmap",
       {"calib", "axis-offset"},
       {help,
        bad,
        {"missing file",
         {"--logs", path("nope.lcmlog"), "--rig", "rig_c", "--out", path("x.yaml")},
         2},
        {"wrong kind", {"--logs", b, "--rig", "rig_c", "--out", path("x.yaml")}, 1},
        {"empty log", {"--logs", empty, "--rig", "rig_c", "--out", path("x.yaml")}, 1},
        {"--out taken", {"--logs", a, "--rig", "rig_a", "--out", taken("axis")}, 2}}},
      {"sweepmap",
       {"calib", "rig"},
       {help,
        bad,
        {"missing file",
         {"--logs", path("nope.lcmlog"), "--rig", "rig_a", "--out", path("r.yaml")},
         2},
        {"wrong kind", {"--logs", b, "--rig", "rig_a", "--out", path("r.yaml")}, 1},
        {"empty log", {"--logs", empty, "--rig", "rig_a", "--out", path("r.yaml")}, 1},
        {"--out taken", {"--logs", a, "--rig", "rig_a", "--out", taken("rig")}, 2}}},
      {"sweepmap", {"calib", "plan"}, {help, bad, {"missing file", {"--rig", missing}, 2}}},
      {"sweepmap",
       {"eval"},
       {help,
        bad,
        {"missing file", {"--logs", path("nope.lcmlog"), "--rig", "rig_a", "--out", path("e1")}, 2},
        {"wrong kind", {"--logs", b, "--rig", "rig_a", "--no-plots", "--out", path("e2")}, 1},
        {"empty log", {"--logs", empty, "--rig", "rig_a", "--no-plots", "--out", path("e3")}, 1},
        {"--out taken", {"--logs", a, "--rig", "rig_a", "--out", taken("eval")}, 2},
        {"--force",
         {"--logs", a, "--rig", "rig_a", "--no-plots", "--force", "--out", taken("eval_f")},
         0}}},
  };
}

// import, emulate, capture, decode, dump, status, record, systemd, launch, view.
std::vector<Row> deviceAndOpsRows(const Inputs& in) {
  const auto& [path, missing, taken, a, b, empty, help, bad] = in;
  return {
      {"sweepmap",
       {"import", "breezyslam"},
       {help,
        bad,
        {"missing file", {path("nope.dat"), "--out", path("i.lcmlog")}, 2},
        {"empty log", {path("empty.dat"), "--out", path("i.lcmlog")}, 1},
        {"--out taken", {path("empty.dat"), "--out", taken("import")}, 2}}},
      {"sweepmap",
       {"emulate"},
       {help, bad, {"missing file", {"ust10lx", "--rig", missing, "--duration", "0.1"}, 2}}},
      {"sweepmap",
       {"capture"},
       {help,
        bad,
        {"missing file", {"scip://127.0.0.1:9", "--rig", missing, "--out", path("c.cap")}, 2},
        {"--out taken", {"scip://127.0.0.1:9", "--out", taken("capture")}, 2}}},
      {"sweepmap",
       {"decode"},
       {help,
        bad,
        {"missing file", {"scip", path("nope.cap"), "--out", path("d.lcmlog")}, 2},
        // Bytes of another kind (an LCM log as X4 bytes): no message decoded.
        {"wrong kind", {"x4", a, "--out", path("d.lcmlog")}, 1},
        {"empty log", {"scip", empty, "--out", path("d.lcmlog")}, 1},
        {"--out taken", {"scip", empty, "--out", taken("decode")}, 2}}},
      {"sweepmap",
       {"dump"},
       {help, bad, {"missing file", {path("nope.lcmlog")}, 2}, {"empty log", {empty}, kNotOurs}}},
      {"sweepmap", {"status"}, {help, bad}},
      {"sweepmap",
       {"record"},
       {help,
        bad,
        {"--out taken",
         {"--out", path("records"), "--name", "taken.lcmlog", "--duration", "1"},
         2}}},
      {"sweepmap",
       {"systemd"},
       {help,
        bad,
        {"missing file", {path("nope.yaml"), "--host", "pi", "--out", path("units")}, 2}}},
      {"sweepmap", {"launch"}, {help, bad, {"missing file", {path("nope.yaml")}, 2}}},
      {"sweepmap",
       {"view"},
       {help,
        bad,
        {"missing file", {path("nope.lcmlog"), "--port", "0"}, 2},
        {"missing rig", {"--rig", missing, "--port", "0"}, 2}}},
  };
}

// The processes' rows: a rig of a kind they do not take is the wrong kind.
std::vector<Row> processRows(const std::string& missing) {
  const Case help{"--help", {"--help"}, 0};
  const Case bad{"bad option", {"--rig", "rig_a", "--no-such-option"}, 2};
  const Case miss{"missing file", {"--rig", missing}, 2};
  const auto wrong = [](const std::string& rig) { return Case{"wrong kind", {"--rig", rig}, 2}; };
  return {
      {"sweepmap-motor", {}, {help, bad, miss, wrong("rig_b")}},
      {"sweepmap-lidar", {}, {help, bad, miss, wrong("rig_c")}},
      {"sweepmap-odometry", {}, {help, bad, miss, wrong("rig_a")}},
      {"sweepmap-assembler", {}, {help, bad, miss}},
      {"sweepmap-mapper", {}, {help, bad, miss}},
      {"sweepmap-profiler", {}, {help, bad, miss, wrong("rig_a")}},
  };
}

std::string rowName(const Row& r) {
  std::string name = r.exe;
  for (const auto& w : r.command) name += " " + w;
  return name;
}

// The markdown table: one row per command, one column per case ("—": not applicable).
std::string table(const std::vector<Row>& rows, const std::map<std::string, int>& codes) {
  std::ostringstream t;
  t << "| command |";
  for (const auto& c : kColumns) t << " " << c << " |";
  t << "\n| --- |";
  for (size_t i = 0; i < kColumns.size(); ++i) t << " --- |";
  t << "\n";
  for (const Row& r : rows) {
    t << "| `" << rowName(r) << "` |";
    for (const auto& c : kColumns) {
      const auto it = codes.find(rowName(r) + "\t" + c);
      t << " " << (it == codes.end() ? "—" : std::to_string(it->second)) << " |";
    }
    t << "\n";
  }
  return t.str();
}

// The doc's text with the table between the markers replaced by `t`.
std::string withTable(const std::string& doc, const std::string& t, std::string* current) {
  const std::string begin = "<!-- exit-code-table:begin -->\n",
                    end = "<!-- exit-code-table:end -->";
  const size_t b = doc.find(begin), e = doc.find(end);
  if (b == std::string::npos || e == std::string::npos || e < b) return "";
  *current = doc.substr(b + begin.size(), e - b - begin.size());
  return doc.substr(0, b + begin.size()) + t + doc.substr(e);
}

TEST_F(ExitCodes, EveryCommandAndProcessFollowsTheConvention) {
  Inputs in;
  in.path = [](const std::string& n) { return path(n); };
  in.missing = missing();
  in.taken = [](const std::string& n) { return taken(n); };
  in.a = path("a.lcmlog");
  in.b = path("b.lcmlog");
  in.empty = path("empty.lcmlog");
  std::vector<Row> rows;
  for (const auto& part :
       {offlineRows(in), calibEvalRows(in), deviceAndOpsRows(in), processRows(missing())}) {
    rows.insert(rows.end(), part.begin(), part.end());
  }
  std::map<std::string, int> codes;
  int n = 0;
  for (const Row& r : rows) {
    for (const Case& c : r.cases) {
      const fs::path out = dir_ / ("case_" + std::to_string(n++) + ".txt");
      const int code = runIn(dir_, r.exe, cat(r.command, c.args), out);
      codes[rowName(r) + "\t" + c.column] = code;
      if (c.expected != kNotOurs) {
        EXPECT_EQ(code, c.expected) << rowName(r) << " (" << c.column << "): " << readFile(out);
      }
    }
  }
  const std::string doc_path = sourcePath("docs/reference/exit-codes.md");
  const std::string doc = readFile(doc_path), generated = table(rows, codes);
  std::string committed;
  const std::string updated = withTable(doc, generated, &committed);
  ASSERT_FALSE(updated.empty()) << doc_path << ": no exit-code-table markers";
  if (const char* env = std::getenv("SWEEPMAP_UPDATE_DOCS"); env && std::string(env) == "1") {
    std::ofstream(doc_path) << updated;
    return;
  }
  EXPECT_EQ(committed, generated) << doc_path
                                  << " is stale: rerun with SWEEPMAP_UPDATE_DOCS=1 to rewrite it";
}

TEST_F(ExitCodes, ForceEmptiesTheFolderFirst) {
  const std::string out = taken("force_check");
  ASSERT_EQ(sweepmap({"replay", path("a.lcmlog"), "--rig", "rig_a", "--no-plots", "--force",
                      "--out", out},
                     dir_ / "force.txt"),
            0)
      << readFile(dir_ / "force.txt");
  EXPECT_FALSE(fs::exists(fs::path(out) / "earlier_run.txt"));
  EXPECT_TRUE(fs::exists(fs::path(out) / "summary.json"));
}

TEST_F(ExitCodes, ErrorsSayWhatWasExpectedAndGiveTheFix) {
  const fs::path o = dir_ / "messages.txt";
  EXPECT_EQ(sweepmap({"replay", path("b.lcmlog"), "--rig", "rig_a", "--out", path("m1")}, o), 1);
  std::string said = readFile(o);
  EXPECT_NE(said.find("needs SCAN_WINDOW + LIDAR_SCAN"), std::string::npos) << said;
  EXPECT_NE(said.find("WHEEL_TICKS x"), std::string::npos) << said;
  EXPECT_NE(said.find("--rig rig_b"), std::string::npos) << said;

  EXPECT_EQ(sweepmap({"replay", path("a.lcmlog"), "--rig", "rig_a", "--out", taken("m2")}, o), 2);
  said = readFile(o);
  EXPECT_NE(said.find("--force"), std::string::npos) << said;
  EXPECT_NE(said.find("taken_m2"), std::string::npos) << said;

  EXPECT_EQ(sweepmap({"sim", "--rig", "rig_d", "--out", path("x.lcmlog")}, o), 2);
  said = readFile(o);
  EXPECT_NE(said.find("rig_a, "), std::string::npos) << said;  // the rigs there are

  EXPECT_EQ(
      sweepmap({"sim", "--rig", "rig_a", "--scene", "scene_nope", "--out", path("x.lcmlog")}, o),
      2);
  said = readFile(o);
  EXPECT_NE(said.find("scene_lab"), std::string::npos) << said;  // the scenes there are

  EXPECT_EQ(
      sweepmap({"sim", "--rig", "rig_a", "--set", "motor.mode=9", "--out", path("x.lcmlog")}, o),
      2);
  said = readFile(o);
  EXPECT_NE(said.find("--set motor.mode=9"), std::string::npos) << said;

  EXPECT_EQ(sweepmap({"sim", "--rig", "rig_a", "--sweeps", "0", "--out", path("x.lcmlog")}, o), 2);
  said = readFile(o);
  EXPECT_NE(said.find("at least 1"), std::string::npos) << said;
  EXPECT_LT(said.size(), 400u) << said;  // no 300-digit range
}

TEST_F(ExitCodes, VersionAndAHelpThatFitsAScreen) {
  for (const std::string exe : {"sweepmap", "sweepmap-motor", "sweepmap-lidar", "sweepmap-odometry",
                                "sweepmap-assembler", "sweepmap-mapper", "sweepmap-profiler"}) {
    const fs::path o = dir_ / (exe + "_version.txt");
    EXPECT_EQ(runIn({}, exe, {"--version"}, o), 0) << exe;
    const std::string said = readFile(o);
    EXPECT_NE(said.find(exe + " 0."), std::string::npos) << said;
    EXPECT_NE(said.find("(git "), std::string::npos) << said;
  }
  const fs::path o = dir_ / "help.txt";
  EXPECT_EQ(sweepmap({"--help"}, o), 0);
  const std::string help = readFile(o);
  EXPECT_LE(std::count(help.begin(), help.end(), '\n'), 40) << help;
  for (const std::string c : {"sim", "replay", "calib", "eval", "status", "launch"}) {
    EXPECT_NE(help.find("\n  " + c + " "), std::string::npos) << c << "\n" << help;
  }
  // Each process's --rig names only the kinds it takes.
  EXPECT_EQ(runIn({}, "sweepmap-profiler", {"--help"}, o), 0);
  EXPECT_EQ(readFile(o).find("rig_a"), std::string::npos) << readFile(o);
  EXPECT_EQ(runIn({}, "sweepmap-motor", {"--help"}, o), 0);
  EXPECT_EQ(readFile(o).find("rig_b"), std::string::npos) << readFile(o);
}

}  // namespace
}  // namespace test
}  // namespace sweepmap
