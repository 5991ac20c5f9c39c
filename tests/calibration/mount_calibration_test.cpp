// SPDX-License-Identifier: Apache-2.0
// rsu-calibrate's registration against the simulator's truth: the background of a known mount, simulated
// by the project's LiDAR simulator, registered against the map sampled from the same static scene, from
// a rough start (about 2 m and 12 deg off). The mount must come back within 2 cm / 0.05 deg, the stated
// covariance must cover the error (3 sigma), and a street with nothing along it must be called ambiguous.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <random>

#include "calibration/coarse_search.h"
#include "common/angles.h"
#include "eval/corridor/map_sampling.h"
#include "sim/lidar_simulator.h"
#include "sim/scenario.h"
#include "tools/rsu_calibrate/mount_calibration.h"

namespace rsu {
namespace {

struct Case {
  tools::CalibrationResult result;
  Pose3 truth;
};

Case calibrate_in(const sim::Scene& static_scene, const sim::LidarConfig& lidar, const Pose3& truth,
                  const Pose3& start_offset) {
  const sim::Raycaster raycaster(static_scene);
  const sim::LidarSimulator simulator(lidar.model, truth, lidar.noise, raycaster);
  const sim::SimulatedFrame frame = simulator.simulate_frame(0);
  std::vector<Eigen::Vector3d> background;
  for (const lidar::LidarPoint& p : frame.frame.points)
    background.emplace_back(p.x, p.y, p.z);
  const std::vector<Eigen::Vector3f> map = eval::sample_static_map(raycaster, 0.25, 5);
  const Pose3 start{truth.x + start_offset.x,         truth.y + start_offset.y,
                    truth.z + start_offset.z,         truth.roll + start_offset.roll,
                    truth.pitch + start_offset.pitch, truth.yaw + start_offset.yaw};
  return Case{tools::calibrate_mount(background, map, start), truth};
}

sim::Scenario corridor() {
  sim::Scenario s = sim::load_scenario_file(std::string(RSU_SOURCE_DIR) + "/scenarios/corridor.yaml");
  s.scene.vehicles.clear();  // the background: the street without traffic
  return s;
}

// Error of each parameter and its stated standard deviation.
void expect_accurate_and_covered(const Case& c) {
  const Pose3& p = c.result.pose;
  const double error[6] = {p.x - c.truth.x,
                           p.y - c.truth.y,
                           p.z - c.truth.z,
                           wrap_angle(p.roll - c.truth.roll),
                           wrap_angle(p.pitch - c.truth.pitch),
                           wrap_angle(p.yaw - c.truth.yaw)};
  const char* names[6] = {"x", "y", "z", "roll", "pitch", "yaw"};
  ASSERT_EQ(c.result.verdict.verdict, calibration::Verdict::kGood) << c.result.verdict.reason;
  for (int i = 0; i < 6; ++i) {
    const double sigma = std::sqrt(c.result.uncertainty.covariance(i, i));
    const double limit = i < 3 ? 0.02 : deg_to_rad(0.05);
    EXPECT_LT(std::abs(error[i]), limit) << names[i] << " error " << error[i];
    EXPECT_LE(std::abs(error[i]), 3.0 * sigma) << names[i] << " error " << error[i] << " sigma " << sigma;
    std::printf("%-5s error %+.5f%s  sigma %.5f%s\n", names[i], i < 3 ? error[i] : rad_to_deg(error[i]),
                i < 3 ? " m  " : " deg", i < 3 ? sigma : rad_to_deg(sigma), i < 3 ? " m" : " deg");
  }
  std::printf("rms %.4f m, %zu matched (%zu on walls and poles), %d iterations\n", c.result.fit.rms_m,
              c.result.fit.matches, c.result.fit.vertical_matches, c.result.iterations);
}

TEST(MountCalibration, CorridorFromTwoMetresAndTwelveDegreesOff) {
  const sim::Scenario s = corridor();
  const Case c =
      calibrate_in(s.scene, s.lidar, s.lidar.mount, Pose3{1.5, -1.3, 0.1, 0.0, 0.0, deg_to_rad(12.0)});
  expect_accurate_and_covered(c);
}

TEST(MountCalibration, ElevatedTiltedMountFromTheOtherSide) {
  // A 5 m pole leaning into the street (pitch and roll as a bracket leaves them), the start off the
  // other way.
  const sim::Scenario s = corridor();
  const Pose3 truth{3.0, -8.7, 5.0, deg_to_rad(1.2), deg_to_rad(-4.0), deg_to_rad(95.0)};
  const Case c = calibrate_in(s.scene, s.lidar, truth,
                              Pose3{-1.2, 1.6, -0.2, deg_to_rad(-1.0), deg_to_rad(2.0), deg_to_rad(-14.0)});
  expect_accurate_and_covered(c);
}

TEST(MountCalibration, FeaturelessStreetIsAmbiguousNotConfident) {
  // Two flat walls longer than the sensor's range and the ground: nothing fixes the position along the
  // street.
  sim::Scenario s = corridor();
  s.scene.buildings = {sim::Building{0, -26, 0, 500, 30, 45}, sim::Building{0, 26, 0, 500, 30, 60}};
  s.scene.ground.half_extent_m = 250.0;
  s.scene.poles.clear();
  s.scene.shrubs.clear();
  s.scene.trees.clear();
  const Case c =
      calibrate_in(s.scene, s.lidar, s.lidar.mount, Pose3{1.5, -1.3, 0.1, 0.0, 0.0, deg_to_rad(12.0)});
  EXPECT_EQ(c.result.verdict.verdict, calibration::Verdict::kAmbiguous) << c.result.verdict.reason;
  EXPECT_NE(c.result.verdict.reason.find("degenerate"), std::string::npos) << c.result.verdict.reason;
  // The weakest direction is along the street.
  EXPECT_GT(std::abs(c.result.uncertainty.weakest_position_direction.x()), 0.9);
  std::printf("%s\n", c.result.verdict.reason.c_str());
}

TEST(MountCalibration, EmptyFieldFailsForTooFewStructures) {
  sim::Scenario s = corridor();
  s.scene.buildings.clear();
  s.scene.poles.clear();
  s.scene.shrubs.clear();
  s.scene.trees.clear();
  const Case c =
      calibrate_in(s.scene, s.lidar, s.lidar.mount, Pose3{1.0, 1.0, 0.0, 0.0, 0.0, deg_to_rad(10.0)});
  EXPECT_EQ(c.result.verdict.verdict, calibration::Verdict::kFailed) << c.result.verdict.reason;
  EXPECT_NE(c.result.verdict.reason.find("too few structures"), std::string::npos) << c.result.verdict.reason;
}

TEST(MountCalibration, PointsWithoutAVoxelAreLeftOut) {
  // An organized cloud's NaN and absurd coordinates in the map or the background: left out, no crash.
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const std::vector<Eigen::Vector3f> map = {{nan, 0, 0}, {1e30F, 0, 0}, {1.0F, 2.0F, 3.0F}};
  const calibration::VoxelOccupancy occupancy(map, 0.5);
  EXPECT_TRUE(occupancy.occupied(Eigen::Vector3d(1.1, 2.1, 3.1)));
  EXPECT_FALSE(occupancy.occupied(Eigen::Vector3d(std::nan(""), 0, 0)));
  EXPECT_FALSE(occupancy.occupied(Eigen::Vector3d(1e300, 0, 0)));
  const std::vector<Eigen::Vector3d> background = {{std::nan(""), 1, 1}, {1e300, 0, 0}, {5, 0, 0}};
  const tools::CalibrationResult r = tools::calibrate_mount(background, map, Pose3{});
  EXPECT_EQ(r.background_points, 1U);
  EXPECT_EQ(r.verdict.verdict, calibration::Verdict::kFailed);
}

// The voxel key against its definition, computed here with std::floor: the voxel's integer corner on
// each axis, offset by 2^20, 21 bits each; none for NaN or beyond +-(2^20 - 1) voxels. Points on voxel
// boundaries (integers, -0), just either side of them, negative and positive, at three voxel sizes.
TEST(MountCalibration, VoxelKeysAreTheirVoxelsCorners) {
  const auto by_floor = [](const Eigen::Vector3d& p, double size) -> std::optional<std::int64_t> {
    std::int64_t k = 0;
    for (int axis = 0; axis < 3; ++axis) {
      const double cell = p[axis] / size;
      if (!(std::abs(cell) < static_cast<double>((1 << 20) - 1)))
        return std::nullopt;
      k = (k << 21) | ((static_cast<std::int64_t>(std::floor(cell)) + (1 << 20)) & ((1 << 21) - 1));
    }
    return k;
  };
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> metres(-300.0, 300.0);
  std::uniform_int_distribution<int> voxels(-2000, 2000);
  int checked = 0;
  for (const double size : {0.5, 0.1, 2.0}) {
    for (int i = 0; i < 100'000; ++i) {
      Eigen::Vector3d p(metres(rng), metres(rng), metres(rng));
      if (i % 2 == 0) {  // on a voxel boundary, or the next double either side of it
        const double edge = voxels(rng) * size;
        p.y() = i % 6 == 0 ? edge : std::nextafter(edge, i % 6 == 2 ? -1e9 : 1e9);
      }
      ASSERT_EQ(calibration::voxel_key(p, size), by_floor(p, size)) << p.transpose() << " at " << size;
      ++checked;
    }
  }
  EXPECT_EQ(checked, 300'000);
  for (const Eigen::Vector3d& p : {Eigen::Vector3d(-0.0, 0.0, -1e-300), Eigen::Vector3d(-0.5, 0.5, -0.25)})
    EXPECT_EQ(calibration::voxel_key(p, 0.5), by_floor(p, 0.5)) << p.transpose();
  EXPECT_FALSE(calibration::voxel_key(Eigen::Vector3d(std::nan(""), 0, 0), 0.5));
  EXPECT_FALSE(calibration::voxel_key(Eigen::Vector3d(0, 0, 0.5 * ((1 << 20) - 1)), 0.5));
  EXPECT_TRUE(calibration::voxel_key(Eigen::Vector3d(0, 0, 0.5 * ((1 << 20) - 2)), 0.5));
}

}  // namespace
}  // namespace rsu
