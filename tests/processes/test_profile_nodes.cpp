// Rig C's live nodes on a virtual clock: the profiler node drives the simulated turntable
// through its sweeps (the simulated devices share the offline simulation's physics), and the
// assembler places each profile by the generalised Eq. 7.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <map>

#include "processes/channels.hpp"
#include "processes/convert.hpp"
#include "processes/profile_assembler_node.hpp"
#include "processes/profile_scan_node.hpp"
#include "sim/profile_devices.hpp"
#include "sweepmap/cloud_chunk_t.hpp"
#include "sweepmap/truth_profile_rig_t.hpp"
#include "tests/processes/node_test_util.hpp"

namespace sweepmap {
namespace {

constexpr int64_t kT0 = 1700000000000000LL;

using test::encode;

bool sameProfile(const Profile& a, const Profile& b) {
  return a.utime == b.utime && a.sequence == b.sequence && a.encoder_counts == b.encoder_counts &&
         a.counts_per_revolution == b.counts_per_revolution && a.column_count == b.column_count &&
         a.column == b.column && a.y_mm == b.y_mm && a.z_mm == b.z_mm;
}

TEST(SimProfileDevices, TheLiveSensorIsTheOfflineSimulationsPhysics) {
  const ProfilerConfig profiler;    // 170 profiles/s
  const TurntableConfig turntable;  // -25 .. 25 deg at 20 deg/s
  const SimProfileConfig sim;
  for (const uint64_t seed : {1u, 7u}) {
    SimProfileWorld world(profiler, turntable, sim, seed, kT0);
    SimTurntable table(&world);
    SimProfilerDevice sensor(&world);
    table.command(kT0, {turntable.sweep_end_deg, turntable.speed_deg_s});
    const std::vector<Profile> live = sensor.poll(kT0 + 2500000);
    std::vector<PlatePose> plates;
    const auto scenes = simProfileScenes(sim, turntable, &plates);
    SimProfiler offline(profiler, turntable, sim, seed);
    const std::vector<Profile> sweep = offline.sweep(scenes[0], 0, kT0);
    ASSERT_EQ(live.size(), sweep.size());
    // Every whole second the two clocks agree exactly on the time and the angle (elsewhere the
    // live exposure's time is rounded to the microsecond first): the same profile, the same
    // noise draws.
    for (const size_t k : {0u, 170u, 340u}) {
      EXPECT_TRUE(sameProfile(live[k], sweep[k])) << "seed " << seed << " profile " << k;
    }
    EXPECT_GT(sweep[170].column.size(), 500u);
  }
}

TEST(SimProfileDevices, TurntableMovesAsCommandedAndTheOperatorMovesThePlate) {
  const ProfilerConfig profiler;
  const TurntableConfig turntable;  // -25 .. 25 deg at 20 deg/s
  const SimProfileConfig sim;
  SimProfileWorld world(profiler, turntable, sim, 1, kT0);
  SimTurntable table(&world);
  const int cpr = table.countsPerRevolution();
  EXPECT_EQ(table.poll(kT0).front().counts, std::llround(-25.0 / 360 * cpr));
  table.command(kT0, {25.0, 20.0});
  EXPECT_NEAR(world.encoderDegAt(kT0 + 1250000), 0.0, 1e-9);
  EXPECT_DOUBLE_EQ(world.encoderDegAt(kT0 + 3000000), 25.0);  // arrived at 2.5 s, stands
  EXPECT_EQ(world.sceneIndexAt(kT0 + 3000000), 0);
  table.command(kT0 + 3000000, {-25.0, 20.0});  // back: the next plate at the arrival
  EXPECT_EQ(world.sceneIndexAt(kT0 + 5499999), 0);
  EXPECT_EQ(world.sceneIndexAt(kT0 + 5500000), 1);
  const auto placed = world.takePlacements(kT0 + 6000000);
  ASSERT_EQ(placed.size(), 2u);
  EXPECT_EQ(placed[0], std::make_pair(kT0, 0));
  EXPECT_EQ(placed[1], std::make_pair(kT0 + 5500000, 1));
  EXPECT_TRUE(world.takePlacements(kT0 + 6000000).empty());
  const auto samples = table.poll(kT0 + 6000000);
  EXPECT_EQ(samples.size(), 600u);  // every 10 ms
  EXPECT_EQ(samples.back().counts, std::llround(-25.0 / 360 * cpr));
}

// Runs the profiler node (and the truth node) on a virtual clock until it is done.
struct ScanRun {
  std::vector<profile_t> profiles;
  std::vector<truth_profile_rig_t> truths;
  int64_t end_utime = 0;
};

ScanRun runScan(ProfileScanNode& node, ProfileTruthNode& truth, int64_t limit_s) {
  ScanRun run;
  for (int64_t t = kT0; t < kT0 + limit_s * 1000000 && !node.done() && !node.failed(); t += 2000) {
    Outbox out;
    truth.tick(t, out);
    node.tick(t, out);
    for (const Message& m : out.take()) {
      if (m.channel == channels::kProfile) {
        run.profiles.emplace_back();
        EXPECT_TRUE(decodeMessage(m, &run.profiles.back()));
      } else if (m.channel == channels::kTruthProfileRig) {
        run.truths.emplace_back();
        EXPECT_TRUE(decodeMessage(m, &run.truths.back()));
      }
    }
    run.end_utime = t;
  }
  return run;
}

TEST(ProfileScanNode, SweepsThePlatePosesAndTheirPointsLieOnTheTruePlanes) {
  const ProfilerConfig profiler;
  const TurntableConfig turntable;
  SimProfileConfig sim;  // 3 plate poses
  SimProfileWorld world(profiler, turntable, sim, 3, kT0);
  SimTurntable table(&world);
  SimProfilerDevice sensor(&world);
  ProfileScanNode node(profiler, turntable, &table, &sensor, {3, 1.0});
  ProfileTruthNode truth_node(&world);
  const ScanRun run = runScan(node, truth_node, 60);
  ASSERT_TRUE(node.done());
  EXPECT_EQ(node.sweepsDone(), 3);
  // 3 sweeps of 2.5 s, 2 returns of 2.5 s and 2 pauses of 1 s.
  EXPECT_NEAR((run.end_utime - kT0) * 1e-6, 3 * 2.5 + 2 * 2.5 + 2 * 1.0, 0.1);
  ASSERT_EQ(run.truths.size(), 3u);
  ProfileAssemblerNode assembler(sim.trueGeometry());
  std::map<int, std::vector<double>> distances;  // sweep -> point-to-true-plane [mm]
  std::map<int, int> profiles;
  int64_t last_counts = INT64_MIN, last_sweep = -1;
  for (const profile_t& p : run.profiles) {
    if (p.sweep_id != last_sweep) last_counts = INT64_MIN;
    if (last_counts != INT64_MIN) {
      EXPECT_GE(p.encoder_counts, last_counts - 4) << "sweep " << p.sweep_id;  // noise: 0.5 count
    }
    last_counts = p.encoder_counts;
    last_sweep = p.sweep_id;
    ++profiles[p.sweep_id];
    const truth_profile_rig_t& t = run.truths.at(static_cast<size_t>(p.sweep_id));
    ASSERT_EQ(t.sweep_id, p.sweep_id);
    EXPECT_DOUBLE_EQ(t.mixed_pixel_probability, 0.5);  // the part's artefacts, on by default
    EXPECT_DOUBLE_EQ(t.dropout_glancing_probability, 0.5);
    EXPECT_DOUBLE_EQ(t.dropout_spot_probability, 0.01);
    const Eigen::Vector3d n(t.plane_normal[0], t.plane_normal[1], t.plane_normal[2]);
    for (const auto& q : profilePointsInRigFrameM(assembler.geometry(), fromLcm(p))) {
      distances[p.sweep_id].push_back(n.dot(q.cast<double>() * 1e3) - t.plane_distance_mm);
    }
  }
  ASSERT_EQ(profiles.size(), 3u);
  for (const auto& [sweep, d] : distances) {
    // 2.5 s at 170 profiles/s, the sweep ending with the first encoder sample at its end.
    EXPECT_NEAR(profiles[sweep], 426, 4) << sweep;
    double sum = 0;
    for (double x : d) sum += x * x;
    const double rms = std::sqrt(sum / d.size());
    std::printf("sweep %d: %d profiles, %zu points, %.4f mm RMS from the true plane\n", sweep,
                profiles[sweep], d.size(), rms);
    EXPECT_LT(rms, 0.05) << "sweep " << sweep << " (" << d.size() << " points)";
  }
  EXPECT_GT(node.counter("profiles_outside_sweeps"), 0);  // returns and pauses
  EXPECT_EQ(node.counter("profiles"), static_cast<int64_t>(run.profiles.size()));
}

// A turntable that never moves: the node fails instead of waiting for ever.
class StuckTurntable : public TurntableDevice {
 public:
  void command(int64_t, const TurntableCommand&) override { ++commands; }
  std::vector<EncoderSample> poll(int64_t now) override {
    if (now < next_) return {};
    next_ = now + 10000;
    return {{now, 0}};
  }
  int countsPerRevolution() const override { return 262144; }
  int commands = 0;

