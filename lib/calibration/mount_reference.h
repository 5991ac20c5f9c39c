// SPDX-License-Identifier: Apache-2.0
// The reference a mount monitor (mount_monitor.h, issue 17) checks each rotation against: the planes of
// the static scene the mount belongs to (the background learned under it, sensor frame), and the
// registration of one rotation onto them by the calibration's point-to-plane Gauss-Newton
// (point_to_plane.h) on a subsample of its points. Immutable once built: a caller may register rotations
// on a thread of its own (rsud does, off its event loop: issue 16's latency) while the monitor's state,
// which decides on the estimates, stays with its owner.
//
// Pure: no clock, no files, no threads of its own.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <unordered_map>
#include <utility>
#include <vector>

#include "calibration/point_to_plane.h"
#include "common/pose.h"
#include "common/time.h"
#include "lidar/point.h"

namespace rsu::calibration {

struct MountMonitorConfig {
  bool enabled = true;
  // The largest horizontal position error the mount's motion may cause to a fix at the coverage radius
  // before fixes stop (m): 5 cm, half the accuracy target, is 0.057 deg of yaw at 50 m.
  double max_position_error_m = 0.05;
  // Fixes resume once every rotation for this long has had its error below resume_fraction of the
  // tolerance (and was observable).
  TimeNs resume_after = 1'000'000'000;
  double resume_fraction = 0.8;
  // The reference: voxels of this size whose points lie on one plane (smallest scatter eigenvalue below
  // max_plane_thickness of the middle one), at least min_plane_points of them.
  double voxel_m = 0.5;
  double coarse_voxel_factor = 3.0;  // the coarse scale, where a fine voxel holds no plane
  int min_plane_points = 8;
  double max_plane_thickness = 0.05;
  double min_plane_spread = 0.15;  // the second spread (sqrt of the middle eigenvalue) over the voxel size
  // Each rotation: at most this many points, evenly spaced, from min_range_m out (nearer ones are the
  // pole and cabinet); residuals beyond max_residual_m are not the static scene (vehicles, passers-by).
  std::size_t sample_points = 3000;
  double min_range_m = 1.5;
  double max_residual_m = 0.5;
  int iterations = 8;
  double huber_sigmas = 3.0;
  double range_sigma_m = 0.02;  // the sensor's noise (as rsu-calibrate's)
  double angle_sigma_rad = 0.001;
  // A rotation with fewer static points than this cannot say (a part of one, a blocked view): counted
  // as unobservable, nothing decided. With enough points but fewer than min_match_fraction of them on
  // the reference's planes, the scene is no longer the reference's (moved far beyond what the
  // registration follows: a remount by metres): the fixes stop as for a drift.
  // Fewer than min_matches on the reference although at least min_match_fraction of them match it (a
  // part of a rotation: packets lost) is unobservable too, not a mismatch.
  std::size_t min_matches = 300;
  double min_match_fraction = 0.3;
  // rsud (RsuCore) does not check a rotation that lacked more than this share of its packets (lost in
  // the kernel by a daemon too slow for its LiDAR, or shed as too late): what is left of it says
  // little, and it must not read as motion. Fewer lost (network loss) are checked on what they have.
  double max_missing_fraction = 0.1;
  // The rule (a bumped sensor must never mislead a vehicle): fixes stop when the estimated error exceeds
  // the tolerance, whether or not by this many of its standard deviations; beyond it by them the motion
  // is confirmed, within them only suspected (stopped all the same, said so, counted as
  // stops_unconfirmed). A scene whose sigma at the radius puts this many of them beyond the tolerance
  // cannot verify the mount to it at all (rotations_unverifiable, warned about once): there the fixes
  // keep flowing while the estimate stays within the tolerance; once stopped there they stay stopped
  // until a recalibration (nothing there can show the LiDAR is back); elsewhere they resume once it is
  // back within resume_fraction of the tolerance by this many sigmas. Where the scene cannot verify,
  // no stop is confirmed either (its sigma is not to be trusted): every stop there is a suspected one.
  double significance_sigmas = 3.0;
  // A suspected motion (beyond the tolerance, not by significance_sigmas) stops the fixes once this many
  // rotations in a row show it: one noisy rotation in a weak scene must not (0.3 s at 10 Hz: well
  // within the second the fixes must stop in). A confirmed one stops them at its first rotation.
  int suspect_rotations = 3;
  // A direction of the motion (metres at the coverage radius) that one rotation's points pin down no
  // better than this is not estimated (mount_monitor.cpp, held_step): what it says there is noise.
  double max_free_sigma_m = 0.025;
  // A direction that one rotation pins down better than that but not to the tolerance over
  // significance_sigmas (1.67 cm at the radius: a street's length between flat facades, 2.1-2.2 cm in
  // the load street) is decided on the information-weighted mean of the rotations of this long, whose
  // sigma shrinks as 1 / sqrt(n): a single rotation's noise there read 5-11 cm now and then, and three
  // such rotations in a row had stopped a still sensor's fixes for good. A motion there is seen once the
  // mean of the rotations since it, or of enough of the window, shows it (mount_monitor.cpp, decide).
  TimeNs weak_evidence_window = 1'000'000'000;
};

// The sensor's motion since the reference: the reference frame -> the current sensor frame's pose in it.
struct MountDrift {
  Pose3 motion;                            // in the reference sensor frame (roll, pitch, yaw as Pose3)
  Matrix6d covariance = Matrix6d::Zero();  // of (dt, w) (point_to_plane.h)
  double error_at_radius_m = 0.0;          // largest horizontal displacement of a fix at the radius
  double error_sigma_m = 0.0;              // its standard deviation, from the covariance
  // The rotations whose information-weighted mean gives the directions one rotation pins down only
  // weakly (MountMonitorConfig::weak_evidence_window); 0: it holds none so (the rotation alone).
  int rotations_averaged = 0;
  // Such directions held at the reference instead: their mean does not verify the tolerance yet.
  bool weak_held = false;
  // The standard deviation at the radius, along the error, of those directions' mean alone (0: none).
  double weak_sigma_m = 0.0;
  double rms_m = 0.0;
  std::size_t matches = 0;
  std::size_t sampled = 0;         // static points of the rotation used
  bool observable = false;         // enough points sampled to tell
  bool matches_reference = false;  // and enough of them matched
};

// What a reference is built from (MountReference's constructor's arguments), so that it can be built
// where the rotations are registered (rsud: 40-52 ms for three 128 x 2048 rotations, off its loop).
struct MountReferenceSource {
  std::shared_ptr<const std::vector<std::vector<lidar::LidarPoint>>> frames;  // sensor frame
  Pose3 mount;
  double coverage_radius_m = 0.0;
  double fix_height_m = 0.0;
  MountMonitorConfig config;
};

class MountReference {
 public:
  explicit MountReference(const MountReferenceSource& source)
      : MountReference(*source.frames, source.mount, source.coverage_radius_m, source.fix_height_m,
                       source.config) {}
  // reference: the static scene the mount belongs to, sensor frame (the learned background's
  // rotations). mount: sensor -> map (the error is horizontal in the map frame). coverage_radius_m and
  // fix_height_m (how far below the sensor a fix's points are: the mount's height above the road, about)
  // place the fixes the error is measured at.
  MountReference(const std::vector<std::vector<lidar::LidarPoint>>& reference, const Pose3& mount,
                 double coverage_radius_m, double fix_height_m, const MountMonitorConfig& config);

