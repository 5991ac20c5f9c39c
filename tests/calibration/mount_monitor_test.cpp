// rsud's mount integrity check (calibration/mount_monitor.h) against the simulator's truth: the corridor
// simulated from the mount its reference was learned under, then from a mount moved by a known amount.
// The registration must find the motion; a bump beyond the tolerance must stop the fixes at its first
// rotation, a slow lean when (and only when) what it does to a fix at the coverage radius crosses the
// tolerance, and a LiDAR put back must resume them after the calm time.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "calibration/mount_monitor.h"
#include "common/angles.h"
#include "sim/lidar_simulator.h"
#include "sim/scenario.h"

namespace rsu {
namespace {

constexpr double kRadius = 50.0;
constexpr TimeNs kRotation = 100'000'000;

class MountMonitorTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    scenario_ =
        new sim::Scenario(sim::load_scenario_file(std::string(RSU_SOURCE_DIR) + "/scenarios/corridor.yaml"));
    scenario_->scene.vehicles.clear();
    raycaster_ = new sim::Raycaster(scenario_->scene);
  }
  static void TearDownTestSuite() {
    delete raycaster_;
    delete scenario_;
  }
  static const Pose3& mount() { return scenario_->lidar.mount; }

  // The rotation starting at rotation index k (its own noise) seen from the mount moved by `motion`
  // (in the sensor frame: mount * motion).
  static std::vector<lidar::LidarPoint> rotation(int k, const Pose3& motion) {
    const Eigen::Isometry3d moved = mount().to_isometry() * motion.to_isometry();
    const Eigen::Vector3d rpy = moved.linear().eulerAngles(2, 1, 0);
    const Pose3 pose{
        moved.translation().x(), moved.translation().y(), moved.translation().z(), rpy[2], rpy[1], rpy[0]};
    const sim::LidarSimulator simulator(scenario_->lidar.model, pose, scenario_->lidar.noise, *raycaster_);
    return simulator.simulate_frame(k * kRotation).frame.points;
  }

  static calibration::MountMonitor monitor(const calibration::MountMonitorConfig& config = {}) {
    return calibration::MountMonitor({rotation(0, {}), rotation(1, {})}, mount(), kRadius, mount().z, config);
  }

  // What a moved mount does to a fix, derived on the map side: a vehicle at X (map) is seen at
  // M'^-1 X and placed at M M'^-1 X; the largest horizontal error over X at the radius, on the road.
  static double true_error(const Pose3& motion) {
    const Eigen::Isometry3d m = mount().to_isometry();
    const Eigen::Isometry3d placed = m * (m * motion.to_isometry()).inverse();
    double worst = 0.0;
    for (int k = 0; k < 360; ++k) {
      const double phi = deg_to_rad(k);
      const Eigen::Vector3d x(mount().x + kRadius * std::cos(phi), mount().y + kRadius * std::sin(phi), 0.0);
      worst = std::max(worst, (placed * x - x).head<2>().norm());
    }
    return worst;
  }

  static sim::Scenario* scenario_;
  static sim::Raycaster* raycaster_;
};

sim::Scenario* MountMonitorTest::scenario_ = nullptr;
sim::Raycaster* MountMonitorTest::raycaster_ = nullptr;

TEST_F(MountMonitorTest, StillMountStaysServingAndEstimatesNoMotion) {
  calibration::MountMonitor m = monitor();
  EXPECT_GT(m.reference_planes(), 1000U);
  for (int k = 2; k < 6; ++k) {
    EXPECT_FALSE(m.check_rotation(rotation(k, {}), k * kRotation));
    const calibration::MountDrift& d = m.last();
    std::printf("still: error at %.0f m %.4f m, motion (%.4f, %.4f, %.4f) m, yaw %.4f deg, %zu matched\n",
                kRadius, d.error_at_radius_m, d.motion.x, d.motion.y, d.motion.z, rad_to_deg(d.motion.yaw),
                d.matches);
    EXPECT_TRUE(d.observable && d.matches_reference);
    EXPECT_LT(d.error_at_radius_m, 0.4 * 0.05);  // the check's own noise: well within the tolerance
  }
  EXPECT_TRUE(m.serving());
  EXPECT_EQ(m.stats().stops, 0U);
}

