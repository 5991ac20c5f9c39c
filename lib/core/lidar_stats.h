// SPDX-License-Identifier: Apache-2.0
// What RsuCore counts on the LiDAR side, from learning the background to the corrections sent, and how
// the stages before it are listed in the stats file.
#pragma once

#include <cstdint>

#include "calibration/mount_monitor.h"
#include "common/counter_list.h"
#include "lidar/packet_order.h"
#include "perception/sweep_clusterer.h"

namespace rsu::core {

struct LidarStats {
  std::uint64_t background_frames = 0;
  std::uint64_t clusters_fitted = 0;
  std::uint64_t fits_failed = 0;
  std::uint64_t clusters_out_of_coverage = 0;
  std::uint64_t clusters_unmatched = 0;   // no registered vehicle within the gates: unregistered
  std::uint64_t fragments_merged = 0;     // extra clusters of one vehicle fitted with its main one
  std::uint64_t vehicles_in_batches = 0;  // registered vehicles offered to association
  std::uint64_t corrections_failed = 0;   // size correction refused the matched cluster
  // the known-size box contradicts the points, or the points do not decide where it sits: no fix
  std::uint64_t corrections_inconsistent = 0;
  // a vehicle's clusters were only gathered (inside its grown footprint), none assigned to it by the
  // association's gate, and some lay beyond its tighter footprint (maybe a neighbour's) or together
  // they are not one vehicle: no fix (gathered_fix.h, no_assigned_cluster)
  std::uint64_t corrections_unassigned = 0;
  std::uint64_t corrections_encode_failed = 0;
  std::uint64_t corrections = 0;
  std::uint64_t corrections_withheld_mount = 0;  // fixed, not sent: the LiDAR moved, or unchecked (RsuCore)
  // fixes computed ahead of their vehicle's release (RsuCoreConfig::prepare_fixes), and those of them
  // its release used (its inputs unchanged)
  std::uint64_t fixes_prepared = 0;
  std::uint64_t fixes_prepared_used = 0;
  // the footprint tracked over rotations (footprint_track.h): fixes withheld as unbounded that its
  // intersection bounded and sent; sent fixes it tightened; rotations whose bound contradicted the
  // track's (withheld); tracks forgotten because the chain broke (a gap, a turn, a new size, ...)
  std::uint64_t track_bounded = 0;
  std::uint64_t track_tightened = 0;
  std::uint64_t track_conflicts = 0;
  std::uint64_t track_resets = 0;
  std::uint64_t packets_too_late = 0;      // older than RsuCoreConfig::max_packet_age when processed
  std::uint64_t packets_clock_offset = 0;  // time_source sensor: the sensor's clock beyond the tolerance
};

// packet.lost / reordered / late_dropped / duplicate / stream_gaps (the reorder stage's), packet.too_late,
// packet.clock_offset,
// sweep.* (the sweep clusterer's) and lidar.*.
void report(const lidar::PacketOrderStats& order, const perception::SweepClustererStats& sweep,
            const LidarStats& stats, CounterList& out);
// mount.*: the mount monitor's counts (zeros without one: nullptr), whether fixes are stopped, its latest
// estimate (measured); rotations_gappy: the rotations not checked for want of packets (RsuCore).
void report_mount(const calibration::MountMonitor* monitor, std::uint64_t rotations_gappy, CounterList& out);

}  // namespace rsu::core
