// SPDX-License-Identifier: Apache-2.0
// The realistic experiment's own parts: the NDT map, the vehicle's NDT self-localization and the error
// statistics of the table, against ground truth the tests compute themselves.
#include <gtest/gtest.h>

#include <Eigen/Cholesky>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "common/angles.h"
#include "eval/corridor/map_sampling.h"
#include "eval/corridor/ndt_localizer.h"
#include "eval/corridor/placement_study.h"
#include "eval/corridor/report.h"
#include "lidar/sensor_model.h"
#include "sim/lidar_simulator.h"
#include "sim/mesh.h"
#include "sim/raycaster.h"
#include "sim/scenario.h"

namespace rsu::eval {
namespace {

TEST(MapSampling, PointsLieOnTheSurfaceAtTheRequestedDensity) {
  // A 10 m x 4 m wall in the plane x = 3: 40 m^2 at 0.25 m spacing is 640 points on average.
  sim::TriangleMesh wall;
  wall.vertices = {{3, 0, 0}, {3, 10, 0}, {3, 10, 4}, {3, 0, 4}};
  wall.triangles = {{0, 1, 2}, {0, 2, 3}};
  const auto points = sample_surface(wall, 0.25, 7);
  EXPECT_NEAR(static_cast<double>(points.size()), 640.0, 3.0);
  double mean_y = 0, mean_z = 0;
  for (const auto& p : points) {
    EXPECT_FLOAT_EQ(p.x(), 3.0F);
    EXPECT_GE(p.y(), 0.0F);
    EXPECT_LE(p.y(), 10.0F);
    EXPECT_GE(p.z(), 0.0F);
    EXPECT_LE(p.z(), 4.0F);
    mean_y += static_cast<double>(p.y());
    mean_z += static_cast<double>(p.z());
  }
  // Uniform over the wall: the mean is its centre (5, 2) within a few standard errors.
  EXPECT_NEAR(mean_y / static_cast<double>(points.size()), 5.0, 0.35);
  EXPECT_NEAR(mean_z / static_cast<double>(points.size()), 2.0, 0.15);
  EXPECT_EQ(sample_surface(wall, 0.25, 7).size(), points.size());  // seeded
}

TEST(NdtLocalizer, ConvergesFromAnOffsetGuessInTheCorridor) {
  const sim::Scenario scenario = sim::load_scenario_file(RSU_SOURCE_DIR "/scenarios/corridor.yaml");
  sim::Scene scene = scenario.scene;
  scene.vehicles.clear();
  const sim::Raycaster raycaster(scene);
  std::vector<Eigen::Vector3f> map;
  for (auto surface : {sim::SurfaceClass::kGround, sim::SurfaceClass::kBuilding, sim::SurfaceClass::kPole,
                       sim::SurfaceClass::kVegetation}) {
    const auto part = sample_surface(raycaster.static_mesh(surface), 0.5, 3);
    map.insert(map.end(), part.begin(), part.end());
  }
  // A roof LiDAR standing still at a known pose near a lamp and the hedges.
  const Pose2 truth{-12.0, -3.5, deg_to_rad(3.0)};
  const Pose3 mount{0.0, 0.0, 2.0, 0.0, 0.0, 0.0};
  const Pose3 sensor_in_map{truth.x, truth.y, mount.z, 0.0, 0.0, truth.yaw};
  const sim::LidarSimulator lidar(lidar::make_vlp16(), sensor_in_map, sim::NoiseModel{}, raycaster);
  const auto frame = lidar.simulate_frame(0);

  NdtConfig config;  // Autoware's parameters
  NdtLocalizer ndt(config, map, 5);
  const Pose2 guess{truth.x + 0.5, truth.y - 0.3, truth.yaw + deg_to_rad(2.0)};
  const NdtResult result = ndt.align(frame.frame.points, mount, guess);
  EXPECT_TRUE(result.converged);
  // One 0.1 m step cannot cover a 0.58 m offset: NDT must iterate (PCL's epsilon is a squared step).
  EXPECT_GT(result.iterations, 1);
  EXPECT_LT(std::hypot(result.pose.x - truth.x, result.pose.y - truth.y), 0.1);
  EXPECT_LT(angle_distance(result.pose.yaw, truth.yaw), deg_to_rad(0.5));
  EXPECT_GT(result.scan_points, 100u);
  EXPECT_NEAR(result.covariance(0, 0), config.output_sigma_xy_m * config.output_sigma_xy_m, 1e-12);

  // The match's own covariance (Laplace): the same pose, a covariance tighter than Autoware's fixed
  // 0.15 m where the corridor's lamps and hedges hold the match, never below its floor, and honest: the
  // error is within 3 sigma on each axis.
  NdtConfig laplace_config;
  laplace_config.covariance_estimate = NdtConfig::CovarianceEstimate::kLaplace;
  NdtLocalizer laplace_ndt(laplace_config, map, 5);
  const NdtResult laplace = laplace_ndt.align(frame.frame.points, mount, guess);
  EXPECT_DOUBLE_EQ(laplace.pose.x, result.pose.x);
  EXPECT_EQ(laplace.fixed_covariance, result.covariance);
  const Eigen::Matrix3d& c = laplace.covariance;
  EXPECT_TRUE(c.isApprox(c.transpose()));
  EXPECT_GT(c.llt().info() == Eigen::Success ? c.determinant() : -1.0, 0.0);
  for (int axis = 0; axis < 2; ++axis) {
    const double sigma = std::sqrt(c(axis, axis));
    EXPECT_GE(sigma, laplace_config.laplace_min_sigma_xy_m - 1e-9);
    EXPECT_LT(sigma, laplace_config.output_sigma_xy_m);
    EXPECT_LE(std::abs((axis == 0 ? laplace.pose.x - truth.x : laplace.pose.y - truth.y)), 3.0 * sigma);
  }
  EXPECT_LE(angle_distance(laplace.pose.yaw, truth.yaw), 3.0 * std::sqrt(c(2, 2)));
}

TEST(ErrorStats, MatchesHandComputedValues) {
  // 20 errors 0.01 .. 0.20: MAE 0.105, RMSE sqrt(mean of squares), nearest-rank p95 = the 19th value.
  std::vector<double> errors;
  double sum_sq = 0;
  for (int i = 1; i <= 20; ++i) {
    errors.push_back(0.01 * i);
    sum_sq += 0.0001 * i * i;
  }
  const ErrorStats s = error_stats(errors);
  EXPECT_EQ(s.count, 20u);
  EXPECT_NEAR(s.mae_m, 0.105, 1e-12);
  EXPECT_NEAR(s.rmse_m, std::sqrt(sum_sq / 20.0), 1e-12);
  EXPECT_NEAR(s.p95_m, 0.19, 1e-12);
  EXPECT_NEAR(s.max_m, 0.20, 1e-12);
  EXPECT_EQ(error_stats({}).count, 0u);
}

TEST(ErrorStats, ShareBeyondThreeSigmaCountsOnlyStatedCovariances) {
  // NEES 1 and 5 lie inside the 2-dof 3-sigma bound (11.83), 20 beyond it; NaN is an estimate without a
  // covariance and does not count either way.
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const ErrorStats s = error_stats({0.1, 0.2, 0.3, 0.4}, {1.0, 20.0, nan, 5.0});
  EXPECT_NEAR(s.beyond_3sigma, 1.0 / 3.0, 1e-12);
  EXPECT_TRUE(std::isnan(error_stats({0.1}, {nan}).beyond_3sigma));
  EXPECT_TRUE(std::isnan(error_stats({0.1}).beyond_3sigma));
}

// The goals compare the fused pose with NDT and the RSU frame for frame: a frame (an NDT pose) is within
// the RSU's coverage when a fix was swept in the frame period ending at it (the newest such fix counts);
// the frames without one compare the fused pose with NDT alone.
TEST(FusedGoals, ComparesFrameForFrameWithinAndBeyondTheRsusCoverage) {
  ExperimentScores scores;
  const auto estimate = [](double t_ms, double along_m, double error_m) {
    ScoredEstimate e;
    e.time_ns = static_cast<TimeNs>(t_ms * 1e6);
    e.along_road_m = along_m;
    e.error_m = error_m;
    return e;
  };
  // Four frames, 100 ms apart, at 0, 10, 20 and 45 m along the road.
  scores.estimates["ndt"] = {estimate(0, 0, 0.2), estimate(100, 10, 0.2), estimate(200, 20, 0.2),
                             estimate(300, 45, 0.1)};
  scores.estimates["fused_vlp16"] = {estimate(0, 0, 0.25), estimate(100, 10, 0.03), estimate(200, 20, 0.04),
                                     estimate(300, 45, 0.05)};
  // Fixes: one for the frame at 100 ms; two in the period before 200 ms (the newer, 0.04 m, counts); none
  // for the first frame (swept after it) nor the last (beyond the RSU's last fix).
  scores.estimates["rsu_vlp16"] = {estimate(50, 5, 0.02), estimate(140, 14, 0.5), estimate(160, 16, 0.04)};
  const std::vector<FusedGoals> goals = fused_goals(scores, {"vlp16", "vlp32c"});  // no vlp32c scores
  ASSERT_EQ(goals.size(), 2u);
  const FusedGoals& pm36 = goals[0];
  EXPECT_EQ(pm36.range, "pm36");
  EXPECT_EQ(pm36.covered_frames, 2u);
  EXPECT_EQ(pm36.uncovered_frames, 1u);
  EXPECT_NEAR(pm36.fused_mae_m, 0.035, 1e-12);
  EXPECT_NEAR(pm36.ndt_mae_m, 0.2, 1e-12);
  EXPECT_NEAR(pm36.rsu_mae_m, 0.03, 1e-12);
  EXPECT_NEAR(pm36.best_mae_m, 0.03, 1e-12);
  EXPECT_NEAR(pm36.reduction_vs_ndt, 1.0 - 0.035 / 0.2, 1e-12);
  EXPECT_TRUE(pm36.below_ndt_met());
  EXPECT_FALSE(pm36.covered_no_worse());  // 0.035 m against the RSU's 0.030 m on the same frames
  EXPECT_NEAR(pm36.fused_uncovered_mae_m, 0.25, 1e-12);
  EXPECT_FALSE(pm36.uncovered_no_worse());  // the first frame: 0.25 m against NDT's 0.2 m
  EXPECT_NEAR(pm36.reduction_vs_ndt_all_frames, 1.0 - (0.25 + 0.03 + 0.04) / 0.6, 1e-12);
  // The cell: fused (0.25 + 0.03 + 0.04) / 3 against the better's (2 x 0.03 + 0.2) / 3.
  EXPECT_NEAR(pm36.fused_all_mae_m, 0.32 / 3.0, 1e-12);
  EXPECT_NEAR(pm36.better_all_mae_m, 0.26 / 3.0, 1e-12);
  EXPECT_FALSE(pm36.no_worse_met());
  const FusedGoals& pm50 = goals[1];
  EXPECT_EQ(pm50.covered_frames, 2u);
  EXPECT_EQ(pm50.uncovered_frames, 2u);
  EXPECT_NEAR(pm50.fused_uncovered_mae_m, 0.15, 1e-12);
  EXPECT_NEAR(pm50.ndt_uncovered_mae_m, 0.15, 1e-12);
  EXPECT_TRUE(pm50.uncovered_no_worse());
  // (0.25 + 0.03 + 0.04 + 0.05) / 4 against (2 x 0.03 + 0.2 + 0.1) / 4: still worse, by 2.5 mm.
  EXPECT_FALSE(pm50.no_worse_met());
  // Had the fused pose been 4 cm better on the first frame: no worse over the cell, though worse than
  // the RSU on its frames (0.035 against 0.030 m).
  scores.estimates["fused_vlp16"][0].error_m = 0.21;
  EXPECT_TRUE(fused_goals(scores, {"vlp16"})[1].no_worse_met());
  EXPECT_FALSE(fused_goals(scores, {"vlp16"})[1].covered_no_worse());
  scores.estimates["fused_vlp16"][0].error_m = 0.25;
  // An RSU without a fix in the range leaves every frame uncovered: the fused pose is held to NDT alone.
  scores.estimates["rsu_vlp16"].clear();
  const FusedGoals none = fused_goals(scores, {"vlp16"})[0];
  EXPECT_EQ(none.covered_frames, 0u);
  EXPECT_EQ(none.uncovered_frames, 3u);
  EXPECT_TRUE(none.below_ndt_met());
  EXPECT_TRUE(none.covered_no_worse());
  EXPECT_NEAR(none.fused_uncovered_mae_m, (0.25 + 0.03 + 0.04) / 3.0, 1e-12);
  EXPECT_TRUE(none.uncovered_no_worse());  // against NDT's 0.2 m
}

// Traffic: a correction nearer another vehicle's true position than its own vehicle's is counted as the
// wrong vehicle's, for the experiment's vehicle (its corrections CSV) and the fleet's (rsu-fleet lines),
// and one naming another vehicle too; HMI: beyond 3 sigma and more than 0.30 m off.
TEST(TrafficScores, CountsCorrectionsNearerAnotherVehicleAsWrong) {
  CorridorExperimentConfig config;
  config.scenario = sim::parse_scenario(R"(
name: traffic_score_test
lidar: {model: vlp16, mount: {x: 0, y: -8.5, z: 2}}
vehicles:
  - {id: 1, trajectory: {static: {x: 0, y: -5.25, yaw_deg: 0}}}
  - {id: 2, trajectory: {static: {x: 0, y: -1.75, yaw_deg: 0}}}
  - {id: 3, trajectory: {static: {x: 20, y: 5.25, yaw_deg: 180}}}
)",
                                        "traffic_score_test");
  config.vehicle_id = 1;
  config.rsu_models = {"vlp16"};
  config.traffic_connected = {3};
  const std::filesystem::path dir = std::filesystem::path(::testing::TempDir()) / "traffic_scores";
  std::filesystem::create_directories(dir);
  const long long epoch = 1'000'000'000;
  std::ofstream(dir / "epoch_vlp16.txt") << epoch << "\n";
  std::ofstream(dir / "ndt.csv") << "time_ns,x,y,yaw\n100000000,0.1,-5.25,0\n";
  std::ofstream(dir / "fused_vlp16.csv") << "time_ns,x,y,yaw,source\n"
                                         << epoch + 100000000 << ",0,-5.25,0,ndt\n";
  // Vehicle 1: 0.05 m off (its own); 0.3 m from vehicle 2, 3.2 m from its own (wrong); 0.5 m off stating
  // sigma 0.1 m (HMI, its own).
  std::ofstream(dir / "corrections_vlp16.csv") << "time_ns,x,y,yaw,cxx,cxy,cyy\n"
                                               << epoch + 100000000 << ",0.05,-5.25,0,0.01,0,0.01\n"
                                               << epoch + 200000000 << ",0,-2.05,0,0.01,0,0.01\n"
                                               << epoch + 300000000 << ",0.5,-5.25,0,0.01,0,0.01\n";
  // Vehicle 3 (the fleet): its own at 0.02 m; one addressed to it naming vehicle 1; one at vehicle 2.
  const auto line = [&](int named, double x, double y, double sigmas) {
    return "correction 0 3 " + std::to_string(named) + " 1 1 " + std::to_string(epoch + 100000000) + " " +
           std::to_string(x) + " " + std::to_string(y) + " 3.14 100 0 0 0 0 " + std::to_string(sigmas) + "\n";
  };
  std::ofstream(dir / "fleet_vlp16.corrections")
      << "# a comment line\n"
      << line(3, 20.02, 5.25, 0.5) << line(1, 20.0, 5.25, 0.5) << line(3, 0.2, -1.75, 40.0);
  const ExperimentScores scores = score_experiment(config, dir.string());
  ASSERT_EQ(scores.traffic.count("vlp16"), 1u);
  const TrafficScores& t = scores.traffic.at("vlp16");
  EXPECT_EQ(t.vehicle_corrections, 3u);
  EXPECT_EQ(t.vehicle_wrong, 1u);
  EXPECT_EQ(t.vehicle_hmi, 2u);  // the wrong one (3.2 m off, 32 sigma) and the 0.5 m one (5 sigma)
  EXPECT_EQ(t.fleet_corrections, 3u);
  EXPECT_EQ(t.fleet_wrong, 2u);
  EXPECT_EQ(t.fleet_hmi, 1u);  // the one at vehicle 2, ~21 m from vehicle 3, 40 sigma
  EXPECT_EQ(t.fleet_pm50.count, 3u);
  EXPECT_NEAR(t.fleet_pm50.max_m, std::hypot(19.8, 7.0), 1e-3);
  EXPECT_NE(summary_json(scores, {"ndt", "rsu_vlp16"}).find("\"wrong_vehicle\": 3"), std::string::npos);
}

// The placement study on one street: a car passes a VLP-16 at 2 m in the inner lane while a truck stands
// in the outer lane between them for part of the pass. Unoccluded, the fix rsud runs is accurate (the
// pilot's 2 m VLP-16); the truck hides the car at some rotations, and the summary counts the samples.
TEST(PlacementStudy, ScoresEveryVehicleRotationAndFlagsOcclusion) {
  const sim::Scenario scenario = sim::parse_scenario(R"(
name: placement_test
lidar: {model: vlp16, mount: {x: 0, y: -8.5, z: 2}, noise: {seed: 3}}
scene: {ground: {half_extent_m: 60}}
vehicles:
  - id: 1
    trajectory: {waypoints: [{t_s: 0, x: -12, y: -1.75, yaw_deg: 0}, {t_s: 2.0, x: 10, y: -1.75, yaw_deg: 0}]}
  - id: 2
    shape: {length: 8.5, width: 2.5, height: 3.6, belt_height: 1.3, hood_length: 0.3, windscreen_run: 0.15,
            wheelbase: 5.0, wheel_radius: 0.48}
    trajectory: {static: {x: 6, y: -5.25, yaw_deg: 0}}
)",
                                                     "placement_test");
  PlacementStudyConfig config;
  config.models = {"vlp16"};
  config.heights_m = {2.0};
  config.laterals = {{"curb", -8.5}};
  config.duration_s = 2.0;
  config.threads = 1;
  const std::vector<PlacementResult> results = run_placement_study(scenario, config);
  ASSERT_EQ(results.size(), 1u);
  const PlacementResult& r = results[0];
  EXPECT_EQ(r.vehicle_rotations, r.samples.size());
  std::size_t occluded_car = 0, clear_car = 0, fixes = 0;
  std::vector<double> clear_errors;
  for (const PlacementSample& s : r.samples) {
    EXPECT_LE(std::abs(s.along_road_m), config.coverage_radius_m);
    fixes += s.fixed ? 1 : 0;
    if (s.vehicle_id == 2) {
      EXPECT_FALSE(s.occluded);  // nothing stands between the truck and the LiDAR
      continue;
    }
    // Independently: the truck (x 1.75..10.25, y -6.5..-4) lies on the line of sight from (0, -8.5) to the
    // car's centre when that line crosses y = -5.25 within the truck's length.
    const double x_at_truck = s.along_road_m * (8.5 - 5.25) / (8.5 - 1.75);
    const bool behind_truck = x_at_truck > 1.75 && x_at_truck < 10.25;
    if (behind_truck) {
      EXPECT_TRUE(s.occluded) << "car at x " << s.along_road_m;
    }
    occluded_car += s.occluded ? 1 : 0;
    if (!s.occluded && std::abs(s.along_road_m) > 4.0) {
      ++clear_car;
      if (s.fixed)
        clear_errors.push_back(s.error_m);
    }
  }
  EXPECT_GE(occluded_car, 3u);
  EXPECT_GE(clear_car, 5u);
  ASSERT_GE(clear_errors.size(), clear_car / 2);
  std::sort(clear_errors.begin(), clear_errors.end());
  EXPECT_LT(clear_errors[clear_errors.size() / 2], config.accurate_m);
  EXPECT_EQ(r.fixes, fixes);
  EXPECT_LE(r.occlusion_losses, r.occluded);
  EXPECT_LE(r.coverage_m, 2 * config.coverage_radius_m);
}

