// SPDX-License-Identifier: Apache-2.0
// Clusters foreground points WHILE the LiDAR sweeps, and releases each cluster as soon as the sweep
// has passed it, instead of waiting for the end of the rotation. This is what keeps the latency from
// "the last packet covering the vehicle" to "correction sent" at a few milliseconds (issue #4: p99 <=
// 5 ms) although a rotation takes 100 ms: a vehicle swept early in the rotation is corrected then, not
// up to 100 ms later.
//
// Release rule (exact, geometric, laser-aware). Points arrive in firing order. Laser i's beam azimuth
// is the encoder azimuth at its firing plus its fixed offset o_i (sensor_model.h; VLP-32C: four
// groups at -4.2, -1.4, +1.4, +4.2 deg, docs/design.md §2), and the encoder azimuth only grows (unwrapped).
// Every return therefore tells the encoder azimuth it was fired at, u - o_ring, and with E the newest
// such encoder azimuth seen, every point laser i still sends has a beam azimuth of at least E + o_i:
// its future points lie in the wedge W_i of azimuths >= E + o_i, at any range.
// Euclidean clustering joins a future point q to a cluster only if q is within the tolerance d of one
// of its points p (planar distance, as the perception clustering; a spatial distance is never
// smaller). The planar distance from p (range r, azimuth a) to W_i is r sin(E + o_i - a) while that
// angle is in [0, 90 deg], at most r beyond, and 0 when p is inside W_i. A cluster is CLOSED - no
// later point of any laser can join it - when every one of its points is farther than d from every
// W_i. The wedges are nested (W_i contains W_j when o_i <= o_j), so the test against all lasers is
// exactly the test against the laser group with the smallest offset: every point must have
//     r sin(min(a_future - a, 90 deg)) > d,   a_future = E + min_i o_i - margin.
// This bound is tight: the smallest-offset lasers really still sweep the wedge's edge, and a return
// there at range r cos(a_future - a) would join. (An earlier rule took the sweep as the largest BEAM
// azimuth seen and subtracted the whole offset spread; that equals this rule only while the
// largest-offset lasers keep returning, and lags by up to the spread where they see nothing, e.g.
// the sky or open road. Without a per-laser table, the constructor taking only the spread keeps it.)
// At 10 m with d = 0.7 m the cluster is closed asin(0.07) = 4 deg (1.1 ms at 10 Hz) after the
// smallest-offset lasers have passed its last point; at 2.5 m, 16 deg (4.5 ms): the exact rule cannot
// release a vehicle that close much sooner, whatever the sensor.
// `margin` (SweepConfig::release_margin_deg) covers the VLP-16's interpolated second-sequence
// azimuths (not exactly monotone across packets) and a slightly tilted mount (azimuths are the
// sensor's, ranges are measured from the LiDAR's map position).
// A closed cluster is released when, in addition, no open cluster that starts nearer to the LiDAR
// overlaps its azimuth span within SweepConfig::joint_release_range_gap_m of its ranges: such a one
// may hide part of it, or be a fragment of the same vehicle in front of it, and the two reach
// association together (the RSU associates each released batch with one global assignment:
// lib/core/rsu_core.h). Clusters farther apart than that in range (|p - q| >= ||p| - |q||: in plane
// too) cannot fall in one vehicle's association gate, and waiting for them cost a car parked behind a
// passing one 10-20 ms (issue 16, load test: p99 17 ms with another vehicle in the line of sight, 5 ms
// without). An open cluster that starts no nearer is not waited for (issue 16, 2026-12-01: a car 10 m
// away waited for a car passing 3-10 m behind it to close, 4.5-7 ms after its own last point): it
// cannot hide the closed one, and what the early release can cost in the association the RSU's
// gatherer catches (core/vehicle_gatherer.h): a vehicle whose gate took a cluster that is not tightly
// inside its footprint is held until the sweep has passed the footprint, so its own cluster, released
// later, is assigned too and wins as the nearer. Such a farther open cluster may still be a fragment of
// the same vehicle: the released cluster names it (SweptCluster::open_beyond), and the gatherer holds
// the vehicle for it where it reaches into the vehicle's footprint.
//
// Released open (release_closed's `fixed_open`; core/prepared_fixes.h): the closing rule is exact about
// the cluster, not about the vehicle. RsuCore names an open cluster every laser has swept past once its
// vehicle's fix, prepared meanwhile, bounds the vehicle inside a box the sweep has passed too: it goes
// with the closed ones, and a point that would still have joined it (another object's) starts a cluster
// of its own.
//
// Each point's bound is a threshold: it can gain no neighbour once a_future > a + asin(d / r) (the
// test r sin(a_future - a) > d rearranged; never while r <= d), so a cluster closes once a_future passes the
// largest of its points' thresholds, kept as the points join (incremental_clustering.h). Clustering is
// incremental too: each foreground point joins its components as it arrives, exactly cluster_grid's
// components of the pending points, so a packet costs what its own points cost and a release only looks at
// the components, not at their points (issue 16: clustering every pending point again on each packet that
// might close something cost a dense sensor's near car up to 9.8 ms a packet).
//
// Bookkeeping: points pending for more than half a rotation are dropped (counted) so that the next
// rotation's points never merge with this one's (only points within d of the LiDAR itself can stay
// open that long); a gap or time going backwards restarts the stream and drops what is pending.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "common/time.h"
#include "lidar/point.h"
#include "perception/euclidean_clustering.h"
#include "perception/incremental_clustering.h"

