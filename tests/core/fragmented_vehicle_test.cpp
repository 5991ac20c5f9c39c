// SPDX-License-Identifier: Apache-2.0
// The corridor experiment's hard case (issue 5): the vehicle approaching the roadside VLP-32C head-on
// from 50 m to 30 m. There its points break into a few small clusters (front face and bumper low,
// cabin high, the hood between rings; the curb hedges hide the lower side) that the VLP-32C's
// per-laser azimuth offsets release in different batches of the sweep. A fix from one fragment is a
// metre off while it claims centimetres; RsuCore must gather the fragments (or send nothing), and the
// covariance it sends must cover the error it makes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "common/angles.h"
#include "common/symmetric_eigen.h"
#include "core/rsu_core.h"
#include "sim/scenario.h"
#include "sim/trajectory.h"
#include "sim_stream.h"
#include "v2i/wire_codec.h"

namespace rsu::core {
namespace {

TEST(RsuCoreFragments, HeadOnVehicleAtLongRangeIsFixedWholeOrNotAtAll) {
  const sim::Scenario scenario = sim::load_scenario_file(RSU_SOURCE_DIR "/scenarios/corridor.yaml");
  ASSERT_FALSE(scenario.scene.vehicles.empty());
  const sim::Vehicle& vehicle = scenario.scene.vehicles.front();
  constexpr int kEmptyRotations = 4;
  testing::SimStream stream(scenario.scene, {vehicle}, lidar::make_vlp32c(), scenario.lidar.mount,
                            scenario.lidar.noise, kEmptyRotations);
  RsuCoreConfig config;
  config.sensor_model = "vlp32c";
  config.mount = scenario.lidar.mount;
  config.background.learning_frames = 3;
  config.security.mode = v2i::SecurityMode::kInsecure;  // this test is about fragments, not signatures
  RsuCore core(config);

  // The vehicle announces its true pose and motion at 10 Hz (this test is about the RSU's own error),
  // with the covariance of a vehicle's NDT (Autoware's fixed output, docs/design.md §2).
  const TimeNs rotation = stream.rotation_ns();
  const TimeNs start = 7 * rotation;  // x = -52 m: |x| from 52 m down to 30 m below
  const TimeNs end = 27 * rotation;
  stream.run_until(core, start);
  std::uint32_t sequence = 1;
  for (TimeNs t = start; t < end; t += rotation, ++sequence) {
    const Pose2 now = sim::pose_at(vehicle.trajectory, t);
    const Pose2 later = sim::pose_at(vehicle.trajectory, t + 10 * kNsPerMs);
    v2i::VehicleAnnouncement a = testing::announce(1, sequence, t, now, "192.0.2.10");
    a.speed_mps = std::hypot(later.x - now.x, later.y - now.y) / 0.01;
    a.pose_covariance = Eigen::Vector3d(0.15 * 0.15, 0.15 * 0.15, 0.025 * 0.025).asDiagonal();
    ASSERT_TRUE(core.on_datagram(v2i::encode_v2i_message(a), {"192.0.2.10", 40000}, t).accepted());
    stream.run_until(core, t + rotation);
  }

  // Truth at each fix's own sweep time, from the trajectory.
  EXPECT_GE(stream.corrections().size(), 4U) << "the nearer rotations must still give a fix";
  double sum = 0.0;
  int confident = 0;
  for (const auto& [out, emitted_at] : stream.corrections()) {
    const v2i::Correction& c = out.correction;
    const Pose2 truth = sim::pose_at(vehicle.trajectory, c.sweep_time);
    const double dx = c.pose.x - truth.x;
    const double dy = c.pose.y - truth.y;
    const double error = std::hypot(dx, dy);
    // The mean error of the fixes that claim a precise position (larger axis sigma <= 0.15 m). Fixes of
    // a front half hidden by the hedge state the spread the points leave (0.3-0.4 m across the road) and
    // are sent: their error counts against their stated covariance (below), not this mean.
    const SymmetricEigen2 eig(c.pose_covariance.topLeftCorner<2, 2>());
    if (std::sqrt(eig.eigenvalues().maxCoeff()) <= 0.15) {
      sum += error;
      ++confident;
    }
    // Whole: within 0.5 m, or (a sparse view near the coverage limit) within 1 m while its stated
    // covariance says so (within 3 sigma along the error). Measured: one fix at 46 m from 24 points,
    // 0.58 m off with a stated sigma of 0.33 m across the road; the rest within 0.09 m. A fragment
    // fixed as the whole vehicle is a metre off while it claims centimetres, and fails both.
    const Eigen::Vector2d e(dx, dy);
    const double mahalanobis = std::sqrt(e.dot(c.pose_covariance.topLeftCorner<2, 2>().inverse() * e));
    EXPECT_TRUE(error < 0.5 || (error < 1.0 && mahalanobis < 3.0))
        << "at x = " << truth.x << ": " << c.quality.points_used << " points, " << error << " m off, "
        << mahalanobis << " sigma";
    // Honest covariance: the error along each map axis within 4 sigma (plus 5 cm for the
    // vehicle's motion during its own sweep).
    EXPECT_LT(std::abs(dx), 4.0 * std::sqrt(c.pose_covariance(0, 0)) + 0.05) << "at x = " << truth.x;
    EXPECT_LT(std::abs(dy), 4.0 * std::sqrt(c.pose_covariance(1, 1)) + 0.05) << "at x = " << truth.x;
    const double yaw_error = angle_distance(c.pose.yaw, truth.yaw);
    EXPECT_LT(yaw_error, 4.0 * std::sqrt(c.pose_covariance(2, 2)) + deg_to_rad(1.0)) << "at x = " << truth.x;
  }
  ASSERT_GE(confident, 4);
  EXPECT_LT(sum / confident, 0.15);
  EXPECT_GT(core.lidar_stats().fragments_merged, 0U);  // the geometry does produce fragments
}

// What the mis-association street's run through RsuCore sent, judged against the truth.
struct StreetRun {
  std::size_t corrections = 0;
  std::size_t wrong_vehicle = 0;  // nearer another vehicle's true place than its own
  std::size_t beyond_3sigma = 0;  // position NEES (2 dof) beyond the 3-sigma quantile
  std::size_t hmi = 0;            // ... and more than 0.30 m off
  double max_error_m = 0.0;
  LidarStats stats;
};

constexpr double kChi2TwoDof3Sigma = 11.829;  // P(chi2_2 <= x) = 0.9973
constexpr double kHmiErrorM = 0.30;

// The mis-association street (tests/integration/scenarios/occlusion_street.yaml) with its VLP-32C raised
// from 2 m to `mount_z` (issue 12, README "An elevated RSU"), from the moment its vehicles are in view
// for `rotations` rotations: the connected cars 1, 3, 5 and 6 announce as rsu-fleet makes them (their true
// poses moved 0.3 m along +x and -y) every rotation. Each correction is checked against the truth of every
// vehicle of the street at its sweep time (connected or not): it must be nearer its own vehicle's than
// any other's, and not grossly off.
// max_position_sigma_m: the fix's cap (0: the default).
StreetRun expect_each_correction_its_own_vehicles(double mount_z, int rotations, bool track = true,
                                                  double max_position_sigma_m = 0.0) {
  sim::Scenario street =
      sim::load_scenario_file(RSU_SOURCE_DIR "/tests/integration/scenarios/occlusion_street.yaml");
  street.lidar.mount.z = mount_z;
  constexpr int kEmptyRotations = 4;
  testing::SimStream stream(street.scene, street.scene.vehicles, lidar::make_vlp32c(), street.lidar.mount,
                            street.lidar.noise, kEmptyRotations);
  RsuCoreConfig config;
  config.sensor_model = "vlp32c";
  config.mount = street.lidar.mount;
  config.background.learning_frames = 3;
  config.security.mode = v2i::SecurityMode::kInsecure;
  config.footprint_track.enabled = track;
  if (max_position_sigma_m > 0.0)
    config.perception.fix.correction.max_position_sigma_m = max_position_sigma_m;
  RsuCore core(config);
  const TimeNs rotation = stream.rotation_ns();
  const TimeNs start = (kEmptyRotations + 1) * rotation;  // the street's vehicles are in view from here
  const TimeNs until = start + rotations * rotation;
  stream.run_until(core, start);
  const std::vector<std::uint32_t> connected{1, 3, 5, 6};
  std::uint32_t sequence = 1;
  for (TimeNs t = start; t < until; t += rotation, ++sequence) {
    for (const std::uint32_t id : connected) {
      const sim::Vehicle& v = street.scene.vehicles.at(id - 1);
      EXPECT_EQ(v.id, id);
      const Pose2 truth = sim::pose_at(v.trajectory, t);
      const sim::Velocity2 velocity = sim::velocity_at(v.trajectory, t);
      const std::string address = "192.0.2." + std::to_string(id);
      v2i::VehicleAnnouncement a =
          testing::announce(id, sequence, t, {truth.x + 0.3, truth.y - 0.3, truth.yaw}, address);
      a.size = {v.shape.length, v.shape.width, v.shape.height};
      a.speed_mps = velocity.vx * std::cos(truth.yaw) + velocity.vy * std::sin(truth.yaw);
      EXPECT_TRUE(
          core.on_datagram(v2i::encode_v2i_message(a), {address, testing::kVehiclePort}, t).accepted());
    }
    stream.run_until(core, t + rotation);
  }
  StreetRun run;
  for (const auto& [out, emitted_at] : stream.corrections()) {
    const v2i::Correction& c = out.correction;
    Eigen::Vector2d own_error = Eigen::Vector2d::Zero();
    double nearest_other = std::numeric_limits<double>::infinity();
    for (const sim::Vehicle& v : street.scene.vehicles) {
      const Pose2 truth = sim::pose_at(v.trajectory, c.sweep_time);
      const Eigen::Vector2d e(c.pose.x - truth.x, c.pose.y - truth.y);
      if (v.id == c.vehicle_id)
        own_error = e;
      else
        nearest_other = std::min(nearest_other, e.norm());
    }
    const double own = own_error.norm();
    EXPECT_LT(own, nearest_other) << mount_z << " m up: vehicle " << c.vehicle_id
                                  << " given another's place at " << c.pose.x << ", " << c.pose.y
                                  << " (swept at " << to_seconds(c.sweep_time) << " s)";
    // Not grossly off: within 1 m, or within 3 sigma of what it states (with the cap at 1 m, fixes
    // stating up to 1 m are 1.0-1.6 m off 6-8 m up).
    const Eigen::Matrix2d cov = c.pose_covariance.topLeftCorner<2, 2>();
    const double nees = own_error.dot(cov.ldlt().solve(own_error));
    EXPECT_TRUE(own < 1.0 || nees <= kChi2TwoDof3Sigma)
        << mount_z << " m up: vehicle " << c.vehicle_id << " at " << to_seconds(c.sweep_time) << " s, " << own
        << " m off";
    run.wrong_vehicle += own >= nearest_other ? 1 : 0;
    run.beyond_3sigma += nees > kChi2TwoDof3Sigma ? 1 : 0;
    run.hmi += nees > kChi2TwoDof3Sigma && own > kHmiErrorM ? 1 : 0;
    run.max_error_m = std::max(run.max_error_m, own);
  }
  run.corrections = stream.corrections().size();
  run.stats = core.lidar_stats();
  return run;
}

// 6 m up, the first 1.3 s: connected car 6 drives west 1.6 m beside unconnected car 7, which the LiDAR
// sees whole over it. Car 6's own cluster was assigned, fixed and refused (its place open) early in the
// sweep; car 7's, released a few milliseconds later, lay mostly inside car 6's grown footprint and was
// gathered for it, alone: its place, 3.5 m off at 30-110 sigma, went out as car 6's (3 of the first 8
// rotations).
TEST(RsuCoreFragments, ElevatedLidarGivesNoVehicleItsNeighbourBesideIt) {
  // 13 corrections were sent before the fix, 3 of them car 7's place.
  const StreetRun run = expect_each_correction_its_own_vehicles(6.0, 8);
  EXPECT_GE(run.corrections, 8U);
  EXPECT_GT(run.stats.corrections_unassigned, 0U);  // car 7's clusters, gathered for car 6 and withheld
}

// 4 m up, the first 3.35 s: a queueing car's bonnet, 4.5 m behind the centre of connected car 1, passed
// its gate by the unseen-extent spread and pulled its fix 2 m back (1.9 s); once the queue stands,
// connected car 3's own cluster is refused (its place open) and unconnected car 2's, ahead of it in its
// lane, was gathered for it alone and sent as its place, 6.5 m off (3.2 and 3.3 s).
TEST(RsuCoreFragments, ElevatedLidarGivesNoVehicleTheOneQueueingBeforeOrBehindIt) {
  const StreetRun run = expect_each_correction_its_own_vehicles(4.0, 29);
  EXPECT_GE(run.corrections, 80U);  // 95 measured
  // Seen from 4 m up some rotations leave a car's place along it open; the footprint tracked over the
  // rotations bounds some of them (footprint_track.h), none of them wrong (above) or beyond 3 sigma.
  EXPECT_GT(run.stats.track_bounded, 0U);
  EXPECT_EQ(run.beyond_3sigma, 0U);
}

// The README's table of the whole street (78 rotations of 4 connected vehicles) at 4, 6 and 8 m, with the
// fix's cap as shipped and at 1 m (README "The cap at 1 m, an operator's choice"): slow (about 20 s), so
// run by hand: rsu_fragment_tests --gtest_also_run_disabled_tests --gtest_filter='*WholeStreet*'. It
// prints each row and asserts what the table promises.
TEST(RsuCoreFragments, DISABLED_WholeStreetAtElevatedMounts) {
  for (const double cap : {0.0, 1.0}) {
    for (const double z : {4.0, 6.0, 8.0}) {
      for (const bool track : {false, true}) {
        const StreetRun run = expect_each_correction_its_own_vehicles(z, 78, track, cap);
        const LidarStats& s = run.stats;
        std::printf(
            "cap %s, street %.0f m, track %s: corrections %zu, withheld %zu of 312, wrong vehicle %zu, "
            "beyond 3 sigma %zu, HMI %zu, max %.3f m, unassigned %llu, bounded by the track %llu, "
            "tightened %llu, conflicts %llu, resets %llu\n",
            cap > 0.0 ? "1 m" : "as shipped", z, track ? "on" : "off", run.corrections,
            312 - std::min<std::size_t>(312, run.corrections), run.wrong_vehicle, run.beyond_3sigma, run.hmi,
            run.max_error_m, static_cast<unsigned long long>(s.corrections_unassigned),
            static_cast<unsigned long long>(s.track_bounded),
            static_cast<unsigned long long>(s.track_tightened),
            static_cast<unsigned long long>(s.track_conflicts),
            static_cast<unsigned long long>(s.track_resets));
        EXPECT_EQ(run.wrong_vehicle, 0U) << z;
        EXPECT_EQ(run.hmi, 0U) << z;
        EXPECT_LE(run.beyond_3sigma * 100, run.corrections) << z;  // at most 1 %
      }
    }
  }
}

}  // namespace
}  // namespace rsu::core
