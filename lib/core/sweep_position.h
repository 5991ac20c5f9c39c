// SPDX-License-Identifier: Apache-2.0
// Where the LiDAR's sweep is (the latest point of the stream: its beam azimuth and firing time) and
// when it will have passed a place on the map far enough that no cluster there can still grow (the
// perception::SweepClusterer's closing rule, sweep_clusterer.h): what tells RsuCore that every cluster of a
// vehicle has been released.
//
// The rule is the clusterer's, per laser: the newest point was fired at the encoder azimuth of its beam
// azimuth minus its laser's offset, and every later firing of any laser points at least that encoder
// azimuth plus the smallest offset. (It used to assume the newest point came from the laser that leads
// most, i.e. subtract the whole offset spread: an OS1-128's four-beam stagger, 8.5 deg, held every
// vehicle three packets (2.3 ms) longer than the sweep needed whenever the stream's last pixel was
// beam 127, which trails. Issue 16, latency.)
#pragma once

#include <span>
#include <vector>

#include <Eigen/Core>

#include "common/time.h"
#include "core/lidar_mount.h"
#include "lidar/lidar_decoder.h"
#include "lidar/point.h"

namespace rsu::core {

class SweepPosition {
 public:
  // `cluster_tolerance_m`: the clustering tolerance; `release_margin_deg`: perception::SweepConfig's margin.
  SweepPosition(const LidarMount& mount, double cluster_tolerance_m, double release_margin_deg,
                const lidar::SweepGeometry& geometry);

  // The sensor's geometry as the decoder measures it now (offsets, lead, rotation rate).
  void follow(const lidar::SweepGeometry& geometry);
  // The rotation rate the stages run at (RsuCore passes a measured one on when it moved enough).
  void set_rotation_hz(double rotation_hz) { rotation_hz_ = rotation_hz; }
  // The points just added to the clusterer (map frame): the last one is where the sweep is.
  void advance(std::span<const lidar::LidarPoint> points);

  double rotation_hz() const { return rotation_hz_; }
  bool known() const { return known_; }
  TimeNs time() const { return latest_.time_ns; }
  TimeNs rotation_period_ns() const { return static_cast<TimeNs>(1e9 / rotation_hz_); }
  // The firing time at which the sweep has passed every point of `outline` (map frame) far enough
  // that no cluster near them can still grow; 0 before the sweep is known or for an empty outline.
  TimeNs passed_time(std::span<const Eigen::Vector2d> outline) const;
  // Whether every laser has swept past every point of `outline` (map frame): no return from inside it
  // can still come (the closing angle of passed_time not added). False before the sweep is known or for
  // an empty outline.
  bool swept(std::span<const Eigen::Vector2d> outline) const;

 private:
  // How far the sweep must still turn until every later firing points `beyond` past every point of
  // `outline` (rad, in [0, 2 pi): above pi it is already past); `outline` not empty.
  double still_to_turn(std::span<const Eigen::Vector2d> outline, double beyond) const;
  // How far behind the newest point's beam azimuth later firings may point: its laser's offset above the
  // smallest, the lead and the margin (the whole spread for a point whose laser is not in the table).
  double lag_rad(const lidar::LidarPoint& newest) const;

  LidarMount mount_;
  double tolerance_m_;
  double release_margin_rad_;
  std::vector<double> ring_offset_rad_;  // SweepGeometry::ring_azimuth_offset_rad
  double min_offset_rad_ = 0.0;
  double max_offset_rad_ = 0.0;
  double lead_rad_ = 0.0;
  double rotation_hz_;
  bool known_ = false;
  lidar::LidarPoint latest_;
};

}  // namespace rsu::core