TEST_F(MountMonitorTest, BumpStopsFixesAtOnceAndIsMeasured) {
  calibration::MountMonitor m = monitor();
  EXPECT_FALSE(m.check_rotation(rotation(2, {}), 2 * kRotation));
  // Across the street: along it the corridor's flat facades hold nothing (its degenerate direction,
  // which the estimate's covariance states; see the README's shortfalls).
  const Pose3 bump{0.0, 0.05, 0.0, 0.0, 0.0, deg_to_rad(0.5)};
  ASSERT_TRUE(m.check_rotation(rotation(3, bump), 3 * kRotation)) << m.last().error_at_radius_m;
  EXPECT_FALSE(m.serving());
  const calibration::MountDrift& d = m.last();
  std::printf(
      "bump: motion (%.4f, %.4f, %.4f) m, roll %.4f pitch %.4f yaw %.4f deg; error %.3f m (true %.3f)\n",
      d.motion.x, d.motion.y, d.motion.z, rad_to_deg(d.motion.roll), rad_to_deg(d.motion.pitch),
      rad_to_deg(d.motion.yaw), d.error_at_radius_m, true_error(bump));
  std::printf("bump: sigma x %.4f y %.4f m, yaw %.4f deg\n", std::sqrt(d.covariance(0, 0)),
              std::sqrt(d.covariance(1, 1)), rad_to_deg(std::sqrt(d.covariance(5, 5))));
  EXPECT_NEAR(d.motion.y, 0.05, 0.01);
  EXPECT_NEAR(rad_to_deg(d.motion.yaw), 0.5, 0.02);
  EXPECT_NEAR(d.error_at_radius_m, true_error(bump), 0.1 * true_error(bump));
  EXPECT_NE(m.notice().find("fixes stopped"), std::string::npos) << m.notice();
  EXPECT_NE(m.reason().find("yaw 0.5"), std::string::npos) << m.reason();
  // Still bumped: stays stopped; put back: resumes only after a second of calm rotations.
  EXPECT_FALSE(m.check_rotation(rotation(4, bump), 4 * kRotation));
  TimeNs t = 5 * kRotation;
  int calm = 0;
  while (!m.check_rotation(rotation(static_cast<int>(t / kRotation), {}), t)) {
    ++calm;
    t += kRotation;
    ASSERT_LT(calm, 20) << "never resumed";
  }
  EXPECT_TRUE(m.serving());
  EXPECT_EQ(calm, 10);  // 1 s of calm rotations at 10 Hz, the first of them included
  EXPECT_EQ(m.stats().stops, 1U);
  EXPECT_EQ(m.stats().resumes, 1U);
}

TEST_F(MountMonitorTest, SlowLeanStopsFixesWhenItsErrorCrossesTheTolerance) {
  calibration::MountMonitor m = monitor();
  // A pole leaning: 0.004 deg of yaw and pitch and 0.4 mm per rotation (sped up ~1e5 times).
  for (int k = 2; k < 80; ++k) {
    const double s = k - 2;
    const Pose3 lean{0.0004 * s, 0.0, 0.0, 0.0, deg_to_rad(0.004 * s), deg_to_rad(0.004 * s)};
    const bool changed = m.check_rotation(rotation(k, lean), k * kRotation);
    if (!changed)
      continue;
    const double truth = true_error(lean);
    std::printf("lean: stopped at rotation %d, true error %.4f m, estimated %.4f m\n", k, truth,
                m.last().error_at_radius_m);
    EXPECT_GT(truth, 0.8 * 0.05);  // not long before the tolerance ...
    EXPECT_LT(truth, 1.3 * 0.05);  // ... nor long after
    EXPECT_FALSE(m.serving());
    return;
  }
  FAIL() << "the lean never stopped the fixes";
}

TEST_F(MountMonitorTest, RemountByMetresStopsFixesAsNotTheReference) {
  calibration::MountMonitor m = monitor();
  ASSERT_TRUE(m.check_rotation(rotation(2, Pose3{2.0, 1.0, 0.0, 0.0, 0.0, deg_to_rad(20.0)}), 2 * kRotation));
  EXPECT_FALSE(m.serving());
  EXPECT_FALSE(m.last().matches_reference);
  EXPECT_EQ(m.stats().rotations_mismatched, 1U);
  std::printf("remount: %zu matched, %s\n", m.last().matches, m.reason().c_str());
}

TEST_F(MountMonitorTest, TooFewStaticPointsDecideNothing) {
  calibration::MountMonitor m = monitor();
  const std::vector<lidar::LidarPoint> full = rotation(2, Pose3{0.0, 0.3, 0.0, 0.0, 0.0, deg_to_rad(3.0)});
  const std::vector<lidar::LidarPoint> part(full.begin(), full.begin() + 200);  // a sliver of a rotation
  EXPECT_FALSE(m.check_rotation(part, 2 * kRotation));
  EXPECT_TRUE(m.serving());
  EXPECT_EQ(m.stats().rotations_unobservable, 1U);
}

}  // namespace
}  // namespace rsu