namespace rsu::perception {

// The release rule (file comment).
struct SweepConfig {
  // Extra azimuth the sweep must be past a cluster before it is released, on top of the spread of
  // the sensor's per-laser azimuth offsets (computed from the model): covers the interpolation of
  // firing azimuths between blocks (the VLP-32C manual's rule puts a pair up to 0.13 deg ahead of the
  // rotor at its firing at 600 rpm, sensor_model.h) and a slightly tilted mount.
  double release_margin_deg = 0.5;
  // Foreground points waiting for their cluster to close; beyond this the oldest are dropped (a flood
  // of foreground, e.g. before any background exists, cannot grow memory without bound).
  std::size_t max_pending_points = 200000;
  // A gap in the point stream longer than this many rotations, or time going backwards, restarts it.
  double max_gap_rotations = 2.0;
  // A closed cluster waits for an open one at overlapping azimuths that starts nearer to the LiDAR only
  // if their planar ranges come this close (file comment): nearer, they may be one vehicle's fragments
  // or fall in one vehicle's association gate, and are associated together. Farther apart, a vehicle
  // whose gate took the other's cluster is held until its own is released and takes that instead
  // (core/vehicle_gatherer.h): what the early release can cost is the other vehicle's fix in that
  // rotation. Infinite: wait for every open cluster in the line of sight that starts nearer.
  double joint_release_range_gap_m = 6.0;
};

struct SweptCluster {
  std::vector<lidar::LidarPoint> points;  // map frame, in arrival order
  // The clusterer's name for it while it was open (its first point's number in the stream): what
  // release_closed's `fixed_open` names. Never reused.
  std::uint64_t id = 0;
  // Released while a nearer cluster in its line of sight was still open (joint_release_range_gap_m):
  // part of it may be hidden behind that one and show again beyond it.
  bool ahead_of_open = false;
  // The planar bounding boxes (map frame) of the clusters still open in its line of sight that it did
  // not wait for, within joint_release_range_gap_m of its ranges: the points they hold so far. One that
  // lies where its vehicle may be is a fragment of it still to come (core/vehicle_gatherer.h).
  std::vector<Eigen::AlignedBox2d> open_beyond;
};

// An open cluster as swept_open gave it: its SweptCluster::id and how many points it held then.
struct OpenClusterName {
  std::uint64_t id = 0;
  std::size_t size = 0;
};

struct SweepClustererStats {
  std::uint64_t points_seen = 0;
  std::uint64_t foreground_points = 0;
  std::uint64_t clusters_released = 0;
  std::uint64_t clusters_released_open = 0;  // of them, released open (release_closed's fixed_open)
  std::uint64_t clusters_dropped_small = 0;  // fewer than ClusteringConfig::min_points (noise)
  std::uint64_t clusters_dropped_large = 0;  // more than max_points (e.g. a wall, no background yet)
  // Reaching back to where the stream (re)started: part of the object went by before the first point.
  std::uint64_t clusters_dropped_cut_at_start = 0;
  std::uint64_t points_dropped_stale = 0;     // pending for half a rotation (see file comment)
  std::uint64_t points_dropped_overflow = 0;  // over SweepConfig::max_pending_points
  std::uint64_t points_dropped_restart = 0;   // pending when the stream restarted
  std::uint64_t invalid_points = 0;           // non-finite coordinates or azimuth, a ring the laser
                                              // table does not have, or a foreground point beyond the
                                              // clustering's domain (hundreds of km)
  std::uint64_t restarts = 0;
};

class SweepClusterer {
 public:
  // Laser-aware (the exact rule of the file comment): `laser_azimuth_offsets_rad[ring]` is laser
  // `ring`'s azimuth offset (SensorModel::azimuth_offset_deg, in radians, channel order). Throws
  // std::invalid_argument for a non-positive rotation rate, non-finite numbers, an empty table or
  // offsets spread over more than 90 deg.
  SweepClusterer(const SweepConfig& config, const perception::ClusteringConfig& clustering,
                 const Eigen::Vector2d& lidar_xy, double rotation_hz,
                 std::span<const double> laser_azimuth_offsets_rad);
  // Without a laser table: `azimuth_spread_rad` is max - min of the per-laser offsets, and every
  // future point is assumed to lag the largest beam azimuth seen by the whole spread (conservative;
  // equal to the laser-aware rule while the largest-offset lasers keep returning).
  SweepClusterer(const SweepConfig& config, const perception::ClusteringConfig& clustering,
                 const Eigen::Vector2d& lidar_xy, double rotation_hz, double azimuth_spread_rad);

