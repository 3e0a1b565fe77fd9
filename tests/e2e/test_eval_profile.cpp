// `sweepmap eval --experiment paper --rig rig_c`: Zhao 2021 Table 2 simulated (plates, both
// calibrations, test-piece scans under four settings), with a smaller repeat count than the
// paper's ten to keep the test short; report.json's structure, our accuracy bound, the wrong
// settings' direction of error, determinism, and options that do not apply.
#include <gtest/gtest.h>

#include "tests/e2e/test_support.hpp"

namespace sweepmap {
namespace test {
namespace {

const std::vector<std::string> kFeatures = {"left_diameter", "left_depth",  "right_diameter",
                                            "right_depth",   "rect_length", "rect_width",
                                            "rect_depth"};
const std::vector<std::string> kSettings = {"ours", "grid", "too_small", "too_large"};
const std::vector<std::string> kAlongScan = {"left_diameter", "right_diameter", "rect_length"};

std::vector<std::string> experiment(int repeats) {
  return {"eval",      "--experiment",          "paper",  "--rig", "rig_c",
          "--repeats", std::to_string(repeats), "--quiet"};
}

class EvalProfilePaper : public ::testing::Test {
 protected:
  void SetUp() override {
    const CachedRun run = cachedRun("eval_profile_paper", experiment(4));
    dir_ = run.out;
    ASSERT_EQ(run.status, 0) << readFile(run.output);
    report_ = readJson(dir_ / "report.json");
  }
  double errorPct(const std::string& setting, const std::string& feature) const {
    return report_["feature_error_pct"][setting][feature]["mean"].get<double>();
  }
  fs::path dir_;
  nlohmann::json report_;
};

TEST_F(EvalProfilePaper, ReportHasTheIssuesKeys) {
  for (const char* who : {"ours", "grid"}) {
    for (const char* k : {"M", "N"}) {
      EXPECT_TRUE(report_["offset_error_mm"][who][k].is_number()) << who << " " << k;
    }
    EXPECT_GT(report_["timings_s"][who].get<double>(), 0.0) << who;
  }
  for (const auto& s : kSettings) {
    for (const auto& f : kFeatures) {
      const auto& e = report_["feature_error_pct"][s][f];
      ASSERT_TRUE(e["mean"].is_number() && e["std"].is_number()) << s << " " << f << e.dump();
      EXPECT_EQ(e["count"].get<int>(), 4) << s << " " << f;
      EXPECT_EQ(report_["settings"][s]["sizes_mm"][f].size(), 4u);
    }
    EXPECT_TRUE(report_["settings"][s]["problems"].empty()) << report_["settings"][s].dump(2);
  }
  // The paper's table beside ours, and the truth from the log's TRUTH_TEST_PIECE.
  EXPECT_DOUBLE_EQ(report_["paper_table2"]["rect_length"]["cmm_mm"].get<double>(), 39.99);
  EXPECT_DOUBLE_EQ(report_["feature_truth_mm"]["left_diameter"].get<double>(), 50.01);
  EXPECT_EQ(report_["logs"].size(), 5u);
  EXPECT_TRUE(fs::exists(dir_ / "report.md"));
  for (const auto& f : report_["figures"])
    EXPECT_TRUE(fs::exists(dir_ / f.get<std::string>())) << f;
}

TEST_F(EvalProfilePaper, OursCalibratesWithinATenthOfAMillimetreAndTheGridToItsStep) {
  for (const char* k : {"M", "N"}) {
    EXPECT_LE(std::abs(report_["offset_error_mm"]["ours"][k].get<double>()), 0.1) << k;
    // The grid's answer is a node: its error is a whole number of millimetres from an
    // integer truth (123, 409).
    const double g = report_["offset_error_mm"]["grid"][k].get<double>();
    EXPECT_NEAR(g, std::round(g), 1e-9) << k;
  }
}

TEST_F(EvalProfilePaper, OurFeaturesAreWithinATenthOfAPercent) {
  for (const auto& f : kFeatures) EXPECT_LE(std::abs(errorPct("ours", f)), 0.1) << f;
  EXPECT_TRUE(report_["checks"]["ours_within_bound"].get<bool>());
}

TEST_F(EvalProfilePaper, WrongSettingsShrinkAndGrowSizesAlongTheScan) {
  for (const auto& f : kAlongScan) {
    EXPECT_LT(errorPct("too_small", f), errorPct("ours", f) - 1.0) << f;
    EXPECT_GT(errorPct("too_large", f), errorPct("ours", f) + 1.0) << f;
  }
  // Across the scan (the rectangle's width along the laser line) and in depth they stay
  // within a few tenths of a percent.
  for (const char* f : {"rect_width", "rect_depth", "left_depth", "right_depth"}) {
    EXPECT_LT(std::abs(errorPct("too_small", f)), 0.3) << f;
    EXPECT_LT(std::abs(errorPct("too_large", f)), 0.3) << f;
  }
  EXPECT_TRUE(report_["checks"]["along_scan_shrink_when_too_small"].get<bool>());
  EXPECT_TRUE(report_["checks"]["along_scan_grow_when_too_large"].get<bool>());
}

TEST_F(EvalProfilePaper, SameSeedGivesTheSameReportButItsTimings) {
  const fs::path again = scratchDir("eval_profile_again");
  std::vector<std::string> args = experiment(4);
  args.insert(args.end(), {"--out", again.string()});
  ASSERT_EQ(sweepmap(args, fs::path(again.string() + ".output.txt")), 0)
      << readFile(fs::path(again.string() + ".output.txt"));
  nlohmann::json a = report_, b = readJson(again / "report.json");
  a.erase("timings_s");
  b.erase("timings_s");
  EXPECT_EQ(a.dump(), b.dump());
  // Paths of the logs are relative to the report: the same in both directories.
  EXPECT_EQ(readFile(dir_ / "logs" / "test_piece_3.lcmlog"),
            readFile(again / "logs" / "test_piece_3.lcmlog"));
}

TEST(EvalProfileOptions, RejectsWhatDoesNotApply) {
  const fs::path dir = scratchDir("eval_profile_options");
  EXPECT_EQ(sweepmap({"eval", "--experiment", "paper", "--rig", "rig_a", "--repeats", "3", "--out",
                      (dir / "a").string()},
                     dir / "a.txt"),
            2);
  EXPECT_NE(readFile(dir / "a.txt").find("--repeats applies to rotating_profile"),
            std::string::npos)
      << readFile(dir / "a.txt");
  EXPECT_EQ(sweepmap({"eval", "--experiment", "paper", "--rig", "rig_c", "--no-naive", "--out",
                      (dir / "c").string()},
                     dir / "c.txt"),
            2);
  EXPECT_EQ(sweepmap({"eval", "--experiment", "paper", "--rig", "rig_c", "--repeats", "1", "--out",
                      (dir / "r").string()},
                     dir / "r.txt"),
            2);
}

}  // namespace
}  // namespace test
}  // namespace sweepmap
