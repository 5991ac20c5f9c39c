// SPDX-License-Identifier: Apache-2.0
// The corridor experiment's hard case (issue 5): the vehicle approaching the roadside VLP-32C head-on
// from 50 m to 30 m. There its points break into a few small clusters (front face and bumper low,
// cabin high, the hood between rings; the curb hedges hide the lower side) that the VLP-32C's
// per-laser azimuth offsets release in different batches of the sweep. A fix from one fragment is a
// metre off while it claims centimetres; RsuCore must gather the fragments (or send nothing), and the
// covariance it sends must cover the error it makes.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Eigenvalues>

#include "common/angles.h"
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
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(c.pose_covariance.topLeftCorner<2, 2>());
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

}  // namespace
}  // namespace rsu::core
