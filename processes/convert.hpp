// The one place where LCM messages and the library structs meet: the generic codec of the
// message types (message_codec.hpp) and the conversions to and from the library structs.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "calib/sweep_assembly.hpp"
#include "core/profile.hpp"
#include "core/scan.hpp"
#include "devices/odometry_devices.hpp"
#include "devices/shaft_trajectory.hpp"
#include "processes/message_codec.hpp"
#include "sweepmap/cloud_chunk_t.hpp"
#include "sweepmap/imu_t.hpp"
#include "sweepmap/lidar_scan_t.hpp"
#include "sweepmap/map_update_t.hpp"
#include "sweepmap/profile_t.hpp"
#include "sweepmap/scan_window_t.hpp"
#include "sweepmap/sweep_status_t.hpp"
#include "sweepmap/truth_shaft_t.hpp"
#include "sweepmap/wheel_ticks_t.hpp"

namespace sweepmap {

lidar_scan_t toLcm(const Scan2D& scan);
Scan2D fromLcm(const lidar_scan_t& msg);

SweepWindow fromLcm(const scan_window_t& msg);
// Empty when valid, else the reason.
std::string validateWindow(const scan_window_t& msg);

// Splits a sweep into self-describing chunks of at most `chunk_points` points, each point
// with its intensity when the sweep has one per point.
std::vector<cloud_chunk_t> toChunks(const AssembledSweep& sweep, int chunk_points);
sweep_status_t toStatus(const AssembledSweep& sweep, int chunk_count);
// Empty when valid, else the reason (a bad chunk index, more points than the sweep, a
// non-finite point or sensor origin, intensities neither 0 nor one per point).
std::string validateChunk(const cloud_chunk_t& msg);

// Voxels per MAP_UPDATE chunk: 4000 * 12 bytes of indices and a 76-byte header, one UDP
// datagram (as SWEEP_CLOUD's 4000-point chunks).
constexpr int kMapUpdateChunkVoxels = 4000;
// Splits one map update (mapping/occupancy_map.hpp's VoxelChanges: the voxel indices that became
// occupied and those freed, each list sorted) into chunks of at most `chunk_voxels` voxels,
// occupied first, then freed, in the lists' order; `header` gives utime, seq, sweep_id,
// resolution_m and occupied_voxels. An update that changed nothing is one empty chunk, so that
// `seq` has no gaps a receiver would take for a loss.
std::vector<map_update_t> toMapUpdates(const std::vector<std::array<int32_t, 3>>& occupied,
                                       const std::vector<std::array<int32_t, 3>>& freed,
                                       const map_update_t& header,
                                       int chunk_voxels = kMapUpdateChunkVoxels);
// Empty when valid, else the reason: seq >= 1, a chunk index inside its count, counts that
// match their arrays and stay within the update's totals (a full update's freed: 0) and
// kMapUpdateChunkVoxels, a finite resolution > 0, indices inside OctoMap's +-2^15 voxels,
// occupied_voxels >= 0.
std::string validateMapUpdate(const map_update_t& msg);

truth_shaft_t toLcm(const ShaftSegment& segment, int64_t utime);

imu_t toLcm(const ImuSample& sample);
wheel_ticks_t toLcm(const WheelTicks& ticks);
ShaftSegment fromLcm(const truth_shaft_t& msg);

profile_t toLcm(const Profile& profile);
Profile fromLcm(const profile_t& msg);
// Empty when valid, else the reason: counts and sizes agree, columns in range, every
// coordinate finite, a positive encoder resolution.
std::string validateProfile(const profile_t& msg);

}  // namespace sweepmap