  // Every point of the stream, in firing order, map frame (its azimuth_rad is still the sensor's beam
  // azimuth). Background points only advance the sweep; foreground points wait for their cluster.
  void add(const lidar::LidarPoint& point, bool foreground);

  // Clusters closed by the sweep so far (see the file comment), in order of their first point; with
  // them the open clusters `fixed_open` names (by SweptCluster::id and size, as swept_open gave them)
  // if every laser has swept past them and they have not grown since: their vehicle's fix is ready, and
  // the sweep has passed the whole of its box (RsuCore, early release), so what may still join them
  // within the tolerance is another object's.
  std::vector<SweptCluster> release_closed(std::span<const OpenClusterName> fixed_open = {});
  // Everything pending, closed or not: the end of a whole frame (PCD replay) or of the stream (drain).
  std::vector<SweptCluster> release_all();
  // Clusters not closed yet that every laser has swept past (a_future beyond their largest azimuth):
  // they are complete unless another object's point still comes within the tolerance, so RsuCore fits
  // and fixes them while the sweep covers the rest of the closing angle, and finds the result ready
  // when release_closed gives the same points (issue 16: a VLP-32C's car at 5 m waits 3.3-4.0 ms for
  // that, exactly, after its last packet). The points as release_closed would give them now; each
  // cluster once (by its first point); none that release would drop (size, cut at the start).
  std::vector<SweptCluster> swept_open();
  // The points swept so far of the open clusters that a released one went ahead of while nearer the
  // LiDAR than its far end (the joint release gap, file comment), one cluster each, in arrival order:
  // they may hide part of it, and every one of them at its azimuths is already there (the sweep has
  // passed them), so the fix reasons about its shadow as if they had been released with it.
  std::vector<std::vector<lidar::LidarPoint>> overtaken_open_points();

  // Drops every pending point (counted as points_dropped_restart) and starts the stream afresh, as a
  // gap does: the caller skipped part of the stream (RsuCore sheds packets it is too late for), so
  // the clusters open at that moment are truncated and must not be fitted as whole vehicles.
  void restart();

  // The spin rate as measured since (lidar_decoder.h: SweepGeometry::rotation_hz). Ignored unless
  // finite and positive.
  void set_rotation_hz(double rotation_hz);

  std::size_t pending_points() const { return clusters_.size(); }
  const SweepClustererStats& stats() const { return stats_; }

 private:
  void init(double rotation_hz);
  std::vector<SweptCluster> release(bool everything, std::span<const OpenClusterName> fixed_open);
  // The released cluster of component `s` and its `members`, named by the `open` ones in its line of sight.
  SweptCluster released(const ComponentSummary& s, std::span<const ComponentSummary> open,
                        std::span<const PendingPoint> members);
  void drop_stale();
  bool cut_at_start(std::span<const PendingPoint> members) const;

  SweepConfig config_;
  perception::ClusteringConfig clustering_;
  std::size_t min_points_;
  std::size_t max_points_;
  Eigen::Vector2d lidar_xy_;
  double radians_per_ns_;
  TimeNs max_gap_ns_;
  // Per ring, the offset subtracted from a beam azimuth to get the encoder azimuth it was fired at;
  // empty without a laser table (then sweep_ tracks the largest beam azimuth).
  std::vector<double> laser_offset_rad_;
  double lag_rad_;  // how far behind sweep_ a future point may still land (file comment), + margin

  bool running_ = false;
  double sweep_ = 0.0;  // newest unwrapped encoder azimuth seen (largest beam azimuth without table)
  // The unwrapped beam azimuth from which every laser has been seen since the stream (re)started: an
  // object within the clustering tolerance of it may have begun before it and is never released whole.
  double start_u_ = 0.0;
  TimeNs last_time_ = 0;

  // Pending foreground points, in their components.
  IncrementalClustering clusters_;
  std::uint64_t next_seq_ = 0;
  std::vector<std::uint64_t> swept_open_given_;  // first_seq of the clusters swept_open gave
  std::vector<std::uint64_t> overtaken_;         // first_seq of open clusters a release went ahead of
  SweepClustererStats stats_;
};

}  // namespace rsu::perception
