#include <gtest/gtest.h>

#include "mapping/plot.hpp"
#include "mapping/synthetic_room.hpp"
#include "mapping_test_util.hpp"

namespace sweepmap {
namespace {

using testing_util::fileBytes;
using testing_util::filesIn;
using testing_util::freshTestDir;

bool isPng(const std::string& bytes) {
  return bytes.size() > 100 && bytes.compare(0, 8, std::string("\x89PNG\r\n\x1a\n", 8)) == 0;
}

class PlotTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!gnuplotAvailable()) GTEST_SKIP() << "gnuplot is not installed";
    dir_ = freshTestDir();
  }
  std::filesystem::path dir_;
};

TEST_F(PlotTest, TopViewWritesAPng) {
  RoomSweepSpec spec;
  spec.scans = 100;
  spec.beams = 271;
  Layer room{"room 'A' (z 0.5..2.5 m)", "#1f77b4", syntheticRoomSweep(spec)};
  Layer marks{"sensor_pos", "red", {spec.sensor_m, {1.0f, 1.0f, 1.0f}}};
  PlotOptions options;
  options.title = "top view: a_b ^ c";
  options.z_band_m = PlotRange{0.5, 2.5};
  options.max_points_per_layer = 5000;     // exercises the subsampling
  const auto png = dir_ / "top view.png";  // a space in the path
  plotTopView(png.string(), {room, marks, Layer{"empty", "", {}}}, options);
  EXPECT_TRUE(isPng(fileBytes(png)));
  EXPECT_EQ(filesIn(dir_), std::vector<std::string>{"top view.png"});  // temporaries gone

  options.x_range_m = PlotRange{-1.0, 9.0};
  options.y_range_m = PlotRange{-1.0, 7.0};
  plotTopView((dir_ / "ranges.png").string(), {room}, options);
  EXPECT_TRUE(isPng(fileBytes(dir_ / "ranges.png")));
  plotTopView((dir_ / "nothing.png").string(), {}, PlotOptions{});
  EXPECT_TRUE(isPng(fileBytes(dir_ / "nothing.png")));
}

TEST_F(PlotTest, PerspectiveAndHeightColouredTopViewWriteTheSamePngTwice) {
  RoomSweepSpec spec;
  spec.scans = 60;
  spec.beams = 181;
  const Layer room{"room", "", syntheticRoomSweep(spec), true};
  const Layer path{"path", "blue", {{1.0f, 1.0f, 1.0f}, {2.0f, 1.0f, 1.0f}}};
  PerspectiveOptions options;
  options.title = "perspective";
  options.max_points_per_layer = 3000;
  plotPerspective((dir_ / "a.png").string(), {room, path}, options);
  plotPerspective((dir_ / "b.png").string(), {room, path}, options);
  EXPECT_TRUE(isPng(fileBytes(dir_ / "a.png")));
  EXPECT_EQ(fileBytes(dir_ / "a.png"), fileBytes(dir_ / "b.png"));  // deterministic
  plotPerspective((dir_ / "empty.png").string(), {Layer{"none", "", {}, true}}, options);
  EXPECT_TRUE(isPng(fileBytes(dir_ / "empty.png")));
  plotTopView((dir_ / "top.png").string(), {room, path}, PlotOptions{});
  EXPECT_TRUE(isPng(fileBytes(dir_ / "top.png")));
  EXPECT_EQ(filesIn(dir_), (std::vector<std::string>{"a.png", "b.png", "empty.png", "top.png"}));
}

TEST_F(PlotTest, SeriesWritesAPng) {
  Series line{"error [mm]", {0, 1, 2, 3}, {1.0, 0.5, 0.25, 0.125}, "linespoints", ""};
  Series hist{"histogram", {0, 1, 2, 3}, {3, 5, 2, 1}, "boxes", "gray"};
  SeriesPlotOptions options;
  options.title = "series";
  options.x_label = "iteration";
  options.y_label = "value";
  plotSeries((dir_ / "s.png").string(), {line, hist}, options);
  EXPECT_TRUE(isPng(fileBytes(dir_ / "s.png")));
  options.log_y = true;
  plotSeries((dir_ / "log.png").string(), {line}, options);
  EXPECT_TRUE(isPng(fileBytes(dir_ / "log.png")));
  EXPECT_EQ(filesIn(dir_), (std::vector<std::string>{"log.png", "s.png"}));

  EXPECT_THROW(
      plotSeries((dir_ / "x.png").string(), {Series{"bad", {1}, {1, 2}, "lines", ""}}, options),
      std::invalid_argument);
  EXPECT_THROW(
      plotSeries((dir_ / "x.png").string(), {Series{"bad", {1}, {1}, "dots!", ""}}, options),
      std::invalid_argument);
}

TEST_F(PlotTest, GnuplotFailureIsReportedAndCleanedUp) {
  Series s{"s", {0, 1}, {0, 1}, "lines", "not-a-colour"};
  try {
    plotSeries((dir_ / "bad.png").string(), {s}, SeriesPlotOptions{});
    FAIL() << "gnuplot must reject the colour";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("exited with status"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(filesIn(dir_).empty());
}

}  // namespace
}  // namespace sweepmap
