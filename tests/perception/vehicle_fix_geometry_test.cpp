// SPDX-License-Identifier: Apache-2.0
// The fix on the views a roadside LiDAR really gets (issue 12): the simulator's vehicle body (hood,
// glasshouse narrower than the body, rounded corners, wheels) seen by a VLP-16 / VLP-32C on a mast, not
// a box. Each case must give a fix that is right (within 0.10 m) or whose stated covariance covers its
// error (position inside the 2-dof 3-sigma ellipse, yaw within 3 sigma), or no fix with a named reason;
// and the case must be the view it claims (the test checks the points it got), so that it cannot pass
// on an easier view.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Cholesky>

#include "common/angles.h"
#include "common/pose.h"
#include "common/time.h"
#include "lidar/point_eigen.h"
#include "lidar/sensor_model.h"
#include "perception/azimuth_thinning.h"
#include "perception/detection.h"
#include "perception/face_envelope.h"
#include "perception/l_shape_criteria.h"
#include "perception/vehicle_fix.h"
#include "sim/lidar_simulator.h"
#include "sim/scenario.h"
#include "sim/scene.h"
#include "sim/trajectory.h"

namespace rsu::perception {
namespace {

constexpr double kChi2TwoDof3Sigma = 11.829;  // P(chi2_2 <= x) = 0.9973
// Returns this close to the road are the ground's to the foreground filter (the pilot drops them too).
constexpr double kGroundFilterM = 0.2;

// A small hatchback and an SUV (the simulator's default body: the paper's test vehicle).
sim::VehicleShape hatchback() {
  sim::VehicleShape s;
  s.length = 3.9;
  s.width = 1.72;
  s.height = 1.5;
  s.belt_height = 0.92;
  s.cabin_inset = 0.12;
  s.hood_length = 0.8;
  s.windscreen_run = 0.7;
  s.rear_slope_run = 0.25;
  s.corner_radius = 0.3;
  s.wheelbase = 2.5;
  s.wheel_radius = 0.3;
  return s;
}

// A panel van: tall and boxy, its belt line (the bonnet's top, 1.2 m) under half its height.
sim::VehicleShape panel_van() {
  return {.length = 5.4,
          .width = 2.0,
          .height = 2.45,
          .corner_radius = 0.22,
          .ground_clearance = 0.2,
          .belt_height = 1.2,
          .cabin_inset = 0.05,
          .hood_length = 0.7,
          .windscreen_run = 0.5,
          .rear_slope_run = 0.05,
          .wheel_radius = 0.34,
          .wheel_width = 0.22,
          .wheelbase = 3.4};
}

// A city bus: flat front, windows from about a third of its height.
sim::VehicleShape city_bus() {
  return {.length = 12.0,
          .width = 2.55,
          .height = 3.1,
          .corner_radius = 0.2,
          .ground_clearance = 0.3,
          .belt_height = 1.1,
          .cabin_inset = 0.03,
          .hood_length = 0.15,
          .windscreen_run = 0.1,
          .rear_slope_run = 0.05,
          .wheel_radius = 0.5,
          .wheel_width = 0.3,
          .wheelbase = 6.0};
}

// A box body (a removal lorry's): flat sides up to 2.5 m, its cab's glass 2 cm in.
sim::VehicleShape box_body() {
  return {.length = 6.9,
          .width = 2.35,
          .height = 3.2,
          .corner_radius = 0.1,
          .ground_clearance = 0.35,
          .belt_height = 2.5,
          .cabin_inset = 0.02,
          .hood_length = 0.5,
          .windscreen_run = 0.3,
          .rear_slope_run = 0.0,
          .wheel_radius = 0.45,
          .wheel_width = 0.3,
          .wheelbase = 4.2};
}

// The pilot matrix's vehicles and the second matrix's (README, the pilot matrix), from their files.
sim::VehicleShape vehicle_file(const std::string& name) {
  return sim::load_vehicle_shape_file(std::string(RSU_SOURCE_DIR) + "/scenarios/vehicles/" + name + ".yaml")
      .shape;
}

struct View {
  std::vector<Eigen::Vector3d> points;  // the vehicle's own returns, map frame
  LidarGeometry lidar;
};

// One rotation of `model` on `mount` at time `at`; the vehicle (id 1) follows `trajectory`; `occluders`
// stand in the scene too. Only the vehicle's own returns are kept (the test judges the fix, not the
// segmentation); median_time is theirs.
struct Sweep {
  View view;
  TimeNs median_time = 0;
};

Sweep sweep_of(const lidar::SensorModel& model, const Pose3& mount, const sim::VehicleShape& shape,
               const sim::Trajectory& trajectory, TimeNs at, const std::vector<sim::Building>& occluders,
               std::uint64_t noise_seed = 1) {
  sim::Scene scene;
  scene.ground.half_extent_m = 60.0;
  scene.buildings = occluders;
  sim::Vehicle vehicle;
  vehicle.id = 1;
  vehicle.shape = shape;
  vehicle.trajectory = trajectory;
  scene.vehicles.push_back(vehicle);
  sim::NoiseModel noise;
  noise.seed = noise_seed;
  const sim::LidarSimulator simulator(model, mount, noise, scene);
  const sim::SimulatedFrame frame = simulator.simulate_frame(at);
  Sweep sweep;
  View& view = sweep.view;
  std::vector<TimeNs> times;
  const Eigen::Isometry3d to_map = mount.to_isometry();
  for (std::size_t i = 0; i < frame.frame.points.size(); ++i) {
    const lidar::LidarPoint& p = frame.frame.points[i];
    const Eigen::Vector3d m = to_map * lidar::position_of(p);
    if (m.z() < kGroundFilterM)
      continue;
    // The vehicle's own returns are its points; any other object's are what may hide part of it (rsud
    // knows them as the sweep's other foreground points).
    if (frame.truth[i].surface == sim::SurfaceClass::kVehicle && frame.truth[i].vehicle_id == 1) {
      view.points.push_back(m);
      times.push_back(p.time_ns);
    } else if (frame.truth[i].surface == sim::SurfaceClass::kBuilding) {
      view.lidar.occluders.push_back(m.head<2>());
    }
  }
  view.lidar.position = {mount.x, mount.y, mount.z};
  for (const double e : model.elevation_deg)
    view.lidar.elevations_rad.push_back(deg_to_rad(e));
  view.lidar.azimuth_step_rad = deg_to_rad(model.azimuth_step_deg());
  if (!times.empty()) {
    std::nth_element(times.begin(), times.begin() + static_cast<std::ptrdiff_t>(times.size() / 2),
                     times.end());
    sweep.median_time = times[times.size() / 2];
  }
  return sweep;
}

// One rotation of `model` mounted `height` m above the road at the origin; the vehicle stands at `truth`.
View look(const lidar::SensorModel& model, double height, const sim::VehicleShape& shape, const Pose2& truth,
          const std::vector<sim::Building>& occluders = {}) {
  Pose3 mount;
  mount.z = height;
  return sweep_of(model, mount, shape, sim::StaticPose{truth}, 0, occluders).view;
}

// A cell of the pilot matrix as `rsu-pilot matrix` makes it (eval/pilot/run_matrix.sh: distances from 3 m
// in 1 m steps, the vehicle spinning in place at 60 deg/s, the LiDAR turned half a turn): frame `frame` at
// `distance` m, and the vehicle's pose at its points' median time; `seed`: the matrix's noise seed (--seed).
struct PilotCell {
  View view;
  Pose2 truth;
};

PilotCell pilot_cell(const lidar::SensorModel& model, double height, const sim::VehicleShape& shape,
                     double distance, int frame, std::uint64_t seed = 1) {
  constexpr double kSpinDegPerS = 60.0;
  const TimeNs period = from_seconds(60.0 / model.rpm);
  const auto frames_per_turn = std::lround(360.0 / (kSpinDegPerS * 60.0 / model.rpm));
  const TimeNs t0 = std::lround(distance - 3.0) * frames_per_turn * period;
  const sim::Spin spin{distance, 0.0, 0.0, deg_to_rad(kSpinDegPerS), t0};
  Pose3 mount;
  mount.z = height;
  mount.yaw = std::numbers::pi;
  const Sweep sweep = sweep_of(model, mount, shape, spin, t0 + frame * period, {}, seed);
  return {sweep.view, sim::pose_at(spin, sweep.median_time)};
}

enum class Verdict { right, covered, withheld };

// The fix of `view` with the announced size and a yaw prior `prior_error` off (sigma 10 deg), judged.
Verdict judge(const View& view, const sim::VehicleShape& shape, const Pose2& truth, double prior_error) {
  AnnouncedVehicle announced;
  announced.size = {shape.length, shape.width, shape.height};
  announced.yaw_prior = YawPrior{truth.yaw + prior_error, deg_to_rad(10.0)};
  const VehicleFix fix = fix_vehicle(view.points, announced, view.lidar);
  if (!fix.ok()) {
    // A refusal names its reason (the counters and the vehicle get it).
    EXPECT_NE(to_string(fix.status()), "unknown");
    return Verdict::withheld;
  }
  const Eigen::Vector2d error(fix.corrected.pose.x - truth.x, fix.corrected.pose.y - truth.y);
  const Eigen::Matrix2d cov = fix.corrected.covariance.topLeftCorner<2, 2>();
  const double nees = error.dot(cov.ldlt().solve(error));
  const double yaw_error = angle_distance(fix.corrected.pose.yaw, truth.yaw);
  const double yaw_sigma = std::sqrt(fix.corrected.covariance(2, 2));
  EXPECT_TRUE(error.norm() < 0.10 || nees <= kChi2TwoDof3Sigma)
      << "error " << error.norm() << " m, stated sigma " << std::sqrt(cov.trace()) << " m (NEES " << nees
      << ") at yaw " << rad_to_deg(truth.yaw) << " deg, " << view.points.size() << " points";
  EXPECT_TRUE(yaw_error < deg_to_rad(1.0) || yaw_error <= 3.0 * yaw_sigma)
      << "yaw error " << rad_to_deg(yaw_error) << " deg, stated " << rad_to_deg(yaw_sigma) << " deg at yaw "
      << rad_to_deg(truth.yaw) << " deg";
  return error.norm() < 0.10 ? Verdict::right : Verdict::covered;
}

double highest(const View& v) {
  double z = -1e9;
  for (const auto& p : v.points)
    z = std::max(z, p.z());
  return z;
}

double lowest(const View& v) {
  double z = 1e9;
  for (const auto& p : v.points)
    z = std::min(z, p.z());
  return z;
}

// A VLP-32C 8 m up sees a hatchback 15-17 m away, driving towards or away from it, from above: a few
// rings across the bonnet or boot, the glasshouse and the near end.
TEST(VehicleFixGeometry, TopDownSparseRoofAndOneEnd) {
  const sim::VehicleShape shape = hatchback();
  int fixed = 0, unbounded = 0, cases = 0;
  for (const double distance : {15.0, 16.0, 17.0}) {
    for (const double yaw_deg : {0.0, 180.0, 8.0, 188.0}) {
      const Pose2 truth{distance, 0.0, deg_to_rad(yaw_deg)};
      const View view = look(lidar::make_vlp32c(), 8.0, shape, truth);
      ASSERT_GE(view.points.size(), 3U) << distance;
      // The view claimed: sparse (a few rings), reaching above the belt line (seen from above).
      EXPECT_LT(view.points.size(), 60U) << distance;
      EXPECT_GT(highest(view), shape.belt_height) << distance;
      for (const double prior_error : {deg_to_rad(7.0), deg_to_rad(-7.0)}) {
        ++cases;
        if (judge(view, shape, truth, prior_error) != Verdict::withheld) {
          ++fixed;
          continue;
        }
        AnnouncedVehicle announced;
        announced.size = {shape.length, shape.width, shape.height};
        announced.yaw_prior = YawPrior{truth.yaw + prior_error, deg_to_rad(10.0)};
        unbounded +=
            fix_vehicle(view.points, announced, view.lidar).status() == CorrectionStatus::position_unbounded
                ? 1
                : 0;
      }
    }
  }
  // Withholding every fix would pass the checks above trivially: a withheld fix must be withheld because
  // the points leave the position open over more than max_position_sigma_m (position_unbounded; README,
  // Known shortfalls: elevated mounts), not refused as inconsistent. With the yaw's measured effect on the
  // box in the covariance all 24 are (22 before it, 2 fixed).
  EXPECT_EQ(fixed + unbounded, cases);
}

// A VLP-16 2 m up sees an SUV 35.5 m away, most of it with its -1 deg laser only: one ring across the
// glasshouse, which is narrower than the body and has no hood or boot (the paper's range limit).
TEST(VehicleFixGeometry, SingleRingOnTheGlasshouse) {
  const sim::VehicleShape shape;  // the paper's SUV
  int fixed = 0, cases = 0;
  for (double yaw_deg = 0.0; yaw_deg < 180.0; yaw_deg += 30.0) {
    const Pose2 truth{35.5, 0.0, deg_to_rad(yaw_deg + 3.0)};
    const View view = look(lidar::make_vlp16(), 2.0, shape, truth);
    if (view.points.size() < 3)
      continue;
    // One ring (within a few cm of one height) above the belt line holds much of the returns; the others
    // are the next laser's grazing the sills and tyres.
    const auto ring = std::count_if(view.points.begin(), view.points.end(), [&](const Eigen::Vector3d& p) {
      return p.z() > shape.belt_height && p.z() > highest(view) - 0.1;
    });
    EXPECT_GE(static_cast<double>(ring), 0.4 * static_cast<double>(view.points.size())) << yaw_deg;
    for (const double prior_error : {deg_to_rad(5.0), deg_to_rad(-9.0)}) {
      ++cases;
      fixed += judge(view, shape, truth, prior_error) != Verdict::withheld;
    }
  }
  ASSERT_GE(cases, 8);
  EXPECT_GE(fixed, cases / 2);
}

// A van's ends above its bonnet are not its footprint's: a VLP-16 2 m up sees it 37-40 m away by one ring at
// 1.3-1.4 m (under 55 % of its height, above its 1.2 m belt line), on the windscreen 0.7 m behind the front
// bumper and along the glasshouse's sides; a VLP-32C 6 m up sees it 10 m away from above: the bonnet's top
// at 1.2 m and the glasshouse, not one point of its lower body. Taken for the footprint's ends (the
// bonnet's trace for a face) they put fixes 0.5-0.7 m off while stating 0.1 m (`rsu-pilot matrix`).
TEST(VehicleFixGeometry, VanAboveItsBonnet) {
  const sim::VehicleShape shape = panel_van();
  struct Case {
    bool vlp16;
    double height, distance, yaw_deg;
  };
  int fixed = 0, cases = 0;
  for (const Case& c :
       {Case{true, 2.0, 37.0, 27.0}, Case{true, 2.0, 39.0, 123.0}, Case{true, 2.0, 40.0, 141.0},
        Case{true, 2.0, 35.0, 81.0}, Case{false, 6.0, 10.0, 111.0}, Case{false, 6.0, 10.0, 279.0},
        Case{false, 6.0, 10.0, 81.0}}) {
    const Pose2 truth{c.distance, 0.0, deg_to_rad(c.yaw_deg)};
    const View view = look(c.vlp16 ? lidar::make_vlp16() : lidar::make_vlp32c(), c.height, shape, truth);
    ASSERT_GE(view.points.size(), 10U) << c.distance;
    // The claimed view: no return from the doors or bumpers (below the bonnet's top, above the sills).
    const auto doors = std::count_if(view.points.begin(), view.points.end(), [&](const Eigen::Vector3d& p) {
      return p.z() > 0.4 && p.z() < shape.belt_height - 0.05;
    });
    EXPECT_LE(static_cast<double>(doors), 0.1 * static_cast<double>(view.points.size())) << c.distance;
    for (const double prior_error : {deg_to_rad(6.0), deg_to_rad(-8.0)}) {
      ++cases;
      fixed += judge(view, shape, truth, prior_error) != Verdict::withheld;
    }
  }
  EXPECT_GE(fixed, cases / 2);
}

// A VLP-32C 4 m up sees an SUV 7-8 m away from behind and the side: its rear and roof above the bonnet's
// height, and one laser's trace along the near side that descends as it goes away and leaves the body
// through its sills, not its front: beyond the trace's end only a laser above the bonnet passes, which
// would not see a bonnet. Taken for the front end, it put fixes 1.8 m off stating 0.17 m.
TEST(VehicleFixGeometry, SideTraceLeavingThroughTheSills) {
  const sim::VehicleShape shape;  // the paper's SUV
  int fixed = 0, cases = 0;
  for (const double distance : {7.0, 8.0}) {
    for (const double yaw_deg : {27.0, 33.0, 333.0, 327.0}) {
      const Pose2 truth{distance, 0.0, deg_to_rad(yaw_deg)};
      const View view = look(lidar::make_vlp32c(), 4.0, shape, truth);
      ASSERT_GE(view.points.size(), 30U) << distance;
      // The claimed view: the lowest returns are the trace's end near the sills.
      double lowest = 1e9;
      for (const auto& p : view.points)
        lowest = std::min(lowest, p.z());
      EXPECT_LT(lowest, 0.4) << distance << " " << yaw_deg;
      for (const double prior_error : {deg_to_rad(5.0), deg_to_rad(-4.0)}) {
        ++cases;
        fixed += judge(view, shape, truth, prior_error) != Verdict::withheld;
      }
    }
  }
  // 7 of the 16 are fixed (8 before the yaw's measured effect on the box widened the covariance).
  EXPECT_GE(fixed, cases / 3);
}

// A VLP-32C 4 m up sees an SUV broadside 17.5 m away (its lower body by one ring); a cabinet 1.5 m wide and 3
// m tall, 8 m from the LiDAR, hides a stretch of its near side: the visible face is cut short at the shadow,
// not at the car's end.
TEST(VehicleFixGeometry, TruncatedFaceBehindAnOccluder) {
  const sim::VehicleShape shape;
  sim::Building cabinet;
  cabinet.x = 8.0;
  cabinet.y = 1.0;
  cabinet.length = 1.0;
  cabinet.width = 1.5;
  cabinet.height = 3.0;
  int fixed = 0, cases = 0;
  for (const double yaw_deg : {90.0, 80.0, 100.0, 270.0}) {
    const Pose2 truth{17.5, 0.0, deg_to_rad(yaw_deg)};
    const View view = look(lidar::make_vlp32c(), 4.0, shape, truth, {cabinet});
    const View clear = look(lidar::make_vlp32c(), 4.0, shape, truth);
    ASSERT_GE(view.points.size(), 10U);
    // The claimed view: the cabinet hides a good part of what the LiDAR would see of the car.
    EXPECT_LT(static_cast<double>(view.points.size()), 0.8 * static_cast<double>(clear.points.size()));
    for (const double prior_error : {deg_to_rad(6.0), deg_to_rad(-6.0)}) {
      ++cases;
      fixed += judge(view, shape, truth, prior_error) != Verdict::withheld;
    }
  }
  EXPECT_GE(fixed, cases / 2);
}

// The L-shape criteria by their definitions (Zhang et al. 2017, Alg. 3-5; Autoware), in double over
// every point: the reference for the evaluator's one pass over the points with the edges from the hull.
double reference_criterion(const std::vector<double>& x, const std::vector<double>& y, double theta,
                           const CriterionConfig& config) {
  const std::size_t n = x.size();
  std::vector<double> c1(n), c2(n);
  for (std::size_t i = 0; i < n; ++i) {
    c1[i] = x[i] * std::cos(theta) + y[i] * std::sin(theta);
    c2[i] = -x[i] * std::sin(theta) + y[i] * std::cos(theta);
  }
  const auto [min1, max1] = std::minmax_element(c1.begin(), c1.end());
  const auto [min2, max2] = std::minmax_element(c2.begin(), c2.end());
  if (config.criterion == LShapeCriterion::area)
    return -(*max1 - *min1) * (*max2 - *min2);
  // D: the distances to whichever edge the distance vector is shorter to (squared 2-norms compared).
  auto distances = [&](const std::vector<double>& c, double lo, double hi) {
    double to_lo = 0.0, to_hi = 0.0;
    for (const double v : c) {
      to_lo += (v - lo) * (v - lo);
      to_hi += (hi - v) * (hi - v);
    }
    std::vector<double> d(c.size());
    for (std::size_t i = 0; i < c.size(); ++i)
      d[i] = to_lo <= to_hi ? c[i] - lo : hi - c[i];
    return d;
  };
  double q = 0.0;
  if (config.criterion == LShapeCriterion::closeness) {
    const auto d1 = distances(c1, *min1, *max1), d2 = distances(c2, *min2, *max2);
    for (std::size_t i = 0; i < n; ++i)
      q += 1.0 / std::max(std::min(d1[i], d2[i]), config.closeness_d0_m);
  } else if (config.criterion == LShapeCriterion::variance) {
    const auto d1 = distances(c1, *min1, *max1), d2 = distances(c2, *min2, *max2);
    std::array<double, 2> sum{}, sum_sq{}, count{};
    for (std::size_t i = 0; i < n; ++i) {
      if (d1[i] == d2[i])
        continue;
      const std::size_t e = d1[i] < d2[i] ? 0 : 1;
      const double d = e == 0 ? d1[i] : d2[i];
      sum[e] += d;
      sum_sq[e] += d * d;
      count[e] += 1.0;
    }
    for (std::size_t e = 0; e < 2; ++e) {
      if (count[e] > 0.0)
        q -= sum_sq[e] / count[e] - (sum[e] / count[e]) * (sum[e] / count[e]);
    }
  } else {
    const double max_sq = config.autoware_max_dist_m * config.autoware_max_dist_m;
    for (std::size_t i = 0; i < n; ++i) {
      const double v1 = std::min(*max1 - c1[i], c1[i] - *min1), v2 = std::min(*max2 - c2[i], c2[i] - *min2);
      const double d = std::min(v1 * v1, v2 * v2);
      if (d <= max_sq)
        q += 1.0 / std::max(d, config.autoware_min_sq_m2);
    }
  }
  return q;
}

// A near car on a dense sensor (issue 16: rsud fits such clusters of 7,300-16,700 points) and a far one
// on a sparse sensor: the evaluator equals the criteria's definitions, to float rounding, at every angle.
TEST(VehicleFixGeometry, CriteriaEvaluatedInOnePassEqualTheirDefinitionsOnNearDenseAndFarSparseCars) {
  struct Case {
    lidar::SensorModel model;
    double height;  // the generic sensor looks down 25 deg at most: a low mount sees a near car whole
    Pose2 truth;
    std::size_t min_points, max_points;
  };
  const std::vector<Case> cases = {{lidar::make_generic(128), 2.0, {1.5, 3.6, deg_to_rad(8.0)}, 5000, 100000},
                                   {lidar::make_vlp16(), 4.0, {31.0, 4.0, deg_to_rad(30.0)}, 20, 600}};
  for (const Case& c : cases) {
    const View view = look(c.model, c.height, sim::VehicleShape{}, c.truth);
    // The claimed view: thousands of points near the dense sensor, a few dozen far from the sparse one.
    ASSERT_GE(view.points.size(), c.min_points);
    ASSERT_LE(view.points.size(), c.max_points);
    Eigen::Vector2d centroid = Eigen::Vector2d::Zero();
    for (const auto& p : view.points)
      centroid += p.head<2>();
    centroid /= static_cast<double>(view.points.size());
    std::vector<double> x, y;
    for (const auto& p : view.points) {
      x.push_back(p.x() - centroid.x());
      y.push_back(p.y() - centroid.y());
    }
    for (const auto criterion : {LShapeCriterion::closeness, LShapeCriterion::area, LShapeCriterion::variance,
                                 LShapeCriterion::autoware_closeness}) {
      CriterionConfig config;
      config.criterion = criterion;
      CriterionEvaluator evaluate(x, y, config);
      // Variance and Autoware's closeness count a point by a comparison that float rounding may tip
      // for a point exactly at its threshold: one such point's worth of slack.
      const double relative =
          criterion == LShapeCriterion::closeness || criterion == LShapeCriterion::area ? 1e-5 : 1e-3;
      for (double deg = 0.0; deg < 90.0; deg += 0.7) {
        const double theta = deg_to_rad(deg);
        const double expected = reference_criterion(x, y, theta, config);
        EXPECT_NEAR(evaluate(theta), expected, relative * std::abs(expected) + 1e-9)
            << "criterion " << static_cast<int>(criterion) << " at " << deg << " deg, " << x.size()
            << " points";
      }
    }
  }
}

// The face envelope's EM by its definition (face_envelope.h), every point in every iteration: the
// reference for the envelope's sums over the points within reach of the face only.
FaceEnvelope reference_envelope(std::vector<double> s, double noise_sigma, double band) {
  const double sigma = std::max(noise_sigma, 1e-4);
  band = std::max(band, 4.0 * sigma);
  std::vector<double> sorted = s;
  std::sort(sorted.begin(), sorted.end());
  double f = sorted[static_cast<std::size_t>(0.9 * static_cast<double>(sorted.size() - 1))];
  double weight = 0.5, n_face = 0.0;
  constexpr double kStray = 0.02;
  auto cdf = [](double v) { return 0.5 * std::erfc(-v / std::numbers::sqrt2); };
  for (int iteration = 0; iteration < 30; ++iteration) {
    double sum_r = 0.0, sum_rs = 0.0;
    for (const double v : s) {
      const double face = weight * std::exp(-0.5 * (v - f) * (v - f) / (sigma * sigma)) /
                          (sigma * std::sqrt(2.0 * std::numbers::pi));
      const double inside =
          (1.0 - weight - kStray) / band * (cdf((f - v) / sigma) - cdf((f - band - v) / sigma));
      const double r = face / (face + inside + kStray / (2.0 * band));
      sum_r += r;
      sum_rs += r * v;
    }
    n_face = sum_r;
    if (!(sum_r > 1e-9))
      break;
    const double next = sum_rs / sum_r;
    weight = std::clamp(sum_r / static_cast<double>(s.size()), 0.05, 1.0 - kStray - 0.01);
    const bool converged = std::abs(next - f) < 1e-5;
    f = next;
    if (converged)
      break;
  }
  return {f, sigma / std::sqrt(std::max(n_face, 1.0)), n_face};
}

// The near car's side towards a dense sensor, along its outward normal: thousands of points, most of
// them inside the body (glasshouse, wheels, roof), metres from the face.
TEST(VehicleFixGeometry, FaceEnvelopeOfANearCarsSideEqualsItsEmOverEveryPoint) {
  const Pose2 truth{1.5, 3.6, 0.0};
  const View view = look(lidar::make_generic(128), 2.0, sim::VehicleShape{}, truth);
  ASSERT_GE(view.points.size(), 5000U);
  std::vector<double> s;
  for (const auto& p : view.points)
    s.push_back(truth.y - p.y());  // the side towards the LiDAR (at y = 0) is at + width / 2
  for (const double noise_sigma : {0.01, 0.03}) {
    const FaceEnvelope fast = outer_envelope(s, noise_sigma, 0.3);
    const FaceEnvelope reference = reference_envelope(s, noise_sigma, 0.3);
    EXPECT_NEAR(fast.position, reference.position, 1e-9);
    EXPECT_NEAR(fast.face_points, reference.face_points, 1e-9 * reference.face_points);
    EXPECT_NEAR(fast.sigma, reference.sigma, 1e-12);
    // The claimed case: the face is the body's side, and most points lie behind it.
    EXPECT_NEAR(fast.position, sim::VehicleShape{}.width / 2.0, 0.05);
    EXPECT_LT(fast.face_points, 0.5 * static_cast<double>(s.size()));
  }
}

// The memo the correction shares between its placements gives outer_envelope's result for inputs it has
// seen, and estimates again for inputs that differ in one bit or in the noise.
TEST(VehicleFixGeometry, FaceEnvelopeMemoGivesTheEnvelopeOfExactlyTheseInputs) {
  const Pose2 truth{1.5, 3.6, 0.0};
  const View view = look(lidar::make_generic(128), 2.0, sim::VehicleShape{}, truth);
  std::vector<double> s;
  for (const auto& p : view.points)
    s.push_back(truth.y - p.y());
  std::vector<double> moved = s;
  moved[moved.size() / 2] = std::nextafter(moved[moved.size() / 2], 1.0);
  std::vector<double> first = s;
  first[0] = sim::VehicleShape{}.width / 2.0 + 0.02;  // a point moved onto the face: a different envelope
  FaceEnvelopeMemo memo;
  for (int round = 0; round < 2; ++round) {
    for (const auto& [input, noise_sigma] :
         {std::pair{&s, 0.03}, std::pair{&s, 0.01}, std::pair{&moved, 0.03}, std::pair{&first, 0.03}}) {
      const FaceEnvelope remembered = memo(*input, noise_sigma, 0.3);
      const FaceEnvelope estimated = outer_envelope(*input, noise_sigma, 0.3);
      EXPECT_EQ(remembered.position, estimated.position);
      EXPECT_EQ(remembered.sigma, estimated.sigma);
      EXPECT_EQ(remembered.face_points, estimated.face_points);
    }
  }
  EXPECT_NE(outer_envelope(s, 0.03, 0.3).position, outer_envelope(first, 0.03, 0.3).position);
}

// Views whose points tell nothing of the heading, so that the fix carries the vehicle's own (sigma 10 deg)
// and places the box along it: a bus 9-10 m from a VLP-16 6 m up, seen from above its roof and one end,
// and an SUV 7 m from a VLP-32C 4 m up, end on. The box is bounded by containment at several points (its
// ends, the far side), not by one anchor: placed along a heading 5-10 deg off, its centre moved 0.3-0.6 m
// while the covariance carried a few cm of that yaw's lever arm (`rsu-pilot matrix`: HMI fixes, NEES
// 14-28). The placement's dependence on the yaw is now measured by placing the box again at the yaw +-
// its sigma points.
TEST(VehicleFixGeometry, PriorYawCarriesItsPlacementsDependence) {
  struct Case {
    bool vlp16;
    double height, distance, yaw_deg, prior_error_deg;
  };
  int fixed = 0, cases = 0, from_prior = 0;
  for (const Case& c : {Case{true, 6.0, 9.0, 86.68, 9.59}, Case{true, 6.0, 10.0, -93.05, -5.5},
                        Case{true, 6.0, 10.0, -86.99, 5.66}, Case{false, 4.0, 7.0, -87.02, 9.47}}) {
    const sim::VehicleShape shape = c.vlp16 ? city_bus() : sim::VehicleShape{};
    const Pose2 truth{c.distance, 0.0, deg_to_rad(c.yaw_deg)};
    const View view = look(c.vlp16 ? lidar::make_vlp16() : lidar::make_vlp32c(), c.height, shape, truth);
    ASSERT_GE(view.points.size(), 30U) << c.distance;
    AnnouncedVehicle announced;
    announced.size = {shape.length, shape.width, shape.height};
    announced.yaw_prior = YawPrior{truth.yaw + deg_to_rad(c.prior_error_deg), deg_to_rad(10.0)};
    // The claimed view: the fix's yaw is the vehicle's own (its points tell no heading).
    const VehicleFix fix = fix_vehicle(view.points, announced, view.lidar);
    if (fix.ok())
      from_prior += fix.corrected.yaw_prior_share > 0.9;
    ++cases;
    fixed += judge(view, shape, truth, deg_to_rad(c.prior_error_deg)) != Verdict::withheld;
  }
  EXPECT_GE(from_prior, 3);
  EXPECT_GE(fixed, cases - 1);
}

// Sparse views whose faces' yaw is far off while a line fit to their points would state 2-4 deg: one
// ring across an SUV's front bumper 25 m from a VLP-16 4 m up, whose rounded corner made an 8-point
// "face" 24 deg off; a VLP-16 2 m up seeing an SUV and a small hatchback at 36 m, and a bus 6 m from a
// VLP-32C 6 m up. A face's direction is known as well as its points' spread along it makes it (not the
// fitted edge's length), and faces farther from the vehicle's own heading than both uncertainties allow
// are not used (`rsu-pilot matrix`: such fixes were 0.3-0.8 m off at NEES 20-870).
TEST(VehicleFixGeometry, SparseFaceOffTheVehiclesHeading) {
  struct Case {
    int shape;  // 0 SUV, 1 hatchback, 2 bus
    bool vlp16;
    double height, distance, yaw_deg, prior_error_deg;
  };
  int fixed = 0, cases = 0;
  for (const Case& c : {Case{0, true, 4.0, 25.0, 3.0, 0.6}, Case{0, true, 2.0, 36.0, -146.99, -8.57},
                        Case{1, true, 2.0, 36.0, 39.01, 4.1}, Case{2, false, 6.0, 6.0, 81.05, 0.39},
                        Case{0, false, 8.0, 23.0, 39.03, 8.45}}) {
    const sim::VehicleShape shape =
        c.shape == 0 ? sim::VehicleShape{} : (c.shape == 1 ? hatchback() : city_bus());
    const Pose2 truth{c.distance, 0.0, deg_to_rad(c.yaw_deg)};
    const View view = look(c.vlp16 ? lidar::make_vlp16() : lidar::make_vlp32c(), c.height, shape, truth);
    ASSERT_GE(view.points.size(), 10U) << c.distance;
    ++cases;
    fixed += judge(view, shape, truth, deg_to_rad(c.prior_error_deg)) != Verdict::withheld;
  }
  // The bus 6 m below the mast is withheld since every yaw probe widens its interval
  // (BusIntervalAtEveryProbe: 1.1 m across near its true heading, position_unbounded); it was sent 0.58 m off
  // stating 0.29 m.
  EXPECT_GE(fixed, cases - 2);
}

// One ring's few returns (4-11 over 0.4-0.7 m) at 15-33 m from a mast 4-6 m up: the trace of a rounded
// corner of the body, whose direction is anything between the side's and the end's. Stated 4-7 deg, they
// were 15-27 deg off (`rsu-pilot matrix`); a face this short now departs from the footprint's direction by
// short_face_tilt_m over its length, and the vehicle's own heading weighs in. Without that the first three
// views are HMI fixes (0.42-0.81 m off, NEES 12-21); the others are the pilot's cells.
TEST(VehicleFixGeometry, ShortFaceOnARoundedCorner) {
  struct Case {
    bool suv, vlp16;
    double height, distance, yaw_deg, prior_error_deg;
  };
  int fixed = 0, cases = 0;
  for (const Case& c :
       {Case{true, true, 4.0, 33.0, -141.0, 8.0}, Case{false, false, 4.0, 15.0, -61.0, -8.0},
        Case{false, false, 4.0, 15.0, -61.0, 8.0}, Case{true, true, 4.0, 33.0, -135.0, 7.84},
        Case{false, false, 4.0, 15.0, -57.04, -9.74}, Case{true, false, 6.0, 31.0, 27.01, 9.34},
        Case{false, true, 6.0, 31.0, -111.0, 6.76}}) {
    const sim::VehicleShape shape = c.suv ? sim::VehicleShape{} : hatchback();
    const Pose2 truth{c.distance, 0.0, deg_to_rad(c.yaw_deg)};
    const View view = look(c.vlp16 ? lidar::make_vlp16() : lidar::make_vlp32c(), c.height, shape, truth);
    // The claimed view: sparse.
    ASSERT_GE(view.points.size(), 10U) << c.distance;
    EXPECT_LT(view.points.size(), 120U) << c.distance;
    ++cases;
    fixed += judge(view, shape, truth, deg_to_rad(c.prior_error_deg)) != Verdict::withheld;
  }
  EXPECT_GE(fixed, cases / 2);
}

// The pilot matrix's cells 6-8 m below a VLP-16 / VLP-32C whose fixes were HMI (`rsu-pilot matrix`, the
// vehicle's heading off as the pilot drew it), one test per cause.
struct MatrixCell {
  bool vlp16;
  int shape;  // 0 SUV, 1 bus
  double height, distance;
  int frame;
  double prior_error_deg;
};

// The cell's view, checked to be the one claimed (`min_points`..`max_points` returns), judged.
Verdict judge_cell(const MatrixCell& c, std::size_t min_points, std::size_t max_points) {
  const sim::VehicleShape shape = c.shape == 0 ? sim::VehicleShape{} : city_bus();
  const PilotCell cell =
      pilot_cell(c.vlp16 ? lidar::make_vlp16() : lidar::make_vlp32c(), c.height, shape, c.distance, c.frame);
  EXPECT_GE(cell.view.points.size(), min_points) << c.distance;
  EXPECT_LE(cell.view.points.size(), max_points) << c.distance;
  return judge(cell.view, shape, cell.truth, deg_to_rad(c.prior_error_deg));
}

// One laser's trace over an SUV's rear window and roof, 16-24 m from a mast 6-8 m up, all above the
// bonnet: its horizontal range varies (the surface slopes), so it was taken for a vertical face, 20-23 deg
// off the heading (across the line of sight) while stating 4-6 deg; the fixes were 0.42-0.53 m off at NEES
// 26-29. One laser's trace above the bonnet now departs from the footprint's direction by about the
// laser's depression (informative_face.cpp).
TEST(VehicleFixGeometry, OneLasersTraceOverTheRearWindow) {
  int fixed = 0;
  for (const MatrixCell& c :
       {MatrixCell{true, 0, 8.0, 24.0, 8, 9.39}, MatrixCell{false, 0, 6.0, 16.0, 9, -5.36},
        MatrixCell{false, 0, 8.0, 23.0, 49, 1.98}})
    fixed += judge_cell(c, 30, 80) != Verdict::withheld;
  EXPECT_EQ(fixed, 3);
}

// One laser along an SUV's side 33 m from a VLP-32C 6 m up, crossing the belt line: its few points below
// the bonnet at the front and one at the rear corner 4 m away, on the line a sparse fit drew between them,
// made a 4.9 m "face" 18 deg off while stating 3 deg (0.40 m off, NEES 13). A face's points on either side
// of a gap wider than a short face now count as separate stretches; the longest tells the direction.
TEST(VehicleFixGeometry, FaceSplitByAGapAlongIt) {
  EXPECT_NE(judge_cell({false, 0, 6.0, 33.0, 11, -9.25}, 30, 80), Verdict::withheld);
}

// An SUV 4 m from a VLP-32C 2 m up, seen on a diagonal: its near end and near side, both ends of the
// side counted as the body's ends and spanning its length within 0.3 m, so the box sat at their middle.
// But the far end lies on a rounded corner that the line of sight leaves early: the points spanned
// 0.26-0.28 m less than the length, all of it at one end, and the fixes were 0.15 m off stating 0.04 m
// along the length (NEES 16-17; the matrix's worst 5 m band 1.9 % beyond 3 sigma). The middle of two ends
// now states the uniform spread of the span's shortfall (box_axis.cpp).
TEST(VehicleFixGeometry, BothEndsSpanningLessThanTheLength) {
  for (const auto& [frame, prior_error_deg] : {std::pair{21, -4.236}, std::pair{51, -9.575}})
    EXPECT_NE(judge_cell({false, 0, 2.0, 4.0, frame, prior_error_deg}, 1800, 2600), Verdict::withheld)
        << frame;
}

// An SUV 36 m from a VLP-16 2 m up: its rear and the rear of its near side below, one laser along its
// glasshouse above; the yaw mostly its own heading's (8.8 deg). Placed again 15 deg off, the box moved
// 0.9 m along its length (re-anchored), and that probe's spread stood for the yaw's effect; but a small
// turn about the side's points moves it across (1.9 m/rad): 5.4 deg off, the fix was 0.18 m off across
// stating 0.05 m there (NEES 14.6, the VLP-16's only fix beyond 3 sigma in the matrix at 2 m, 1 of the
// 97 in its worst 5 m band). The turn's spread now covers the lever's as well as the probes'.
TEST(VehicleFixGeometry, YawProbesReanchoringAlongWhileASmallTurnMovesAcross) {
  EXPECT_NE(judge_cell({true, 0, 2.0, 36.0, 51, 2.798}, 30, 40), Verdict::withheld);
}

// A bus 6-9 m from a mast 6 m up, its points telling no heading: placed along the vehicle's own heading
// (8-10 deg off) the across-axis interval is squeezed to 0.36-0.53 m, and the one probe that held the
// points (17 deg the other way) squeezed it more; at the true heading it is 1.1-1.3 m wide. The fixes were
// 0.57-0.71 m off at NEES 13-17; every probe that holds the points now widens the interval.
TEST(VehicleFixGeometry, BusIntervalAtEveryProbe) {
  for (const MatrixCell& c :
       {MatrixCell{true, 1, 6.0, 9.0, 14, 9.59}, MatrixCell{false, 1, 6.0, 6.0, 43, -7.86}})
    EXPECT_NE(judge_cell(c, 100, 600), Verdict::right) << c.distance;
}

// The traffic street's van behind the box truck (`rsu-corridor placement` on
// scenarios/corridor_degraded_traffic_experiment.yaml, a VLP-32C 2 m up at the curb): the truck's rear hides
// the near half of the van's front, whose far half and windscreen are seen. The shadow's edge was taken for
// the van's near side: 1.15 m off across the road at NEES 79 (its live runs' HMI corrections, 1.25-1.38 m
// off). A face whose points end in another object's shadow now places nothing: the fix is withheld or
// states the interval containment leaves (its position sigma over 0.5 m).
TEST(VehicleFixGeometry, FaceEndingInATrucksShadow) {
  const sim::VehicleShape van = panel_van();
  // The truck (8.5 x 2.5 x 3.6 m) in the lane nearer the LiDAR, 7.8-8.2 m ahead of the van.
  for (const auto& [truck_x, van_x] :
       {std::pair{-22.0, -29.75}, std::pair{-22.0, -29.0}, std::pair{-21.5, -28.25}}) {
    const std::vector<sim::Building> truck{
        {.x = truck_x, .y = 3.25, .yaw = 0.0, .length = 8.5, .width = 2.5, .height = 3.6}};
    const Pose2 truth{van_x, 6.75, 0.0};
    const View view = look(lidar::make_vlp32c(), 2.0, van, truth, truck);
    // The claimed view: the truck hides most of the van.
    ASSERT_FALSE(view.lidar.occluders.empty());
    EXPECT_LT(view.points.size(), look(lidar::make_vlp32c(), 2.0, van, truth).points.size() / 2) << van_x;
    // Judged (consistent with its covariance), and withheld or stating the interval containment leaves.
    judge(view, van, truth, deg_to_rad(4.6));
    AnnouncedVehicle announced;
    announced.size = {van.length, van.width, van.height};
    announced.yaw_prior = YawPrior{truth.yaw + deg_to_rad(4.6), deg_to_rad(10.0)};
    const VehicleFix fix = fix_vehicle(view.points, announced, view.lidar);
    // The van's near side lies somewhere in the shadow: withheld (0.83-0.86 m stated when the cap is 1 m).
    EXPECT_TRUE(!fix.ok() || position_sigma_m(fix.corrected) > 0.5) << van_x;
  }
}

// The corridor's car driving away 33 m from a VLP-32C 6 m up on the south sidewalk: its rear face, its roof
// and its near side at grazing incidence (the line of sight 10 deg off its length). One laser's trace along
// the side has its returns 0.68 m apart; the next two, on the front tyre 0.98 m on, were beyond the
// segmentation's 0.7 m and left out of the cluster, which ends 2.1 m short of the car's front. Its end
// was taken for the front: 1.61 m off at NEES 12.6 (README, the corridor at 6 m). The points are rsud's
// cluster of that rotation (RsuCore on the corridor scenario's simulated packets, the mount raised to 6 m).
TEST(VehicleFixGeometry, GrazingSideCutShortByTheSegmentation) {
  const sim::VehicleShape shape;  // the paper's SUV, the corridor's car
  const Pose2 truth{33.31, -1.5555, -0.0022};
  const std::vector<Eigen::Vector3d> points = {
      {31.004, -1.319, 1.049}, {31.008, -0.975, 1.036}, {31.019, -1.087, 1.038}, {31.020, -1.657, 1.058},
      {31.022, -1.201, 1.042}, {31.022, -1.429, 1.050}, {31.022, -2.104, 1.072}, {31.028, -1.881, 1.064},
      {31.031, -1.541, 1.052}, {31.036, -1.767, 1.059}, {31.068, -2.207, 1.068}, {31.073, -1.980, 1.060},
      {31.101, -2.314, 1.067}, {31.135, -0.829, 1.011}, {31.165, -0.591, 0.998}, {31.251, -2.397, 1.046},
      {31.319, -0.668, 0.977}, {31.753, -2.414, 0.970}, {32.046, -2.474, 0.927}, {32.414, -1.484, 1.779},
      {32.691, -1.304, 1.739}, {32.742, -1.652, 1.742}, {32.833, -2.444, 0.806}, {32.935, -0.888, 1.697},
      {32.972, -2.196, 1.727}, {32.984, -1.119, 1.698}, {33.129, -2.046, 1.704}, {33.130, -1.689, 1.695},
      {33.161, -1.920, 1.697}, {33.251, -2.263, 1.694}, {33.258, -1.780, 1.681}, {33.329, -0.920, 1.649},
      {33.463, -1.379, 1.645}, {33.488, -2.444, 0.706}, {33.569, -2.325, 1.655}, {33.672, -2.532, 0.680}};
  LidarGeometry lidar;
  lidar.position = {0.0, -8.5, 6.0};
  const auto model = lidar::make_vlp32c();
  for (const double e : model.elevation_deg)
    lidar.elevations_rad.push_back(deg_to_rad(e));
  lidar.azimuth_step_rad = deg_to_rad(model.azimuth_step_deg());
  // The view claimed: the cluster ends more than 2 m short of the car's front, on a side seen at grazing
  // incidence from far (returns 0.6-0.7 m apart along it).
  double front_most = -1e9;
  for (const Eigen::Vector3d& p : points)
    front_most = std::max(front_most, p.x() - truth.x);
  EXPECT_LT(front_most, shape.length / 2.0 - 2.0);
  const double range = std::hypot(truth.x + front_most, truth.y + 0.96 - lidar.position.y());
  const double sin_incidence = (truth.y - shape.width / 2.0 - lidar.position.y()) / range;
  EXPECT_GT(range * lidar.azimuth_step_rad / sin_incidence, 0.6);
  // The vehicle announced its heading to within 1.4 deg (an NDT's covariance), as in the corridor.
  for (const double prior_error_deg : {0.0, 1.0, -1.0}) {
    AnnouncedVehicle announced;
    announced.size = {shape.length, shape.width, shape.height};
    announced.yaw_prior = YawPrior{truth.yaw + deg_to_rad(prior_error_deg), deg_to_rad(1.4)};
    const VehicleFix fix = fix_vehicle(points, announced, lidar);
    if (!fix.ok()) {
      EXPECT_EQ(fix.status(), CorrectionStatus::position_unbounded);  // its place along the road is open
      continue;
    }
    const Eigen::Vector2d error(fix.corrected.pose.x - truth.x, fix.corrected.pose.y - truth.y);
    const double nees = error.dot(fix.corrected.covariance.topLeftCorner<2, 2>().ldlt().solve(error));
    EXPECT_TRUE(error.norm() < 0.10 || nees <= kChi2TwoDof3Sigma)
        << "prior " << prior_error_deg << " deg: " << error.norm() << " m off at NEES " << nees;
  }
}

// --- thinning a dense cluster along azimuth (azimuth_thinning.h) ---------------------------------------

// LaserLookup, searched from any hint, names the laser laser_of names (every laser scanned), over the
// sensors' own elevation tables (a VLP-16's are interleaved, not sorted) and a table with a repeated
// elevation (the first of the two, as laser_of), for points at every elevation in and beyond the field
// of view; unknown elevations give no rank.
TEST(LaserLookup, NamesTheLaserLaserOfNames) {
  std::vector<std::vector<double>> tables;
  for (const auto& model : {lidar::make_vlp16(), lidar::make_vlp32c(), lidar::make_generic(128)}) {
    tables.emplace_back();
    for (const double e : model.elevation_deg)
      tables.back().push_back(deg_to_rad(e));
  }
  tables.push_back({deg_to_rad(-5.0), deg_to_rad(3.0), deg_to_rad(-5.0), deg_to_rad(10.0)});
  for (const std::vector<double>& table : tables) {
    LidarGeometry lidar;
    lidar.position = {0.5, -1.0, 6.0};
    lidar.elevations_rad = table;
    const LaserLookup lookup(table);
    ASSERT_EQ(lookup.count(), table.size());
    std::size_t hint = 0;
    for (int i = 0; i <= 4000; ++i) {
      const double elevation = deg_to_rad(-40.0 + 0.02 * i);  // -40 .. +40 deg
      const double run = 3.0 + 0.01 * (i % 700);
      const Eigen::Vector3d p(lidar.position.x() + run * std::cos(0.3 * i),
                              lidar.position.y() + run * std::sin(0.3 * i),
                              lidar.position.z() + run * std::tan(elevation));
      const double rise_over_run = (p.z() - lidar.position.z()) / (p.head<2>() - lidar.xy()).norm();
      hint = lookup.rank(rise_over_run, hint);
      ASSERT_EQ(lookup.laser(hint), lidar.laser_of(p)) << "elevation " << rad_to_deg(elevation) << " deg";
      ASSERT_EQ(lookup.laser(lookup.rank(rise_over_run, table.size() - 1 - hint)), lidar.laser_of(p));
    }
  }
  EXPECT_EQ(LaserLookup({}).count(), 0U);
}

// ranks over a cloud names each point's laser as laser_of does, whatever order the points come in, and
// kNone where there is no laser to name: a point not finite, one straight above the LiDAR, every point
// when the elevations are unknown.
TEST(LaserLookup, RanksNameEachPointsLaser) {
  LidarGeometry lidar;
  lidar.position = {2.0, 1.0, 4.5};
  for (const double e : lidar::make_vlp32c().elevation_deg)
    lidar.elevations_rad.push_back(deg_to_rad(e));
  const LaserLookup lookup(lidar.elevations_rad);
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < 3000; ++i) {  // a jumble of elevations, ranges and azimuths
    const double elevation = deg_to_rad(-30.0 + std::fmod(37.01 * i, 45.0));  // off the lasers' midpoints
    const double run = 2.0 + std::fmod(7.3 * i, 40.0);
    points.emplace_back(lidar.position.x() + run * std::cos(1.7 * i),
                        lidar.position.y() + run * std::sin(1.7 * i),
                        lidar.position.z() + run * std::tan(elevation));
  }
  const std::size_t nan = points.size();
  points.emplace_back(std::numeric_limits<double>::quiet_NaN(), 3.0, 1.0);
  points.emplace_back(lidar.position.x(), lidar.position.y(), 1.0);  // straight below the LiDAR
  const std::vector<std::size_t> ranks = lookup.ranks(points, lidar.position);
  ASSERT_EQ(ranks.size(), points.size());
  for (std::size_t i = 0; i < nan; ++i) {
    ASSERT_NE(ranks[i], LaserLookup::kNone);
    ASSERT_EQ(lookup.laser(ranks[i]), lidar.laser_of(points[i])) << "point " << i;
  }
  EXPECT_EQ(ranks[nan], LaserLookup::kNone);
  EXPECT_EQ(ranks[nan + 1], LaserLookup::kNone);
  for (const std::size_t r : LaserLookup({}).ranks(points, lidar.position))
    ASSERT_EQ(r, LaserLookup::kNone);
}

// The near car of a dense sensor (issue 16: 5,600-17,600 points in rsud) and its lasers' traces, told apart
// by the reference rule (LidarGeometry::laser_of, every laser scanned) and the points' absolute azimuth.
struct Traces {
  View view;
  std::vector<int> laser;       // per point
  std::vector<double> azimuth;  // per point, radians seen from the LiDAR
};

Traces near_dense_car(const Pose2& truth = {1.5, 3.6, deg_to_rad(8.0)}) {
  Traces t{look(lidar::make_generic(128), 2.0, sim::VehicleShape{}, truth), {}, {}};
  for (const auto& p : t.view.points) {
    t.laser.push_back(t.view.lidar.laser_of(p));
    t.azimuth.push_back(std::atan2(p.y() - t.view.lidar.position.y(), p.x() - t.view.lidar.position.x()));
  }
  return t;
}

bool contains(const std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& p) {
  return std::find(points.begin(), points.end(), p) != points.end();
}

// Each laser's trace keeps points (none of the lasers that saw the car is dropped), both its ends, and
// about max_points remain.
TEST(AzimuthThinning, KeepsEveryLaserAndBothEndsOfEachTrace) {
  const Traces t = near_dense_car();
  const std::size_t n = t.view.points.size();
  ASSERT_GE(n, 5000U);  // the claimed view: a dense cluster
  constexpr std::size_t kMax = 2000;
  const AzimuthThinning thinned = thin_along_azimuth(t.view.points, t.view.lidar, kMax);
  const int k = static_cast<int>((n + kMax - 1) / kMax);
  ASSERT_EQ(thinned.stride, k);
  ASSERT_GT(k, 1);
  EXPECT_GE(thinned.points.size(), n / static_cast<std::size_t>(k));
  EXPECT_LE(thinned.points.size(), kMax + kMax / 2);
  std::map<int, std::pair<std::size_t, std::size_t>> ends;  // laser -> (westmost, eastmost) point
  for (std::size_t i = 0; i < n; ++i) {
    auto [it, fresh] = ends.try_emplace(t.laser[i], i, i);
    if (t.azimuth[i] < t.azimuth[it->second.first])
      it->second.first = i;
    if (t.azimuth[i] > t.azimuth[it->second.second])
      it->second.second = i;
  }
  EXPECT_GE(ends.size(), 40U);  // the claimed view: many lasers on the car
  for (const auto& [laser, e] : ends) {
    EXPECT_TRUE(contains(thinned.points, t.view.points[e.first]))
        << "laser " << laser << ": first end dropped";
    EXPECT_TRUE(contains(thinned.points, t.view.points[e.second]))
        << "laser " << laser << ": last end dropped";
  }
}

// A break in the traces (a pole in front of the car: 1.5 deg of azimuth without returns) ends each trace on
// both sides of it: the points beside it are kept.
TEST(AzimuthThinning, KeepsThePointsBesideABreakInATrace) {
  const Traces t = near_dense_car();
  const auto [lo, hi] = std::minmax_element(t.azimuth.begin(), t.azimuth.end());
  const double from = 0.5 * (*lo + *hi), to = from + deg_to_rad(1.5);
  std::vector<Eigen::Vector3d> points;
  std::map<int, std::pair<std::size_t, std::size_t>> beside;  // laser -> (last before, first after)
  for (std::size_t i = 0; i < t.view.points.size(); ++i) {
    if (t.azimuth[i] >= from && t.azimuth[i] <= to)
      continue;
    points.push_back(t.view.points[i]);
    auto [it, fresh] = beside.try_emplace(t.laser[i], i, i);
    auto& [before, after] = it->second;
    if (t.azimuth[i] < from && (t.azimuth[before] >= from || t.azimuth[i] > t.azimuth[before]))
      before = i;
    if (t.azimuth[i] > to && (t.azimuth[after] <= to || t.azimuth[i] < t.azimuth[after]))
      after = i;
  }
  const AzimuthThinning thinned = thin_along_azimuth(points, t.view.lidar, 2000);
  ASSERT_GT(thinned.stride, 1);
  std::size_t broken = 0;
  for (const auto& [laser, b] : beside) {
    const auto [before, after] = b;
    if (t.azimuth[before] >= from || t.azimuth[after] <= to)
      continue;  // this laser's trace does not cross the break
    ++broken;
    EXPECT_TRUE(contains(thinned.points, t.view.points[before])) << "laser " << laser;
    EXPECT_TRUE(contains(thinned.points, t.view.points[after])) << "laser " << laser;
  }
  EXPECT_GE(broken, 40U);  // the claimed view: the break crosses most traces
}

// rsud fits a dense cluster's rectangle to its thinned points (detect with FitThinning) and fixes the
// vehicle of that detection alone from the detection's thinning: the same thinning fix_vehicle makes of
// the points, and the same fix to the last bit. Without FitThinning the detection has none.
TEST(AzimuthThinning, TheDetectionsThinningFixesAsThePointsDo) {
  const Traces t = near_dense_car();
  std::vector<lidar::LidarPoint> cloud;
  for (const Eigen::Vector3d& p : t.view.points) {
    lidar::LidarPoint q;
    q.x = static_cast<float>(p.x());
    q.y = static_cast<float>(p.y());
    q.z = static_cast<float>(p.z());
    cloud.push_back(q);
  }
  const VehicleFixConfig config;
  const LidarGeometry& lidar = t.view.lidar;
  const Detection d = detect(cloud, lidar.xy(), config.fit, {&lidar, config.thin_above_points});
  ASSERT_TRUE(d.thinning.has_value());
  const AzimuthThinning again = thin_along_azimuth(d.points, lidar, config.thin_above_points);
  ASSERT_GT(again.stride, 1);
  EXPECT_EQ(d.thinning->stride, again.stride);
  EXPECT_EQ(d.thinning->points, again.points);
  EXPECT_FALSE(detect(cloud, lidar.xy(), config.fit).thinning.has_value());

  const sim::VehicleShape shape;
  AnnouncedVehicle announced;
  announced.size = {shape.length, shape.width, shape.height};
  announced.yaw_prior = YawPrior{deg_to_rad(8.0), deg_to_rad(10.0)};
  const VehicleFix reused = fix_vehicle(d.points, *d.thinning, announced, lidar, config);
  const VehicleFix made = fix_vehicle(d.points, announced, lidar, config);
  ASSERT_TRUE(made.ok()) << to_string(made.status());
  EXPECT_EQ(reused.status(), made.status());
  EXPECT_EQ(reused.azimuth_stride, made.azimuth_stride);
  EXPECT_EQ(reused.points_used, made.points_used);
  EXPECT_EQ(reused.corrected.pose.x, made.corrected.pose.x);
  EXPECT_EQ(reused.corrected.pose.y, made.corrected.pose.y);
  EXPECT_EQ(reused.corrected.pose.yaw, made.corrected.pose.yaw);
  EXPECT_EQ(reused.corrected.covariance, made.corrected.covariance);
}

// The thinned points lie k azimuth steps apart along a trace, and the fix says so: its stride is k, and
// its covariance is the one stated with that spacing, wider than with the sensor's own step (which the
// same points, given unthinned, are stated with).
TEST(AzimuthThinning, FixStatesTheCoarserSpacing) {
  // Broadside, the LiDAR abreast of its middle: both ends seen, neither facing the LiDAR, so its place
  // along its length is their midpoint, as uncertain as the points' spacing (fix_covariance.h).
  const Pose2 truth{0.0, 4.0, 0.0};
  const Traces t = near_dense_car(truth);
  const sim::VehicleShape shape;
  AnnouncedVehicle announced;
  announced.size = {shape.length, shape.width, shape.height};
  announced.yaw_prior = YawPrior{truth.yaw, deg_to_rad(10.0)};
  VehicleFixConfig config;
  config.thin_above_points = 2000;
  const VehicleFix fix = fix_vehicle(t.view.points, announced, t.view.lidar, config);
  ASSERT_TRUE(fix.ok()) << to_string(fix.status());
  const AzimuthThinning thinned = thin_along_azimuth(t.view.points, t.view.lidar, config.thin_above_points);
  ASSERT_GT(thinned.stride, 1);
  EXPECT_EQ(fix.azimuth_stride, thinned.stride);
  EXPECT_EQ(fix.points_used, thinned.points.size());
  // The spacing measured along each laser's trace, in azimuth steps: its median is the stride.
  std::map<int, std::vector<double>> trace;
  for (const auto& p : thinned.points)
    trace[t.view.lidar.laser_of(p)].push_back(
        std::atan2(p.y() - t.view.lidar.position.y(), p.x() - t.view.lidar.position.x()));
  std::vector<double> gaps;
  for (auto& [laser, azimuths] : trace) {
    std::sort(azimuths.begin(), azimuths.end());
    for (std::size_t i = 1; i < azimuths.size(); ++i)
      gaps.push_back((azimuths[i] - azimuths[i - 1]) / t.view.lidar.azimuth_step_rad);
  }
  ASSERT_GE(gaps.size(), 1000U);
  std::nth_element(gaps.begin(), gaps.begin() + static_cast<std::ptrdiff_t>(gaps.size() / 2), gaps.end());
  EXPECT_NEAR(gaps[gaps.size() / 2], static_cast<double>(fix.azimuth_stride), 0.5);
  // The same points unthinned, stated with the sensor's step: the same box, a tighter covariance.
  VehicleFixConfig never;
  never.thin_above_points = 0;
  const VehicleFix fine = fix_vehicle(thinned.points, announced, t.view.lidar, never);
  ASSERT_TRUE(fine.ok());
  EXPECT_EQ(fine.azimuth_stride, 1);
  const double coarse = fix.corrected.covariance(0, 0) + fix.corrected.covariance(1, 1);
  EXPECT_GT(coarse, fine.corrected.covariance(0, 0) + fine.corrected.covariance(1, 1));
}

// A cluster at or under the threshold, and any cluster of a sensor whose elevations are unknown, is fixed
// from all its points: the fix is the same bit for bit as with thinning off.
TEST(AzimuthThinning, ClusterUnderTheThresholdIsUntouched) {
  const Traces dense = near_dense_car();
  // A car 20 m from a VLP-32C 2 m up: under the threshold (at 10 m it holds 1,358 points, at 3.6 m 2,177).
  const View sparse = look(lidar::make_vlp32c(), 2.0, sim::VehicleShape{}, {1.5, 20.0, deg_to_rad(8.0)});
  ASSERT_GE(sparse.points.size(), 400U);  // a cluster that is not trivially small
  ASSERT_LE(sparse.points.size(), VehicleFixConfig{}.thin_above_points);
  View unknown_lasers = dense.view;
  unknown_lasers.lidar.elevations_rad.clear();
  struct Case {
    const View* view;
    std::size_t threshold;
  };
  for (const Case& c : {Case{&sparse, VehicleFixConfig{}.thin_above_points},
                        Case{&dense.view, dense.view.points.size()}, Case{&unknown_lasers, 2000}}) {
    const sim::VehicleShape shape;
    AnnouncedVehicle announced;
    announced.size = {shape.length, shape.width, shape.height};
    announced.yaw_prior = YawPrior{deg_to_rad(8.0), deg_to_rad(10.0)};
    VehicleFixConfig config;
    config.thin_above_points = c.threshold;
    VehicleFixConfig never;
    never.thin_above_points = 0;
    const VehicleFix fix = fix_vehicle(c.view->points, announced, c.view->lidar, config);
    const VehicleFix all = fix_vehicle(c.view->points, announced, c.view->lidar, never);
    EXPECT_EQ(fix.azimuth_stride, 1);
    EXPECT_EQ(fix.points_used, c.view->points.size());
    EXPECT_EQ(fix.status(), all.status());
    EXPECT_EQ(fix.corrected.pose.x, all.corrected.pose.x);
    EXPECT_EQ(fix.corrected.pose.y, all.corrected.pose.y);
    EXPECT_EQ(fix.corrected.pose.yaw, all.corrected.pose.yaw);
    EXPECT_EQ(fix.corrected.covariance, all.corrected.covariance);
    EXPECT_EQ(fix.fit.yaw, all.fit.yaw);
  }
}

// A hatchback (1.5 m tall, its belt line 0.92 m up) broadside 22.3 m from a VLP-16 2 m up: only the -3 deg
// laser meets it (the -1 deg laser passes over the roof, the -5 deg one under the sills), on its doors at
// 2 - 21.44 tan(3 deg) = 0.88 m, above 55 % of its height (0.825 m). The doors were taken for the upper
// body, the side for a possible window, and the box was placed in the 1.6 m interval containment leaves
// across it: 0.5-0.8 m off (stating 0.36-0.5 m; the pilot matrix's small car at 22-24 m). Where the lower
// body makes no face at a side seen at a shallow depression, a point up to full_plan_height_m (0.9 m) can
// be on it (side_body_height), set back by at most a window's inset: the fix must be right. Within 3-6 deg of
// broadside: exactly broadside the trace along the side is an arc within the points' noise (0.09 m over the
// car's length), which tells no heading, and the vehicle's own, 7 deg off, turns the box (covered, not
// right).
TEST(VehicleFixGeometry, DoorsSeenOnlyAboveTheLowerBodyShare) {
  const sim::VehicleShape shape = hatchback();
  const double lower = 0.55 * shape.height;
  for (const double yaw_deg : {84.0, 87.0, 93.0, 96.0, 264.0, 267.0, 273.0, 276.0}) {
    const Pose2 truth{22.3, 0.0, deg_to_rad(yaw_deg)};
    const View view = look(lidar::make_vlp16(), 2.0, shape, truth);
    // The claimed view: one laser's trace, all of it between 55 % of the height and the belt line.
    ASSERT_GE(view.points.size(), 30U) << yaw_deg;
    for (const Eigen::Vector3d& p : view.points) {
      EXPECT_GT(p.z(), lower) << yaw_deg;
      EXPECT_LT(p.z(), shape.belt_height) << yaw_deg;
    }
    for (const double prior_error : {deg_to_rad(7.0), deg_to_rad(-7.0)})
      EXPECT_EQ(judge(view, shape, truth, prior_error), Verdict::right) << yaw_deg;
  }
}

// The same small car broadside 7 m from a 128-ring sensor 4 m up: its doors' few points below 55 % of its
// height make no face, and above it most points are the belt line's ledge, seen from above, up to the
// cabin's inset inside the side. Placed on them the side was 0.1 m in (0.09-0.12 m off, the 128-ring
// matrix's small car at 4 m); from a mast (a depression at which a laser lands on the ledge over more than
// the points' noise) the side is not placed on points above the lower body, and the fix must stay right.
TEST(VehicleFixGeometry, BeltLedgeSeenFromAMast) {
  const sim::VehicleShape shape = hatchback();
  for (const double yaw_deg : {78.0, 102.0, 258.0, 282.0}) {
    const Pose2 truth{7.0, 0.0, deg_to_rad(yaw_deg)};
    const View view = look(lidar::make_generic(128), 4.0, shape, truth);
    // The claimed view: many more points between 55 % of the height and 0.9 m than below.
    const auto band = std::count_if(view.points.begin(), view.points.end(), [&](const Eigen::Vector3d& p) {
      return p.z() > 0.55 * shape.height && p.z() <= 0.9;
    });
    const auto below = std::count_if(view.points.begin(), view.points.end(),
                                     [&](const Eigen::Vector3d& p) { return p.z() <= 0.55 * shape.height; });
    EXPECT_GT(band, 3 * below) << yaw_deg;
    for (const double prior_error : {deg_to_rad(6.0), deg_to_rad(-6.0)})
      EXPECT_EQ(judge(view, shape, truth, prior_error), Verdict::right) << yaw_deg;
  }
}

// A city bus end-on, 13-20 m from a VLP-16 2 m up: its flat front (or back) is seen by six lasers, four of
// them above 1 m (the bonnet's height, max_end_body_height_m). Faces seen mostly above the bonnet were
// trusted less whatever the points showed (3.9 deg for a face known to 0.05 deg), so the vehicle's own
// heading, 9.5 deg off, was fused in and turned the box about its front, its centre 6 m behind: 0.12-0.16
// m off (the pilot matrix's bus). The points above the bonnet run parallel to those below (a flat front):
// the face's direction stands, and the fix must be right in position and yaw.
TEST(VehicleFixGeometry, FlatFrontMostlyAboveTheBonnet) {
  const sim::VehicleShape shape = city_bus();
  for (const double distance : {13.0, 16.0, 20.0}) {
    for (const double yaw_deg : {3.0, 183.0}) {
      const Pose2 truth{distance, 0.0, deg_to_rad(yaw_deg)};
      const View view = look(lidar::make_vlp16(), 2.0, shape, truth);
      // The claimed view: the near end only (every point within 0.5 m of it: its rounded corners), mostly
      // above 1 m.
      const double end = distance - 0.5 * shape.length;
      const auto above = std::count_if(view.points.begin(), view.points.end(),
                                       [](const Eigen::Vector3d& p) { return p.z() > 1.0; });
      ASSERT_GE(view.points.size(), 100U) << distance;
      EXPECT_GT(2 * above, static_cast<std::ptrdiff_t>(view.points.size())) << distance;
      for (const Eigen::Vector3d& p : view.points)
        EXPECT_LT(p.x(), end + 0.5) << distance;
      for (const double prior_error : {deg_to_rad(9.5), deg_to_rad(-9.5)}) {
        EXPECT_EQ(judge(view, shape, truth, prior_error), Verdict::right) << distance << " " << yaw_deg;
        AnnouncedVehicle announced;
        announced.size = {shape.length, shape.width, shape.height};
        announced.yaw_prior = YawPrior{truth.yaw + prior_error, deg_to_rad(10.0)};
        const VehicleFix fix = fix_vehicle(view.points, announced, view.lidar);
        EXPECT_LT(angle_distance(fix.corrected.pose.yaw, truth.yaw), deg_to_rad(0.5)) << distance;
      }
    }
  }
}

// A sedan 3 m from a HDL-32E 3 m up (its lowest laser 30.7 deg down; the second matrix's cell, frame 48): no
// laser reaches the doors on its near side. The lowest laser's trace over the roof and bonnet (85 of the near
// face's 89 points, 4 another laser's) made the "side": 11 deg off while stating 3.6 deg, the fix 0.38 m
// off at NEES 12.8 (HMI). A face above the bonnet that is nearly all one laser's trace now counts as that
// trace (CorrectionConfig::single_trace_share), which tells the direction only to about its depression.
TEST(VehicleFixGeometry, LowestLasersTraceOverRoofAndBonnetNearTheMast) {
  const sim::VehicleShape shape = vehicle_file("second/sedan");
  const PilotCell cell = pilot_cell(lidar::make_hdl32e(), 3.0, shape, 3.0, 48);
  // The claimed view: dense, nothing on the doors.
  EXPECT_GT(cell.view.points.size(), 2000U);
  EXPECT_GT(lowest(cell.view), 0.75);
  EXPECT_NE(judge(cell.view, shape, cell.truth, deg_to_rad(-9.03)), Verdict::withheld);
}

// A small car's end 31-39 m from a VLP-16 or VLP-32C 5-7 m up (the matrices' cells, the pilot's prior
// errors): 20-43 returns, one or two faces of 1.0-1.7 m below the bonnet, a rounded corner in them. The fits
// were 6-13 deg off while stating 2-3 deg (0.1-0.7 % of the fixes in their 5 m bands). A rounded corner's
// turn of a face now enters its departure (informative_face.cpp, rounded_corner_departure).
TEST(VehicleFixGeometry, SparseEndsTurnedByRoundedCorners) {
  struct Case {
    int shape;  // 0 sedan, 1 microcar, 2 the pilot matrix's small car
    bool vlp16;
    double height, distance;
    int frame;
    double prior_error_deg;
  };
  for (const Case& c : {Case{0, false, 7.0, 35.0, 30, 5.257}, Case{0, false, 5.0, 38.0, 29, -7.408},
                        Case{0, false, 7.0, 34.0, 2, -0.476}, Case{1, false, 7.0, 34.0, 25, 3.682},
                        Case{1, true, 5.0, 39.0, 7, 7.894}, Case{2, false, 6.0, 37.0, 36, 7.444}}) {
    const sim::VehicleShape shape = vehicle_file(c.shape == 0   ? "second/sedan"
                                                 : c.shape == 1 ? "second/microcar"
                                                                : "small_car");
    const PilotCell cell = pilot_cell(c.vlp16 ? lidar::make_vlp16() : lidar::make_vlp32c(), c.height, shape,
                                      c.distance, c.frame);
    // The claimed view: sparse, some of it below the bonnet.
    EXPECT_GE(cell.view.points.size(), 15U) << c.distance;
    EXPECT_LE(cell.view.points.size(), 60U) << c.distance;
    EXPECT_LT(lowest(cell.view), 0.55 * shape.height) << c.distance;
    EXPECT_NE(judge(cell.view, shape, cell.truth, deg_to_rad(c.prior_error_deg)), Verdict::withheld)
        << c.distance;
  }
}

// A coupe: low, long sloped glass at both ends, 0.35 m corners (a third pilot matrix's vehicle, kept out of
// the repository's scenarios: README, the pilot matrix).
sim::VehicleShape coupe() {
  return {.length = 4.5,
          .width = 1.9,
          .height = 1.25,
          .corner_radius = 0.35,
          .ground_clearance = 0.11,
          .belt_height = 0.8,
          .cabin_inset = 0.14,
          .hood_length = 1.3,
          .windscreen_run = 0.9,
          .rear_slope_run = 0.8,
          .wheel_radius = 0.34,
          .wheel_width = 0.25,
          .wheelbase = 2.7};
}

// The lasers (index into the elevations) the points of `view` were returned by.
std::vector<int> lasers_in(const View& view) {
  std::vector<int> lasers;
  for (const auto& p : view.points)
    lasers.push_back(view.lidar.laser_of(p));
  std::sort(lasers.begin(), lasers.end());
  lasers.erase(std::unique(lasers.begin(), lasers.end()), lasers.end());
  return lasers;
}

// A coupe's side 35 m from a VLP-16 2.5 m up, 15 deg from broadside (the third matrix's cell, seed 7): one
// laser along it at 0.68-0.74 m, its lower body up to 0.69 m (0.55 of its height). Split by height, the
// trace's farthest returns (both ends of the side) made the outline the rectangle was fitted to: 17 deg off,
// the fix 0.45 m off at NEES 15, an HMI fix. A level trace is judged whole (vehicle_fix.cpp, trace_heights).
TEST(VehicleFixGeometry, LevelTraceAcrossTheLowerBodysHeight) {
  const sim::VehicleShape shape = coupe();
  const PilotCell cell = pilot_cell(lidar::make_vlp16(), 2.5, shape, 35.0, 47, 7);
  // The claimed view: one laser, its heights on both sides of the lower body's.
  EXPECT_EQ(lasers_in(cell.view).size(), 1U);
  EXPECT_LT(lowest(cell.view), 0.55 * shape.height);
  EXPECT_GT(highest(cell.view), 0.55 * shape.height);
  EXPECT_LT(highest(cell.view) - lowest(cell.view), 0.15);
  EXPECT_EQ(judge(cell.view, shape, cell.truth, deg_to_rad(7.6645)), Verdict::right);
}

// An estate (a third pilot matrix's vehicle, as the coupe).
sim::VehicleShape estate() {
  return {.length = 4.85,
          .width = 1.85,
          .height = 1.5,
          .corner_radius = 0.2,
          .ground_clearance = 0.15,
          .belt_height = 0.98,
          .cabin_inset = 0.12,
          .hood_length = 0.95,
          .windscreen_run = 0.7,
          .rear_slope_run = 0.08,
          .wheel_radius = 0.33,
          .wheel_width = 0.22,
          .wheelbase = 2.85};
}

// An estate's side 24 m from a VLP-32C 4.5 m up (the third matrix's cell, seed 7): one laser along the
// doors at 0.78-0.98 m, straight in plan, its lower body up to 0.83 m, and one over the glasshouse. Split by
// height, the doors' trace left 9 returns at its far end for the outline: 12.8 deg off stating 3.8 deg,
// 0.52 m off at NEES 11.4. A trace straight in plan is judged whole (vehicle_fix.cpp, trace_heights).
TEST(VehicleFixGeometry, StraightTraceAcrossTheLowerBodysHeight) {
  const sim::VehicleShape shape = estate();
  const PilotCell cell = pilot_cell(lidar::make_vlp32c(), 4.5, shape, 24.0, 42, 7);
  EXPECT_EQ(lasers_in(cell.view).size(), 2U);
  EXPECT_LT(lowest(cell.view), 0.55 * shape.height);
  EXPECT_EQ(judge(cell.view, shape, cell.truth, deg_to_rad(1.8980)), Verdict::right);
}

// The same side 34 m from a VLP-16 6 m up (frames 12, 17, 47, 48 of the cell, seed 7): one laser at
// 0.62-0.83 m, the trace's lowest returns a clump at one end and one return at the other. The rectangle
// fitted to them lies along neither; its "side" held the 4-7 returns where the trace crosses it, stating
// 3.9-4.5 deg, 12-15 deg off. Such a face is a chord of the trace (informative_face.cpp,
// crossing_trace_departure): its yaw must be covered.
TEST(VehicleFixGeometry, FaceThatIsAChordOfATrace) {
  const sim::VehicleShape shape = coupe();
  for (const auto& [frame, prior_error_deg] :
       {std::pair{12, 7.4188}, std::pair{17, 8.3176}, std::pair{47, -9.5383}, std::pair{48, 5.7447}}) {
    const PilotCell cell = pilot_cell(lidar::make_vlp16(), 6.0, shape, 34.0, frame, 7);
    EXPECT_EQ(lasers_in(cell.view).size(), 1U) << frame;
    EXPECT_GT(highest(cell.view) - lowest(cell.view), 0.15) << frame;
    EXPECT_NE(judge(cell.view, shape, cell.truth, deg_to_rad(prior_error_deg)), Verdict::withheld) << frame;
  }
}

// A city bus 5 m from a 128-ring sensor 4 m up, spinning at 120 deg/s (the 128-ring matrix's cell: frames
// 6, 8 and 21 at 5 m, the vehicle's heading 1.2-1.7 deg off), broadside: the sweep
// takes 30 ms over it and the fit is 1.6-1.7 deg off. Its side's points below the bonnet span 1.5 m of its
// 12 m and run parallel to those above within what 1.5 m tells (1.5 deg); taken as good as a 12 m face the
// side stated 0.5 deg. It is as good as its lower body's 1.5 m: the yaw must be covered (judge).
TEST(VehicleFixGeometry, LongSideWithAShortLowerBody) {
  const lidar::SensorModel model = lidar::make_generic(128);
  const TimeNs period = from_seconds(60.0 / model.rpm);
  const TimeNs t0 = 30 * period;  // the second distance of the matrix's grid (3, 5, ... m), 30 frames each
  const sim::Spin spin{5.0, 0.0, 0.0, deg_to_rad(120.0), t0};
  Pose3 mount;
  mount.z = 4.0;
  mount.yaw = std::numbers::pi;
  for (const auto& [frame, prior_error_deg] : {std::pair{6, 1.21}, std::pair{8, -1.7}, std::pair{21, 1.7}}) {
    const Sweep sweep = sweep_of(model, mount, city_bus(), spin, t0 + frame * period, {});
    ASSERT_GE(sweep.view.points.size(), 5000U) << frame;
    EXPECT_NE(
        judge(sweep.view, city_bus(), sim::pose_at(spin, sweep.median_time), deg_to_rad(prior_error_deg)),
        Verdict::withheld)
        << frame;
  }
}

// A coupe 9 m from a HDL-32E 6 m up, seen from above (the third matrix's cell, frame 11, seed 7): four
// lasers over its roof, sloped glass and bonnet, and 13 returns of its doors at one end. The face fitted
// through them crossed the roof: 15 deg off stating 2.7 deg, 0.15 m off at NEES 15.8. Its lasers' runs
// along it tilt 5-46 deg from it (informative_face.cpp, run_tilt_departure): the yaw must be covered.
TEST(VehicleFixGeometry, UpperBodyFaceThroughSeveralLasersRuns) {
  const sim::VehicleShape shape = coupe();
  const PilotCell cell = pilot_cell(lidar::make_hdl32e(), 6.0, shape, 9.0, 11, 7);
  EXPECT_EQ(lasers_in(cell.view).size(), 4U);
  EXPECT_NE(judge(cell.view, shape, cell.truth, deg_to_rad(7.7691)), Verdict::withheld);
}

// The coupe 40 m from a HDL-32E 4.5 m up (frame 24, seed 7): one laser along its side and across its
// windscreen's foot, 27 returns. The face fitted across both held the returns where the trace crossed it
// (face_traces.h, crossing_returns): 26 deg off stating 5.3 deg. The yaw must be covered.
TEST(VehicleFixGeometry, FaceThroughWhereOneTraceCrossesIt) {
  const sim::VehicleShape shape = coupe();
  const PilotCell cell = pilot_cell(lidar::make_hdl32e(), 4.5, shape, 40.0, 24, 7);
  EXPECT_EQ(lasers_in(cell.view).size(), 1U);
  EXPECT_NE(judge(cell.view, shape, cell.truth, deg_to_rad(-2.1887)), Verdict::withheld);
}

// A box body's side, flat up to 2.5 m, seen broadside 18 m from a VLP-32C 6 m up: its lowest returns lie
// at 1.0-1.5 m, above the bonnet, the rest on its upper side and roof. Judged as an end's, up to the bonnet
// only, the side told little and the fix stated 1.4-1.5 deg; judged up to the lower body where its returns
// there lie on one surface (informative_face.h, face_lower_height), it states 0.35 deg, and is right.
TEST(VehicleFixGeometry, BoxBodysSideAboveTheBonnetTellsTheYaw) {
  const sim::VehicleShape box = box_body();
  for (int frame = 13; frame <= 16; ++frame) {
    const PilotCell cell = pilot_cell(lidar::make_vlp32c(), 6.0, box, 18.0, frame, 3);
    AnnouncedVehicle announced;
    announced.size = {box.length, box.width, box.height};
    announced.yaw_prior = YawPrior{cell.truth.yaw + deg_to_rad(8.0), deg_to_rad(10.0)};
    const VehicleFix fix = fix_vehicle(cell.view.points, announced, cell.view.lidar);
    ASSERT_TRUE(fix.ok()) << frame;
    // Broadside (its heading 81-99 deg from the line of sight): nothing below the bonnet (1.0 m).
    EXPECT_GT(lowest(cell.view), 1.0) << frame;
    const double yaw_sigma = std::sqrt(fix.corrected.covariance(2, 2));
    EXPECT_LT(yaw_sigma, deg_to_rad(1.0)) << frame;
    EXPECT_EQ(judge(cell.view, box, cell.truth, deg_to_rad(8.0)), Verdict::right) << frame;
  }
}

// A panel van's side seen 19-25 m from a VLP-32C 6-8 m up, one laser crossing its belt line (1.2 m, under
// 55 % of its 2.45 m): the glass above it lies 5 cm in. Taken for the lower body it turned the side 1.9-6.7
// deg while stating 0.6-1.2 deg; the step between its returns below and above keeps it to the bonnet.
TEST(VehicleFixGeometry, VansGlassAboveItsBeltIsNotItsSide) {
  const sim::VehicleShape van = vehicle_file("van");
  struct Case {
    double height, distance;
    int frame;
    double prior_error_deg;
  };
  for (const Case& c :
       {Case{6.0, 19.0, 27, -6.7419}, Case{8.0, 25.0, 19, -0.9564}, Case{8.0, 25.0, 51, -9.2041}}) {
    const PilotCell cell = pilot_cell(lidar::make_vlp32c(), c.height, van, c.distance, c.frame);
    EXPECT_GE(cell.view.points.size(), 60U) << c.frame;
    EXPECT_NE(judge(cell.view, van, cell.truth, deg_to_rad(c.prior_error_deg)), Verdict::withheld) << c.frame;
  }
}

// A minibus seen broadside 30 m from a HDL-32E 7 m up, a little from behind: its rear's returns below the
// bonnet are one on the rear and three on the side by the rounded corner. Their envelope placed the rear
// 0.14 m inside the body, stating 0.02 m (NEES 15.5). An end whose returns lie mostly within a corner's
// radius of the seen side now states the corner's setback (box_axis.cpp, face_on_outline).
TEST(VehicleFixGeometry, EndSeenOnlyAtItsCornerStatesTheCorner) {
  const sim::VehicleShape minibus = vehicle_file("second/minibus");
  const PilotCell cell = pilot_cell(lidar::make_hdl32e(), 7.0, minibus, 30.0, 46);
  EXPECT_GT(cell.view.points.size(), 300U);
  EXPECT_NE(judge(cell.view, minibus, cell.truth, deg_to_rad(2.5917)), Verdict::withheld);
}

// Small cars 33-36 m from a mast 4-5 m up (a VLP-32C, a 64-ring sensor), seen on a diagonal: their L-shape
// fits were 5-7 deg off and the refit on the faces' support bands left them 5.4-7.1 deg off stating
// 1.5-2.2 deg. Refit again on the refit's bands the direction moves on by 3-4 deg (or goes round in a
// cycle); that movement now widens the faces' yaw (face_refinement.h, refit_unsettled_rad).
TEST(VehicleFixGeometry, UnsettledRefitOfAFarSmallCarStatesItsMovement) {
  const sim::VehicleShape small_car = vehicle_file("small_car");
  const PilotCell car = pilot_cell(lidar::make_vlp32c(), 4.0, small_car, 33.0, 52);
  EXPECT_NE(judge(car.view, small_car, car.truth, deg_to_rad(5.9902)), Verdict::withheld);
  const sim::VehicleShape microcar = vehicle_file("second/microcar");
  const PilotCell micro = pilot_cell(*lidar::sensor_model_by_name("generic64"), 5.0, microcar, 36.0, 39);
  EXPECT_NE(judge(micro.view, microcar, micro.truth, deg_to_rad(-3.2293)), Verdict::withheld);
}

// A low sports car (a fourth pilot matrix's vehicle, kept out of the repository's scenarios: README, the
// pilot matrix): its belt line at 0.75 m, below the 0.9 m a small car's doors reach.
sim::VehicleShape sports_car() {
  return {.length = 4.4,
          .width = 1.95,
          .height = 1.15,
          .corner_radius = 0.4,
          .ground_clearance = 0.1,
          .belt_height = 0.75,
          .cabin_inset = 0.16,
          .hood_length = 1.5,
          .windscreen_run = 1.0,
          .rear_slope_run = 1.0,
          .wheel_radius = 0.33,
          .wheel_width = 0.26,
          .wheelbase = 2.55};
}

// The sports car's side 31 m from a VLP-16 5.5 m up (seed 11): one laser along it at 0.58-0.80 m. Its
// returns below the lower body's 0.63 m that tell the side's direction are four within 0.87 m at one end,
// one of them in the wheel arch, 0.28 m in; spread evenly they would span 1.17 m, longer than a short face,
// so the face through them stated 5.1 deg and was 21 deg off (the fix 16 deg off). A face whose returns
// reach less than a short face from first to last now departs as a short face does (informative_face.cpp).
TEST(VehicleFixGeometry, FewReturnsBunchedAtOneEndOfASideAreAShortFace) {
  const sim::VehicleShape shape = sports_car();
  const PilotCell cell = pilot_cell(lidar::make_vlp16(), 5.5, shape, 31.0, 41, 11);
  EXPECT_EQ(lasers_in(cell.view).size(), 1U);
  EXPECT_NE(judge(cell.view, shape, cell.truth, deg_to_rad(-3.2749)), Verdict::withheld);
}

// A city hatchback (a fourth pilot matrix's vehicle, as the sports car): short, its belt line at 0.85 m.
sim::VehicleShape city_hatchback() {
  return {.length = 3.57,
          .width = 1.63,
          .height = 1.49,
          .corner_radius = 0.38,
          .ground_clearance = 0.13,
          .belt_height = 0.85,
          .cabin_inset = 0.1,
          .hood_length = 0.65,
          .windscreen_run = 0.75,
          .rear_slope_run = 0.25,
          .wheel_radius = 0.3,
          .wheel_width = 0.2,
          .wheelbase = 2.3};
}

// The hatchback's rear 16 m from a 32-ring sensor 7.5 m up (seed 11), 9 deg from head-on: one laser along
// it at 0.72-0.87 m, crossing its belt line. Four of its returns lie below the lower body's 0.82 m, three at
// one end and one on the far corner 0.2 m in: their face was 9 deg off stating 2.8 deg. A face of fewer
// returns than the outline needs departs as a short face does (informative_face.cpp).
TEST(VehicleFixGeometry, AFaceOfFourReturnsOneOnACornerStatesIt) {
  const sim::VehicleShape shape = city_hatchback();
  const PilotCell cell = pilot_cell(*lidar::sensor_model_by_name("generic32"), 7.5, shape, 16.0, 58, 11);
  EXPECT_GT(cell.view.points.size(), 100U);
  EXPECT_NE(judge(cell.view, shape, cell.truth, deg_to_rad(6.5194)), Verdict::withheld);
}

// A kei car (a fifth pilot matrix's vehicle, kept out of the repository's scenarios as the sports car):
// tall (1.78 m), its bonnet short (0.45 m) and at 0.95 m, 53 % of its height.
sim::VehicleShape kei_car() {
  return {.length = 3.39,
          .width = 1.47,
          .height = 1.78,
          .corner_radius = 0.2,
          .ground_clearance = 0.15,
          .belt_height = 0.95,
          .cabin_inset = 0.06,
          .hood_length = 0.45,
          .windscreen_run = 0.55,
          .rear_slope_run = 0.05,
          .wheel_radius = 0.28,
          .wheel_width = 0.17,
          .wheelbase = 2.46};
}

// An MPV of our own (the same): 1.80 m tall, its bonnet 0.80 m long and at 0.92 m, 51 % of its height.
sim::VehicleShape mpv() {
  return {.length = 4.95,
          .width = 1.9,
          .height = 1.8,
          .corner_radius = 0.3,
          .ground_clearance = 0.15,
          .belt_height = 0.92,
          .cabin_inset = 0.08,
          .hood_length = 0.8,
          .windscreen_run = 0.9,
          .rear_slope_run = 0.1,
          .wheel_radius = 0.33,
          .wheel_width = 0.22,
          .wheelbase = 3.0};
}

// How far `p` lies ahead of the vehicle's centre along its true heading, and the foremost point's.
double ahead_of_centre(const PilotCell& cell, const Eigen::Vector3d& p) {
  return Eigen::Vector2d(std::cos(cell.truth.yaw), std::sin(cell.truth.yaw))
      .dot(Eigen::Vector2d(p.x() - cell.truth.x, p.y() - cell.truth.y));
}
double foremost_ahead(const PilotCell& cell) {
  double foremost = -std::numeric_limits<double>::infinity();
  for (const Eigen::Vector3d& p : cell.view.points)
    foremost = std::max(foremost, ahead_of_centre(cell, p));
  return foremost;
}

// Head-on (within 25 deg) from a mast, the lasers passing over the bonnet: the returns nearest the front lie
// on the windscreen's base, just above the bonnet but below 55 % of the height, and were taken for the front
// end set back by at most 0.3 m. The kei car 21 m from a VLP-32C 6.5 m up and 39 m from a HDL-32E 4.5 m up
// (seed 23): 0.32-0.35 m off stating 0.09 m along (NEES 12.4, 14.0: HMI); the MPV 30 m from a VLP-16 6.5 m up
// and 19 m from a VLP-32C 4.5 m up (seed 5): 0.70-0.73 m off (NEES 55-63). An end seen only above 0.9 m
// (full_plan_height_m) is now set back by up to a bonnet's length (low_bonnet_inset_m, 0.8 m).
TEST(VehicleFixGeometry, FrontSeenOnlyAtTheWindscreensBase) {
  struct Case {
    const char* model;
    bool kei;
    double height, distance;
    int frame;
    std::uint64_t seed;
    double prior_error_deg;
  };
  for (const Case c :
       {Case{"vlp32c", true, 6.5, 21.0, 29, 23, 0.2167}, Case{"hdl32e", true, 4.5, 39.0, 29, 23, 5.1911},
        Case{"vlp16", false, 6.5, 30.0, 30, 5, 6.8711}, Case{"vlp32c", false, 4.5, 19.0, 33, 5, 0.4920}}) {
    const sim::VehicleShape shape = c.kei ? kei_car() : mpv();
    const PilotCell cell =
        pilot_cell(*lidar::sensor_model_by_name(c.model), c.height, shape, c.distance, c.frame, c.seed);
    // The claimed view: head-on, nothing within 0.4 m of the front (the bumper and the bonnet's front
    // unseen), and the returns within 0.15 m of the foremost one above 0.9 m, several of them under 55 % of
    // the height.
    EXPECT_LT(angle_distance(cell.truth.yaw, std::numbers::pi), deg_to_rad(25.0)) << c.distance;
    const auto along = [&](const Eigen::Vector3d& p) { return ahead_of_centre(cell, p); };
    const double foremost = foremost_ahead(cell);
    EXPECT_LT(foremost, 0.5 * shape.length - 0.4) << c.distance;
    std::size_t lower_body = 0;
    for (const Eigen::Vector3d& p : cell.view.points) {
      if (along(p) < foremost - 0.15)
        continue;
      EXPECT_GT(p.z(), 0.9) << c.distance;
      lower_body += p.z() < 0.55 * shape.height;
    }
    EXPECT_GE(lower_body, 5U) << c.distance;
    EXPECT_NE(judge(cell.view, shape, cell.truth, deg_to_rad(c.prior_error_deg)), Verdict::withheld)
        << c.distance;
  }
}

// The same view on the minivan: the returns nearest its front lie on the windscreen's base at 0.86-0.9 m,
// below the full plan's height, and were taken for the front: these four 0.80-0.89 m off stating 0.04-0.1
// m (NEES 160-740; the pilot's cells, seed 5, 109 HMI fixes over 9 of them). Such an end, seen lowest above
// min_bonnet_height_m, now states a bonnet's length at 3 sigma along the length: covered.
TEST(VehicleFixGeometry, FrontSeenOnlyAtTheWindscreensBaseUnderTheFullPlanHeight) {
  struct Case {
    const char* model;
    double height, distance;
    int frame;
  };
  // A minivan of our own: 1.76 m tall, its bonnet 0.75 m long and at 0.86 m, 49 % of its height.
  const sim::VehicleShape shape = vehicle_file("low_bonnet/minivan");
  for (const Case c :
       {Case{"vlp16", 4.5, 15.0, 29}, Case{"vlp32c", 2.5, 5.0, 29}, Case{"vlp32c", 6.5, 21.0, 24},
        Case{"generic64", 4.5, 9.0, 27}, Case{"vlp16", 4.5, 14.0, 37}, Case{"vlp32c", 6.5, 36.0, 40}}) {
    const PilotCell cell =
        pilot_cell(*lidar::sensor_model_by_name(c.model), c.height, shape, c.distance, c.frame, 5);
    // The claimed view: nothing within 0.6 m of the front, the lowest return within 0.15 m of the foremost
    // one between 0.8 and 0.9 m (the windscreen rising behind it).
    const auto along = [&](const Eigen::Vector3d& p) { return ahead_of_centre(cell, p); };
    const double foremost = foremost_ahead(cell);
    EXPECT_LT(foremost, 0.5 * shape.length - 0.6) << c.model << " " << c.distance;
    double lowest = std::numeric_limits<double>::infinity();
    for (const Eigen::Vector3d& p : cell.view.points)
      lowest = along(p) >= foremost - 0.15 ? std::min(lowest, p.z()) : lowest;
    EXPECT_GT(lowest, 0.8) << c.model << " " << c.distance;
    EXPECT_LE(lowest, 0.9) << c.model << " " << c.distance;
    for (const double prior_error_deg : {-5.0, 0.0, 5.0}) {
      EXPECT_EQ(judge(cell.view, shape, cell.truth, deg_to_rad(prior_error_deg)), Verdict::covered)
          << c.model << " " << c.distance << " m, prior " << prior_error_deg << " deg";
    }
  }
}

// The minivan 29 m from a VLP-16 2.5 m up, seen from behind and one side: one laser's trace over its back
// and along its glasshouse at 0.95-1.1 m, leaving the body where the windscreen meets the bonnet (0.86 m),
// over a metre short of the front. The trace's front end, under the lower body's share (0.97 m), was
// taken for the body's end, where the body would have shown had it gone on at the front's height:
// 0.81-0.99 m off stating 0.31-0.38 m (NEES 12.5-20.4: HMI). A car's front may go on lower than that, down to
// min_bonnet_height_m, which no laser reaches there: containment bounds it.
TEST(VehicleFixGeometry, SideTraceLeavingOverALowBonnet) {
  const sim::VehicleShape shape = vehicle_file("low_bonnet/minivan");
  for (const int frame : {6, 53}) {
    const PilotCell cell = pilot_cell(lidar::make_vlp16(), 2.5, shape, 29.0, frame, 5);
    // The claimed view: every return above the bonnet, the foremost over 0.8 m short of the front.
    EXPECT_GT(lowest(cell.view), shape.belt_height) << frame;
    EXPECT_LT(highest(cell.view), 1.15) << frame;
    EXPECT_LT(foremost_ahead(cell), 0.5 * shape.length - 0.8) << frame;
    for (const double prior_error_deg : {-5.0, 0.0, 5.0}) {
      EXPECT_EQ(judge(cell.view, shape, cell.truth, deg_to_rad(prior_error_deg)), Verdict::covered)
          << frame << ", prior " << prior_error_deg << " deg";
    }
  }
}

// The minivan and the MPV 14 m from a VLP-32C 6.5 m up, within 20 deg of head-on: the front's returns are one
// laser's arc at one range across the bonnet's top (0.82-0.89 m, under the lower body's share), across the
// line of sight whatever the heading, and were taken for the front's vertical face: 17.3-18.0 deg off
// stating 1.5-2.1 deg (HMI: the fixes 0.58-0.68 m off). Between min_bonnet_height_m and the end's lower
// body such an arc tells no direction; the vehicle's own heading and its other faces do (here they leave the
// fix withheld, or covered).
TEST(VehicleFixGeometry, OneLasersArcOverALowBonnet) {
  for (const bool minivan : {true, false}) {
    const sim::VehicleShape shape =
        minivan ? vehicle_file("low_bonnet/minivan") : vehicle_file("low_bonnet/mpv");
    for (const int frame : {27, 32}) {
      const PilotCell cell = pilot_cell(lidar::make_vlp32c(), 6.5, shape, 14.0, frame, 5);
      // The claimed view: near head-on, the returns within 0.8 m of the foremost one between 0.75 and 0.97 m
      // (under the lower body's share), nine in ten of them within 0.1 m of one range.
      EXPECT_GT(angle_distance(cell.truth.yaw, std::numbers::pi), deg_to_rad(10.0)) << frame;
      EXPECT_LT(angle_distance(cell.truth.yaw, std::numbers::pi), deg_to_rad(20.0)) << frame;
      const double foremost = foremost_ahead(cell);
      std::vector<double> ranges;
      for (const Eigen::Vector3d& p : cell.view.points) {
        if (ahead_of_centre(cell, p) < foremost - 0.8)
          continue;
        EXPECT_GT(p.z(), 0.75) << frame;
        EXPECT_LT(p.z(), 0.97) << frame;
        ranges.push_back(p.head<2>().norm());
      }
      std::sort(ranges.begin(), ranges.end());
      const double median = ranges[ranges.size() / 2];
      const auto within =
          std::count_if(ranges.begin(), ranges.end(), [&](double r) { return std::abs(r - median) <= 0.1; });
      EXPECT_GE(static_cast<double>(within), 0.9 * static_cast<double>(ranges.size())) << frame;
      EXPECT_GE(ranges.size(), 20U) << frame;
      // Right, or its stated covariance covers it, or withheld (the vehicle's own heading, 10 deg, alone
      // leaves the centre open over more than max_position_sigma_m).
      for (const double prior_error_deg : {-5.0, 0.0, 5.0})
        judge(cell.view, shape, cell.truth, deg_to_rad(prior_error_deg));
    }
  }
}

// The minivan 5 m from a 64-ring sensor 2.5 m up, seen from behind along its length: the foremost return the
// fix keeps (thinned: every sixth column), on the side's sill under lowest_body_m, lies 0.3-0.45 m short of
// the front's rounded corner. The lasers
// passing above it are under lowest_body_m already there, and the shadow they bound took a negative reach
// beyond it, eating the corner's end_allowance_m: the box's front 0.24 m short of the interval's, the fix
// 0.31-0.42 m off stating 0.11-0.14 m (NEES 17: HMI). The shadow now reaches at least the extreme itself.
TEST(VehicleFixGeometry, ShadowBeyondALowExtreme) {
  const sim::VehicleShape shape = vehicle_file("low_bonnet/minivan");
  const PilotCell cell = pilot_cell(*lidar::sensor_model_by_name("generic64"), 2.5, shape, 5.0, 57, 5);
  // The claimed view: from behind within 20 deg of the length, the foremost return under 0.5 m 0.3-0.45 m
  // short of the front.
  EXPECT_LT(angle_distance(cell.truth.yaw, std::atan2(-cell.truth.y, -cell.truth.x) + std::numbers::pi),
            deg_to_rad(20.0));
  double foremost_low = -std::numeric_limits<double>::infinity();
  for (const Eigen::Vector3d& p : cell.view.points)
    foremost_low = p.z() < 0.5 ? std::max(foremost_low, ahead_of_centre(cell, p)) : foremost_low;
  EXPECT_GT(foremost_low, 0.5 * shape.length - 0.45);
  EXPECT_LT(foremost_low, 0.5 * shape.length - 0.3);
  for (const double prior_error_deg : {-5.0, 0.0, 5.0})
    EXPECT_NE(judge(cell.view, shape, cell.truth, deg_to_rad(prior_error_deg)), Verdict::withheld)
        << prior_error_deg;
}

// The minivan 30 m from a VLP-16 2.5 m up, seen from ahead and one side: one laser's trace, 0.89-1.01 m up,
// along the glasshouse above its 0.86 m belt line and across the windscreen's base. The side's points lie a
// window's inset (0.12 m) inside the doors, under the full plan's 0.9 m at the rear: taken for the doors,
// the fix was 0.43 m off stating 0.03 m across (NEES 15-16: HMI). A car's or MPV's side seen lowest above
// min_bonnet_height_m may be its glasshouse: its sigma now reaches the doors.
TEST(VehicleFixGeometry, GlasshouseSideOverALowBeltLine) {
  const sim::VehicleShape shape = vehicle_file("low_bonnet/minivan");
  for (const int frame : {21, 39}) {
    const PilotCell cell = pilot_cell(lidar::make_vlp16(), 2.5, shape, 30.0, frame, 5);
    // The claimed view: every return above min_bonnet_height_m and under 1.05 m, most on the side's glass
    // 0.08-0.16 m inside the doors.
    const Eigen::Vector2d left(-std::sin(cell.truth.yaw), std::cos(cell.truth.yaw));
    std::size_t on_glass = 0;
    for (const Eigen::Vector3d& p : cell.view.points) {
      EXPECT_GT(p.z(), 0.85);
      EXPECT_LT(p.z(), 1.05);
      const double inside =
          0.5 * shape.width - std::abs(left.dot(Eigen::Vector2d(p.x() - cell.truth.x, p.y() - cell.truth.y)));
      on_glass += inside > 0.08 && inside < 0.16;
    }
    EXPECT_GE(on_glass, cell.view.points.size() / 2) << frame;
    for (const double prior_error_deg : {-5.0, 0.0, 5.0})
      EXPECT_NE(judge(cell.view, shape, cell.truth, deg_to_rad(prior_error_deg)), Verdict::withheld)
          << frame << " " << prior_error_deg;
  }
}

// The minivan 36 m from a VLP-16 6.5 m up, seen from ahead and one side: one laser's trace along the side,
// falling from 1.05 to 0.69 m as the range grows, crosses the 0.86 m belt line: above it the glasshouse,
// 0.12 m inside the doors below it. Between min_bonnet_height_m and the lower body's 0.97 m it counted as
// the doors, so the side's direction was turned by that step: 3-5 deg off stating 0.7-1.4 deg (beyond 3
// sigma in yaw in 1.4 % of that pilot cell's fixes, 4.1 % of its worst 5 m band). A car's or MPV's returns
// there are now the upper body's, which tells the direction only as far as it runs with the lower body's.
TEST(VehicleFixGeometry, OneLasersTraceAcrossALowBeltLine) {
  const sim::VehicleShape shape = vehicle_file("low_bonnet/minivan");
  for (const int frame : {21, 39}) {
    const PilotCell cell = pilot_cell(lidar::make_vlp16(), 6.5, shape, 36.0, frame, 5);
    // The claimed view: one laser's returns (30-50) on either side of the belt line, those above it on the
    // glass, 0.08-0.2 m inside the doors.
    EXPECT_GE(cell.view.points.size(), 30U) << frame;
    EXPECT_LE(cell.view.points.size(), 50U) << frame;
    const Eigen::Vector2d left(-std::sin(cell.truth.yaw), std::cos(cell.truth.yaw));
    std::size_t below = 0, on_glass = 0;
    for (const Eigen::Vector3d& p : cell.view.points) {
      const double inside =
          0.5 * shape.width - std::abs(left.dot(Eigen::Vector2d(p.x() - cell.truth.x, p.y() - cell.truth.y)));
      below += p.z() < 0.8;
      on_glass += p.z() > 0.87 && inside > 0.08 && inside < 0.2;
    }
    EXPECT_GE(below, 3U) << frame;
    EXPECT_GE(on_glass, 8U) << frame;
    for (const double prior_error_deg : {-5.0, 0.0, 5.0})
      judge(cell.view, shape, cell.truth, deg_to_rad(prior_error_deg));
  }
}

}  // namespace
}  // namespace rsu::perception
