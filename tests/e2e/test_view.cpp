// `sweepmap view` in real browsers (Debian's chromium, headless, and firefox-esr, on its own
// Xvfb display; both driven by puppeteer-core from tests/js): live, inside a private network
// namespace with rig A's processes, beside a client that connects and then stops reading; and
// from a log, through its time slider. Every test runs once per browser. The node scripts
// report what the page shows as JSON; this file judges it.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <set>

#include "core/event_log.hpp"
#include "core/lcm_schema.hpp"
#include "processes/channels.hpp"
#include "processes/message_codec.hpp"
#include "sim/scene.hpp"
#include "sweepmap/cloud_chunk_t.hpp"
#include "sweepmap/map_stats_t.hpp"
#include "tests/e2e/fixtures.hpp"

namespace sweepmap {
namespace test {
namespace {

const std::string kRig = sourcePath("config/rig_a.yaml");
const std::string kScene = sourcePath("config/scene_conference_room.yaml");
const std::string kUrl = kDefaultLcmUrl;
constexpr int kPort = 8080;   // inside the test's own network namespace
const double kVoxelM = 0.05;  // rig_a.yaml's mapper.resolution_m

// Why the browser tests cannot run in `browser` here ("" when they can).
std::string browserMissing(const std::string& browser) {
  const std::vector<std::string> needs =
      browser == "firefox" ? std::vector<std::string>{"/usr/bin/firefox-esr", "/usr/bin/Xvfb"}
                           : std::vector<std::string>{"/usr/bin/chromium"};
  for (const std::string& program : needs) {
    if (!fs::exists(program)) return "no " + program + " (tools/ops/setup.sh)";
  }
  if (!fs::exists(sourcePath("tests/js/node_modules/puppeteer-core"))) {
    return "no tests/js/node_modules (tools/ops/setup.sh installs it)";
  }
  return "";
}

// The last line of a node script's output that is a JSON object.
nlohmann::json lastJson(const std::string& said) {
  const size_t at = said.rfind("\n{");
  const std::string line = said.substr(at == std::string::npos ? 0 : at + 1);
  return nlohmann::json::parse(line.substr(0, line.find('\n')), nullptr, false);
}

// A TCP connection to the port that becomes a /ws WebSocket and then never reads: a page whose
// tab hangs. Its receive buffer is made small, so the server meets the stall early.
class StalledClient {
 public:
  explicit StalledClient(int port) {
    fd_ = ::socket(AF_INET, SOCK_STREAM, 0);
    const int small = 4096;
    ::setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &small, sizeof(small));
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(port);
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    connected_ = ::connect(fd_, reinterpret_cast<sockaddr*>(&a), sizeof(a)) == 0;
    const std::string upgrade =
        "GET /ws HTTP/1.1\r\nHost: 127.0.0.1\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
        "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n";
    connected_ = connected_ && ::send(fd_, upgrade.data(), upgrade.size(), 0) ==
                                   static_cast<ssize_t>(upgrade.size());
  }
  ~StalledClient() { ::close(fd_); }
  bool connected() const { return connected_; }