// rsud passes each fix the static scene's objects as occluders, and so must the study that stands for it:
// a lamp post 1.1 m from a VLP-32C 6 m up on the corridor's north sidewalk hid the rear half of a car
// changing lanes 12 m away, and the front half's end was taken for the car's rear (2.33 and 1.17 m off at
// NEES 216 and 54, `rsu-corridor placement`; with the post passed the fix is withheld or right).
TEST(PlacementStudy, StaticObjectsHideVehiclesFromTheFixAsInRsud) {
  const sim::Scenario scenario = sim::parse_scenario(R"(
name: placement_lamp_post
lidar: {model: vlp32c, mount: {x: 0, y: 8.5, z: 6}, noise: {seed: 7}}
scene:
  ground: {half_extent_m: 60}
  poles: [{x: 0, y: 7.4, radius: 0.12, height: 8, arm_length: 1.5, arm_yaw_deg: -90}]
vehicles:
  - id: 1
    shape: {length: 4.89, width: 1.92, height: 1.70}
    trajectory: {waypoints: [{t_s: 0, x: -3.0, y: -4.40, yaw_deg: 7}, {t_s: 1.0, x: 8.0, y: -3.05, yaw_deg: 7}]}
)",
                                                     "placement_lamp_post");
  PlacementStudyConfig config;
  config.models = {"vlp32c"};
  config.heights_m = {6.0};
  config.laterals = {{"across", 8.5}};
  config.duration_s = 1.0;
  config.threads = 1;
  const std::vector<PlacementResult> results = run_placement_study(scenario, config);
  ASSERT_EQ(results.size(), 1u);
  std::size_t behind_post = 0;
  for (const PlacementSample& s : results[0].samples) {
    // Independently: the post's shadow (its radius seen from 1.1 m, +-6.2 deg) spans x within 1.35 m of
    // the mast's at the car's lane 12 m away; a car whose footprint reaches into it is partly hidden.
    behind_post += std::abs(s.along_road_m) < 1.35 + 4.89 / 2.0 ? 1 : 0;
    EXPECT_FALSE(s.occluded) << "no other vehicle stands in the way, at x " << s.along_road_m;
    if (s.fixed) {
      EXPECT_TRUE(s.error_m <= config.hmi_m || s.nees <= 11.829)
          << "HMI fix at x " << s.along_road_m << ": " << s.error_m << " m off, NEES " << s.nees;
    }
  }
  EXPECT_GE(behind_post, 3u);
  EXPECT_EQ(results[0].hmi, 0u);
}

}  // namespace
}  // namespace rsu::eval