 private:
  int64_t next_ = 0;
};

class NoProfiles : public ProfilerDevice {
 public:
  std::vector<Profile> poll(int64_t) override { return {}; }
};

TEST(ProfileScanNode, ATurntableThatDoesNotArriveFailsTheNode) {
  TurntableConfig turntable;
  turntable.sweep_start_deg = 10;  // the stuck table reads 0
  StuckTurntable table;
  NoProfiles sensor;
  ProfileScanNode node(ProfilerConfig{}, turntable, &table, &sensor, {1, 0.0});
  SimProfileWorld world(ProfilerConfig{}, TurntableConfig{}, SimProfileConfig{}, 1, kT0);
  ProfileTruthNode truth(&world);
  runScan(node, truth, 30);
  EXPECT_TRUE(node.failed());
  EXPECT_FALSE(node.done());
  EXPECT_EQ(table.commands, 1);
}

Profile handMade(int64_t utime, int32_t sweep, int64_t counts) {
  Profile p;
  p.utime = utime;
  p.sequence = utime;
  p.sweep_id = sweep;
  p.encoder_counts = counts;
  p.counts_per_revolution = 360000;
  p.column_count = 4;
  p.column = {0, 3};
  p.y_mm = {-10.0f, 20.0f};
  p.z_mm = {-300.0f, -310.0f};
  return p;
}

std::vector<cloud_chunk_t> feed(ProfileAssemblerNode& node, const Message& m) {
  Outbox o;
  node.receive(m, o);
  std::vector<cloud_chunk_t> out;
  for (const Message& r : o.take()) {
    cloud_chunk_t c;
    if (r.channel == channels::kSweepCloud && decodeMessage(r, &c)) out.push_back(c);
  }
  return out;
}

TEST(ProfileAssemblerNode, PlacesEachProfileByEq7AsOneChunk) {
  const ProfileGeometry g{123.0, 409.0, 0.0035, 0.0087};
  ProfileAssemblerNode node(g);
  const Profile p = handMade(100, 2, 90000);  // 90 deg
  const auto chunks = feed(node, encode(channels::kProfile, toLcm(p)));
  ASSERT_EQ(chunks.size(), 1u);
  const cloud_chunk_t& c = chunks[0];
  EXPECT_EQ(c.utime, 100);
  EXPECT_EQ(c.sweep_id, 2);
  EXPECT_EQ(c.chunk_count, 1);
  EXPECT_EQ(c.frame, "O_r");
  ASSERT_EQ(c.npoints, 2);
  for (int i = 0; i < 2; ++i) {
    const Eigen::Vector3d e = profilePointInRigFrame(g, p.y_mm[i], p.z_mm[i], M_PI / 2) * 1e-3;
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(c.xyz_m[i][k], e[k], 1e-7) << i << " " << k;
  }
  // Hand check of Eq. 7 at 90 deg without tilt and zero: (M, -(N + y), z) turned by -90 deg
  // about Z is (-(N + y), -M, z).
  ProfileAssemblerNode plain(ProfileGeometry{123.0, 409.0, 0.0, 0.0});
  const auto c2 = feed(plain, encode(channels::kProfile, toLcm(p)));
  ASSERT_EQ(c2.size(), 1u);
  EXPECT_NEAR(c2[0].xyz_m[0][0], -(409.0 - 10.0) * 1e-3, 1e-6);
  EXPECT_NEAR(c2[0].xyz_m[0][1], -123.0 * 1e-3, 1e-6);
  EXPECT_NEAR(c2[0].xyz_m[0][2], -300.0 * 1e-3, 1e-6);
  // The sensor's origin at that angle: (-N, -M, 0).
  EXPECT_NEAR(c2[0].sensor_origin_m[0], -0.409, 1e-9);
  EXPECT_NEAR(c2[0].sensor_origin_m[1], -0.123, 1e-9);
  EXPECT_NEAR(c2[0].sensor_origin_m[2], 0.0, 1e-9);
}

TEST(ProfileAssemblerNode, BadProfilesAreCountedNeverFatal) {
  ProfileAssemblerNode node(ProfileGeometry{123.0, 409.0, 0.0, 0.0});
  Message garbage;
  garbage.channel = channels::kProfile;
  garbage.data = {1, 2, 3, 4, 5};
  EXPECT_TRUE(feed(node, garbage).empty());
  // A point count that asks for more bytes than the message has.
  Message huge = encode(channels::kProfile, toLcm(handMade(50, 0, 0)));
  huge.data[44] = 0x7f;
  EXPECT_TRUE(feed(node, huge).empty());
  Profile nan = handMade(60, 0, 0);
  nan.z_mm[1] = NAN;
  EXPECT_TRUE(feed(node, encode(channels::kProfile, toLcm(nan))).empty());
  EXPECT_EQ(node.counter("invalid"), 3);
  EXPECT_EQ(feed(node, encode(channels::kProfile, toLcm(handMade(200, 0, 0)))).size(), 1u);
  // Out of order: dropped, counted.
  EXPECT_TRUE(feed(node, encode(channels::kProfile, toLcm(handMade(150, 0, 0)))).empty());
  EXPECT_EQ(node.counter("dropped"), 1);
  // An empty profile is assembled (counted) but maps nothing.
  Profile empty = handMade(300, 0, 0);
  empty.column.clear();
  empty.y_mm.clear();
  empty.z_mm.clear();
  EXPECT_TRUE(feed(node, encode(channels::kProfile, toLcm(empty))).empty());
  EXPECT_EQ(node.counter("profiles"), 2);
}

}  // namespace
}  // namespace sweepmap