 private:
  int fd_ = -1;
  bool connected_ = false;
};

// Waits (polling every 0.1 s) until `done`; false after timeout_s.
bool waitUntil(const std::function<bool()>& done, double timeout_s) {
  for (double t = 0; t < timeout_s; t += 0.1) {
    if (done()) return true;
    sleepS(0.1);
  }
  return false;
}

// Waits until something listens on the port (the view is up).
bool waitForPort(int port, double timeout_s) {
  return waitUntil(
      [port] {
        const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
        sockaddr_in a{};
        a.sin_family = AF_INET;
        a.sin_port = htons(port);
        a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
        const bool ok = ::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof(a)) == 0;
        ::close(fd);
        return ok;
      },
      timeout_s);
}

// The browser under test is the parameter ("chromium" or "firefox": tests/js/browser.js).
class ViewTest : public PrivateNetworkTest, public ::testing::WithParamInterface<std::string> {
 protected:
  void SetUp() override {
    PrivateNetworkTest::SetUp();
    if (const std::string why = browserMissing(GetParam()); !why.empty()) GTEST_SKIP() << why;
  }
  // `node tests/js/SCRIPT ARGS` with the browser under test.
  std::vector<std::string> nodeCommand(const std::string& script,
                                       const std::vector<std::string>& args) const {
    std::vector<std::string> argv = {"env", "SWEEPMAP_BROWSER=" + GetParam(), "node",
                                     sourcePath("tests/js/" + script)};
    argv.insert(argv.end(), args.begin(), args.end());
    return argv;
  }
  // `sweepmap view ARGS --port kPort`, up and listening.
  pid_t startView(const std::vector<std::string>& args) {
    std::vector<std::string> argv = {binPath("sweepmap"), "view", "--port", std::to_string(kPort)};
    argv.insert(argv.end(), args.begin(), args.end());
    const pid_t view = procs.start("view", argv);
    EXPECT_TRUE(waitForPort(kPort, 10.0)) << procs.said("view");
    return view;
  }
  nlohmann::json runNode(const std::string& script, const std::vector<std::string>& args,
                         double timeout_s) {
    const pid_t node = procs.start("node", nodeCommand(script, args));
    EXPECT_EQ(procs.wait(node, timeout_s), 0) << procs.said("node");
    return lastJson(procs.said("node"));
  }
  Launcher procs;
};

// Where a surface bounds the room on each side of each axis, in frame O (the rig's axis at the
// scene's rig position, yaw 0): [nearest, farthest] per axis and side. One plane per side but
// +Y, where the door leaf stands door_depth_m behind the wall: a quantile of the points there
// lies anywhere from the wall through the recess's sides to the leaf, as the door's share of
// the points (which sweeps the page holds, how they were thinned) puts it.
struct Bound {
  double nearest, farthest;
};
std::array<std::array<Bound, 2>, 3> roomInFrameO() {
  const SceneConfig s = loadScene(kScene);
  const double x_min = -s.room_length_m / 2 - s.rig_x_m, x_max = s.room_length_m / 2 - s.rig_x_m;
  const double y_min = -s.room_width_m / 2 - s.rig_y_m, y_max = s.room_width_m / 2 - s.rig_y_m;
  const double z_min = -s.rig_z_m, z_max = s.room_height_m - s.rig_z_m;
  return {{{{{x_min, x_min}, {x_max, x_max}}},
           {{{y_min, y_min}, {y_max, y_max + s.door_depth_m}}},
           {{{z_min, z_min}, {z_max, z_max}}}}};
}

// The q-quantile per axis of every point the assembler published (the log's SWEEP_CLOUD), as
// the page computes it (view.js: sorted float coordinates, index floor(q n)).
std::array<double, 3> publishedQuantile(const Chunks& chunks, double q) {
  std::array<std::vector<float>, 3> axes;
  for (const auto& [key, bytes] : chunks) {
    cloud_chunk_t c;
    EXPECT_TRUE(decodeMessage(bytes.data(), bytes.size(), &c));
    for (const auto& p : c.xyz_m) {
      for (int a = 0; a < 3; ++a) axes[a].push_back(p[a]);
    }
  }
  std::array<double, 3> out{};
  for (int a = 0; a < 3; ++a) {
    std::sort(axes[a].begin(), axes[a].end());
    const size_t n = axes[a].size();
    out[a] = n ? axes[a][std::min(n - 1, static_cast<size_t>(q * n))] : NAN;
  }
  return out;
}

// The drawn extent (1 % and 99 % quantiles per axis: the surfaces, not the range noise's
// tail) lies on the room's bounding surfaces, within a voxel; and it is the published
// points' extent: between their 0.5 % and 2 % quantiles (a page drops a share of the older
// sweeps' points when over its budget, which moves a quantile by rank, not by metres).
void expectRoomExtent(const nlohmann::json& extent, const Chunks& published) {
  const auto room = roomInFrameO();
  const auto low_in = publishedQuantile(published, 0.02),
             low_out = publishedQuantile(published, 0.005);
  const auto high_in = publishedQuantile(published, 0.98);
  const auto high_out = publishedQuantile(published, 0.995);
  for (int a = 0; a < 3; ++a) {
    for (int side = 0; side < 2; ++side) {
      const double drawn = extent[a][side].get<double>();
      const auto [nearest, farthest] = room[a][side];
      const std::string where = "axis " + std::to_string(a) + (side ? " max" : " min");
      EXPECT_GE(drawn, std::min(nearest, farthest) - kVoxelM) << where;
      EXPECT_LE(drawn, std::max(nearest, farthest) + kVoxelM) << where;
      const double inner = side ? high_in[a] : low_in[a], outer = side ? high_out[a] : low_out[a];
      EXPECT_GE(drawn, std::min(inner, outer)) << where;
      EXPECT_LE(drawn, std::max(inner, outer)) << where;
    }
  }
}

std::vector<uint8_t> fromHex(const std::string& hex) {
  std::vector<uint8_t> out;
  for (size_t i = 0; i + 1 < hex.size(); i += 2) {
    out.push_back(static_cast<uint8_t>(std::stoi(hex.substr(i, 2), nullptr, 16)));
  }
  return out;
}

// A raw LCM channel as the reference client saw it (`c` advertised, `t` received): on
// /lcm/CHANNEL, named by its LCM type with the type's .lcm text as the schema, and its first
// message a whole valid message of that type (the type's fingerprint in its first 8 bytes, its
// length what its counts and strings make: validate() leaves no byte over or missing).
void expectRawLcm(const nlohmann::json& c, const nlohmann::json& t) {
  const std::string topic = c["topic"];
  EXPECT_EQ(topic.rfind("/lcm/", 0), 0u) << topic;
  EXPECT_EQ(c["schemaEncoding"], "lcm") << topic;
  const LcmSchema& lcm = LcmSchema::builtIn();
  const LcmStruct* type = lcm.find(c["schemaName"].get<std::string>());
  ASSERT_NE(type, nullptr) << topic << ": " << c["schemaName"];
  EXPECT_EQ(c["schemaName"], type->package + "." + type->name) << topic;
  EXPECT_EQ(c["schema"], lcmTypeSource(*type)) << topic;
  if (t["messages"].get<int>() == 0) return;
  const std::vector<uint8_t> first = fromHex(t["first_hex"].get<std::string>());
  EXPECT_EQ(lcm.typeOf(first.data(), first.size()), type) << topic;
  EXPECT_EQ(lcm.validate(first.data(), first.size()), "") << topic;
  EXPECT_GE(first.size(), t["min_bytes"].get<size_t>()) << topic;
  EXPECT_LE(first.size(), t["max_bytes"].get<size_t>()) << topic;
}

// What the reference Foxglove client (tests/js/foxglove_client.js) saw: the server's info, every
// converted channel advertised in JSON with the schema @foxglove/schemas publishes for its name,
// every raw LCM channel as expectRawLcm says, messages on each of `topics`, and every JSON
// message valid against its schema.
void expectFoxglove(const nlohmann::json& fox, const std::vector<std::string>& topics) {
  ASSERT_TRUE(fox.is_object());
  EXPECT_TRUE(fox["errors"].empty()) << fox["errors"];
  EXPECT_EQ(fox["server_info"]["op"], "serverInfo");
  ASSERT_FALSE(fox["channels"].empty());
  for (const auto& c : fox["channels"]) {
    if (c["encoding"] == "lcm") {
      expectRawLcm(c, fox["topics"][c["topic"].get<std::string>()]);
      continue;
    }
    EXPECT_EQ(c["encoding"], "json") << c;
    EXPECT_EQ(c["schemaEncoding"], "jsonschema") << c;
    const auto& t = fox["topics"][c["topic"].get<std::string>()];
    EXPECT_TRUE(t["schema_matches_published"].get<bool>()) << c;
    EXPECT_TRUE(t["problems"].empty()) << c["topic"] << ": " << t["problems"];
  }
  for (const std::string& topic : topics) {
    EXPECT_GT(fox["topics"][topic]["messages"].get<int>(), 0) << topic;
  }
}

// The page's colour mode `mode` (tests/js/view_live.js's sample: [value, hue] per point): the
// hue falls as the value rises (view.js's ramp: blue for the lowest, red for the highest), and
// the sample spans more than one colour.
void expectHueFollows(const nlohmann::json& samples, const std::string& mode) {
  std::vector<std::pair<double, double>> v;
  for (const auto& p : samples) {
    ASSERT_TRUE(p[0].is_number()) << mode << ": a point without its value: " << p;
    v.emplace_back(p[0].get<double>(), p[1].get<double>());
  }
  ASSERT_GT(v.size(), 50u) << mode;
  std::sort(v.begin(), v.end());
  size_t bluer = 0;  // points drawn bluer than a lower value
  std::string first;
  for (size_t i = 1; i < v.size(); ++i) {
    if (v[i].second <= v[i - 1].second + 1e-3) continue;
    if (bluer++ == 0) {
      first = std::to_string(v[i].first) + " drawn bluer than " + std::to_string(v[i - 1].first);
    }
  }
  EXPECT_EQ(bluer, 0u) << mode << " of " << v.size() << " points, e.g. " << first;
  EXPECT_GT(v.front().second - v.back().second, 0.2) << mode << ": one colour for all";
}

// The voxels are the mapper's OctoMap (MAP_UPDATE), not the cloud points': the view's set has
// the mapper's occupied count (MAP_STATS), and so has the page's when it lost no frame; the
// Foxglove client's last /map holds as many voxel centres as the mapper had after one of its
// updates (the counts MAP_STATS published, in the log).
void expectMapperVoxels(const nlohmann::json& page, const nlohmann::json& fox,
                        const std::string& log) {
  const nlohmann::json& status = page["status"];
  const nlohmann::json& vm = status["board"]["view_model"];
  const int64_t mapper = status["board"]["mapper"]["occupied_voxels"].get<int64_t>();
  EXPECT_EQ(vm["voxel_source"], "mapper") << vm;
  EXPECT_EQ(page["voxel_source"], "mapper");
  EXPECT_EQ(vm["map_updates_invalid"], 0) << vm;
  EXPECT_EQ(vm["map_update_gaps"], 0) << vm;
  EXPECT_GT(mapper, 0);
  EXPECT_EQ(vm["voxels"].get<int64_t>(), mapper) << vm;
  EXPECT_EQ(vm["mapper_occupied_voxels"].get<int64_t>(), mapper) << vm;
  if (status["you"]["frames_dropped"].get<int64_t>() == 0) {
    EXPECT_EQ(page["voxels"].get<int64_t>(), mapper);
  }
  std::set<int64_t> counts;
  for (const Message& m : readChannel(log, channels::kMapStats)) {
    map_stats_t st;
    if (decodeMessage(m, &st)) counts.insert(st.occupied_voxels);
  }
  const nlohmann::json& map = fox["topics"]["/map"];
  ASSERT_TRUE(map.contains("points") && !map["points"].empty()) << map;
  EXPECT_TRUE(counts.count(map["points"].back().get<int64_t>()))
      << "/map's last " << map["points"].back() << " voxels are no count the mapper had";
}

// Rig A's processes in mode 2 (4 sweeps, ~5 MB of clouds and voxels) with the view, a page,
// a stalled client and a Foxglove client: the page draws every point the server says it sent
// it and shows the room, while the stalled client's frames are dropped and counted, the view
// still takes every chunk the assembler published, and the Foxglove client gets valid messages.
TEST_P(ViewTest, LivePageShowsTheSweepsBesideAStalledClient) {
  const auto dir = scratchDir("view_live_" + GetParam());
  procs.setDir(dir);
  const ProcessCommand proc{{"--rig", kRig, "--set", "motor.mode=2", "--lcm-url", kUrl}};
  const std::string log = (dir / "live.lcmlog").string();
  const pid_t logger = procs.startSubscriber(
      "logger", loggerCommand(kUrl, log, "SWEEP_CLOUD|MAP_STATS"), kDefaultLcmPort);
  const pid_t view = startView({"--lcm-url", kUrl, "--rig", kRig, "--client-queue-mb", "2"});
  const pid_t mapper = procs.startSubscriber("mapper", proc("mapper"), kDefaultLcmPort);
  const pid_t assembler = procs.startSubscriber("assembler", proc("assembler"), kDefaultLcmPort);
  const pid_t lidar = procs.startSubscriber(
      "lidar", proc("lidar", {"--sim", "--scene", kScene, "--seed", "4"}), kDefaultLcmPort);
  StalledClient stalled(kPort);
  ASSERT_TRUE(stalled.connected());
  const std::string shot = (dir / "live.png").string();
  const pid_t node =
      procs.start("node", nodeCommand("view_live.js", {"http://127.0.0.1:8080/", "4", "80", shot}));
  const std::vector<std::string> topics = {"/sweep_cloud",     "/map",           "/tf",
                                           "/lidar_scan",      "/status",        "/lcm/LIDAR_SCAN",
                                           "/lcm/SWEEP_CLOUD", "/lcm/MAP_UPDATE"};
  std::vector<std::string> foxglove_args = {"node", sourcePath("tests/js/foxglove_client.js"),
                                            "ws://127.0.0.1:8080/", "80"};
  foxglove_args.insert(foxglove_args.end(), topics.begin(), topics.end());
  const pid_t foxglove = procs.start("foxglove", foxglove_args);
  // The sweeps start once the page is connected: a browser that starts slowly (Firefox and its
  // display take seconds) would otherwise get the sweeps made so far as one snapshot larger
  // than its 2 MiB queue, and lose part of it.
  ASSERT_TRUE(
      waitUntil([&] { return procs.said(node).find("page connected") != std::string::npos; }, 60))
      << procs.said(node);
  sleepS(0.7);
  const pid_t motor =
      procs.start("motor", proc("motor", {"--sim", "--sweeps", "4", "--seed", "4"}));
  ASSERT_EQ(procs.wait(motor, 90.0), 0) << procs.said(motor);
  ASSERT_EQ(procs.wait(node, 90.0), 0) << procs.said(node);
  ASSERT_EQ(procs.wait(foxglove, 90.0), 0) << procs.said(foxglove);
  procs.stopInOrder({{lidar, 5.0}, {assembler, 10.0}, {mapper, 30.0}, {logger, 10.0}, {view, 10.0}},
                    0.5);

  const nlohmann::json page = lastJson(procs.said(node));
  ASSERT_TRUE(page.is_object()) << procs.said(node);
  ASSERT_FALSE(page.contains("failure")) << page["failure"] << "\n" << page["at_failure"].dump();
  EXPECT_TRUE(page["errors"].empty()) << page["errors"];
  EXPECT_EQ(page["mode"], "live");
  EXPECT_EQ(page["sweeps"], 4);
  // What the page draws is what the server sent it (after its thinning arithmetic).
  EXPECT_EQ(page["check"]["drawn"], page["check"]["server"]);
  EXPECT_EQ(page["points_drawn"], page["check"]["server"]);
  EXPECT_GT(page["points_drawn"].get<int64_t>(), 0);
  EXPECT_GT(page["non_blank"].get<double>(), 0.02) << "the screenshot is (nearly) blank";
  const Chunks published = chunksOf(log);
  expectRoomExtent(page["extent"], published);
  const nlohmann::json& status = page["status"];
  // The stalled client's frames were dropped and counted. (The page may lose frames too when
  // the machine is too loaded for its renderer to keep up: that is the same rule, and the
  // page still draws exactly what it was sent, checked above.)
  EXPECT_GT(status["view"]["frames_dropped_all"].get<int64_t>(), 0) << status["view"];
  // The view took every chunk the assembler published: its intake was not held up.
  EXPECT_EQ(status["board"]["view_model"]["chunks"].get<size_t>(), published.size());
  EXPECT_EQ(status["board"]["mapper"]["sweeps"], 4);
  const nlohmann::json fox = lastJson(procs.said(foxglove));
  expectFoxglove(fox, topics);
  // The raw channel's bytes are those the assembler published (its chunks in the log).
  const auto& raw_cloud = fox["topics"]["/lcm/SWEEP_CLOUD"];
  if (raw_cloud["messages"].get<int>() > 0) {
    const std::vector<uint8_t> first = fromHex(raw_cloud["first_hex"].get<std::string>());
    EXPECT_TRUE(std::any_of(published.begin(), published.end(), [&](const auto& chunk) {
      return chunk.second == first;
    })) << "the first /lcm/SWEEP_CLOUD message is no chunk the assembler published";
  }
  expectMapperVoxels(page, fox, log);
  // Colour by intensity (the simulated UST measures it) and back by height.
  ASSERT_TRUE(page.contains("colour")) << page.dump();
  const nlohmann::json& colour = page["colour"];
  EXPECT_EQ(colour["initial"], "height");
  EXPECT_TRUE(colour["available"].get<bool>()) << "the intensity option stayed disabled";
  EXPECT_TRUE(colour["intensity_set"].get<bool>());
  EXPECT_TRUE(colour["height_set"].get<bool>());
  expectHueFollows(colour["intensity"], "intensity");
  expectHueFollows(colour["height"], "height");
}

// A replayed log (two mode-1 sweeps): moving the time slider to the end shows both sweeps and
// the mapper's final voxels, back to the start none, between the two sweeps' clouds one.
TEST_P(ViewTest, TimeSliderReplaysALog) {
  const auto dir = scratchDir("view_log_" + GetParam());
  procs.setDir(dir);
  const std::string sim = (dir / "sim.lcmlog").string();
  ASSERT_EQ(sweepmap({"sim", "--rig", kRig, "--scene", kScene, "--mode", "1", "--sweeps", "2",
                      "--seed", "3", "--out", sim}),
            0);
  ASSERT_EQ(replayInto(dir / "replay", sim, {"--rig", kRig}), 0) << readFile(dir / "replay.txt");
  const std::string derived = (dir / "replay" / "derived.lcmlog").string();
  // The log times of each sweep's first and last chunk.
  std::map<int64_t, std::pair<int64_t, int64_t>> times;
  EventLogReader reader(derived);
  LogEvent e;
  int64_t start = -1, end = 0;
  while (reader.next(&e)) {
    if (start < 0) start = e.utime;
    end = e.utime;
    if (e.channel != channels::kSweepCloud) continue;
    cloud_chunk_t c;
    ASSERT_TRUE(decodeMessage(e.data.data(), e.data.size(), &c));
    auto [it, fresh] = times.try_emplace(c.sweep_id, e.utime, e.utime);
    it->second.second = e.utime;
  }
  ASSERT_EQ(times.size(), 2u);
  const int64_t between = (times.begin()->second.second + times.rbegin()->second.first) / 2;
  startView({derived, "--rig", kRig});
  const nlohmann::json page = runNode("view_log.js",
                                      {"http://127.0.0.1:8080/", std::to_string(end),
                                       std::to_string(start), std::to_string(between)},
                                      90.0);
  ASSERT_TRUE(page.is_object()) << procs.said("node");
  ASSERT_FALSE(page.contains("failure")) << page["failure"];
  EXPECT_TRUE(page["errors"].empty()) << page["errors"];
  EXPECT_EQ(page["mode"], "log");
  ASSERT_EQ(page["seeks"].size(), 3u);
  const std::vector<int> sweeps = {2, 0, 1};
  for (size_t i = 0; i < 3; ++i) {
    const auto& s = page["seeks"][i];
    EXPECT_EQ(s["sweeps"], sweeps[i]) << "seek " << i << ": " << s;
    EXPECT_EQ(s["check"]["drawn"], s["check"]["server"]) << s;
    EXPECT_EQ(s["points_drawn"], s["check"]["server"]) << s;
  }
  EXPECT_GT(page["seeks"][0]["points_drawn"].get<int64_t>(),
            page["seeks"][2]["points_drawn"].get<int64_t>());
  // The replay's mapper recorded MAP_UPDATE: at the end the page draws its final map.
  const std::vector<Message> stats = readChannel(derived, channels::kMapStats);
  ASSERT_FALSE(stats.empty());
  map_stats_t last;
  ASSERT_TRUE(decodeMessage(stats.back(), &last));
  EXPECT_EQ(page["seeks"][0]["voxel_source"], "mapper");
  EXPECT_EQ(page["seeks"][0]["voxels"].get<int64_t>(), last.occupied_voxels);
  EXPECT_EQ(page["seeks"][1]["voxels"], 0);
}

INSTANTIATE_TEST_SUITE_P(Browser, ViewTest, ::testing::Values("chromium", "firefox"),
                         [](const auto& info) { return info.param; });

}  // namespace
}  // namespace test
}  // namespace sweepmap
