// Clusters foreground points WHILE the LiDAR sweeps, and releases each cluster as soon as the sweep
// has passed it, instead of waiting for the end of the rotation. This is what keeps the latency from
// "the last packet covering the vehicle" to "correction sent" at a few milliseconds (issue #4: p99 <=
// 5 ms) although a rotation takes 100 ms: a vehicle swept early in the rotation is corrected then, not
// up to 100 ms later.
//
// Release rule (exact, geometric). Points arrive in firing order; a spinning LiDAR's beam azimuth
// only grows (unwrapped), except for the spread of the per-laser azimuth offsets (VLP-32C: -4.2 to
// +4.2 deg, DESIGN.md §2). So every point still to come in this rotation has an azimuth of at least
//     a_future = sweep - spread - margin,
// where `sweep` is the largest azimuth seen so far. Euclidean clustering joins a future point q to a
// cluster only if q is within the tolerance d of one of its points p (planar distance, as the
// perception clustering). The future points all lie in the wedge of azimuths >= a_future, and the
// planar distance from p (range r, azimuth a < a_future) to that wedge is r sin(a_future - a) while
// the angle is below 90 deg, and at most r beyond. A cluster is therefore CLOSED - no later point can
// join it - when every one of its points has r sin(min(a_future - a, 90 deg)) > d. At 20 m with
// d = 0.7 m that is 2 deg (0.56 ms at 10 Hz) past the cluster's last point, plus the offset spread.
// A closed cluster is released when, in addition, no open cluster overlaps its azimuth span, so that
// vehicles side by side in one line of sight reach association together (RsuCore associates each
// released batch with one global assignment).
//
// Bookkeeping: points pending for more than half a rotation are dropped (counted) so that the next
// rotation's points never merge with this one's (only points within d of the LiDAR itself can stay
// open that long); a gap or time going backwards restarts the stream and drops what is pending.
// The azimuths are the sensor's beam azimuths (LidarPoint::azimuth_rad); ranges are measured from
// the LiDAR's map position, which equals the sensor's horizontal range for a level mount (a small tilt
// is covered by the margin).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "common/time.h"
#include "lidar/point.h"
#include "perception/euclidean_clustering.h"
#include "rsu/rsu_core_config.h"

namespace rsu::core {

struct SweptCluster {
  std::vector<LidarPoint> points;  // map frame, in arrival order
};

struct SweepClustererStats {
  std::uint64_t points_seen = 0;
  std::uint64_t foreground_points = 0;
  std::uint64_t clusters_released = 0;
  std::uint64_t clusters_dropped_small = 0;   // fewer than ClusteringConfig::min_points (noise)
  std::uint64_t clusters_dropped_large = 0;   // more than max_points (e.g. a wall, no background yet)
  std::uint64_t points_dropped_stale = 0;     // pending for half a rotation (see file comment)
  std::uint64_t points_dropped_overflow = 0;  // over SweepConfig::max_pending_points
  std::uint64_t points_dropped_restart = 0;   // pending when the stream restarted
  std::uint64_t invalid_points = 0;           // non-finite coordinates, azimuth or time
  std::uint64_t restarts = 0;
};

class SweepClusterer {
 public:
  // `azimuth_spread_rad`: max - min of the sensor's per-laser azimuth offsets. Throws
  // std::invalid_argument for a non-positive rotation rate or non-finite numbers.
  SweepClusterer(const SweepConfig& config, const perception::ClusteringConfig& clustering,
                 const Eigen::Vector2d& lidar_xy, double rotation_hz, double azimuth_spread_rad);

  // Every point of the stream, in firing order, map frame (its azimuth_rad is still the sensor's beam
  // azimuth). Background points only advance the sweep; foreground points wait for their cluster.
  void add(const LidarPoint& point, bool foreground);

  // Clusters closed by the sweep so far (see the file comment), in order of their first point.
  std::vector<SweptCluster> release_closed();
  // Everything pending, closed or not: the end of a whole frame (PCD replay) or of the stream (drain).
  std::vector<SweptCluster> release_all();

  std::size_t pending_points() const { return points_.size(); }
  const SweepClustererStats& stats() const { return stats_; }

 private:
  void restart();
  std::vector<SweptCluster> release(bool everything);
  void drop_stale();

  SweepConfig config_;
  perception::ClusteringConfig clustering_;  // min 1 / max unbounded: size limits applied on release
  std::size_t min_points_;
  std::size_t max_points_;
  Eigen::Vector2d lidar_xy_;
  double radians_per_ns_;
  TimeNs max_gap_ns_;
  double lag_rad_;  // spread + margin: how far behind the sweep a future point may still land

  bool running_ = false;
  double sweep_ = 0.0;  // largest unwrapped azimuth seen, radians
  TimeNs last_time_ = 0;

  // Pending foreground points and, in parallel, their unwrapped azimuth and planar range.
  std::vector<LidarPoint> points_;
  std::vector<double> azimuth_;
  std::vector<double> range_;
  SweepClustererStats stats_;
};

}  // namespace rsu::core