  // The drift of `rotation` (sensor frame) from `start`: the registration alone, nothing decided.
  MountDrift estimate(std::span<const lidar::LidarPoint> rotation, const Pose3& start) const;
  // The error at the radius (the worst azimuth) and its standard deviation under `covariance`.
  std::pair<double, double> error_at_radius(const Pose3& motion, const Matrix6d& covariance) const;
  // Metres at the coverage radius per unit of each motion parameter (x, y, z, roll, pitch, yaw): 1 for
  // the translations, the radius for the rotations; held_step and the monitor weigh directions in these.
  Vector6d at_radius_scale() const;
  std::size_t planes() const { return planes_[0].size() + planes_[1].size() + planes_[2].size(); }
  const MountMonitorConfig& config() const { return config_; }

 private:
  struct Plane {
    Eigen::Vector3f point;
    Eigen::Vector3f normal;
    float thickness_m = 0.0F;  // rms of its points along the normal
    bool weak = false;         // a line of points (one ring): on the structure, normal unknown
  };
  // The fine planes, the coarse ones, and the fine voxels that hold a line of points (one ring across a
  // facade or the road: flat, but which way it faces is the noise's choice). Those count as the
  // reference's structure (is this still the reference's scene?) but are not fitted: their arbitrary
  // normals pinned the estimate (a 0.5 deg bump measured as 0.26 deg in the fault street) and claimed a
  // precision along the street that no structure there gives.
  static constexpr int kScales = 3;
  static constexpr int kWeakScale = 2;
  static constexpr std::size_t kMinFitted = 30;  // fewer fitted points: no covariance (unverifiable)
  // The plane a point (reference frame) lies on: the fine voxel's, else the coarse one's, else the line's.
  const Plane* plane_at(const Eigen::Vector3d& a) const;
  // Matches on the fitted planes; weak_matches counts those on lines (within the gate of their plane).
  std::vector<PlaneMatch> match(const std::vector<Eigen::Vector3d>& points, const Pose3& motion,
                                double max_residual_m, std::size_t& weak_matches) const;
  Vector6d held_step(const PlaneFit& fit) const;

  MountMonitorConfig config_;
  Eigen::Matrix3d mount_rotation_;
  double radius_m_;
  double fix_height_m_;
  std::unordered_map<std::int64_t, Plane> planes_[kScales];
  double voxel_sizes_[kScales] = {};
};

}  // namespace rsu::calibration
