// SPDX-License-Identifier: Apache-2.0
// The realistic experiment's configuration (scenarios/corridor_experiment.yaml): the scenario it runs in,
// the vehicle's own LiDAR and NDT parameters, and which RSU LiDAR models to compare.
#pragma once

#include <string>
#include <vector>

#include "common/pose.h"
#include "eval/corridor/ndt_localizer.h"
#include "sim/scenario.h"

namespace rsu::eval {

struct CorridorExperimentConfig {
  std::string source;
  sim::Scenario scenario;
  std::uint32_t vehicle_id = 1;
  // Other connected vehicles of the scenario (traffic, issue 13 item 3): they announce their true poses
  // through rsu-fleet in the live runs; the rest of the scenario's vehicles are not connected.
  std::vector<std::uint32_t> traffic_connected;
  std::vector<std::string> rsu_models;
  double duration_s = 10.8;
  std::uint64_t seed = 11;
  std::string vehicle_lidar_model = "vlp16";
  Pose3 vehicle_lidar_mount;  // vehicle frame
  sim::NoiseModel vehicle_lidar_noise;
  double map_spacing_m = 0.25;
  NdtConfig ndt;
  Pose2 initial_pose_error;  // added to the true start pose to seed NDT
};

// Throws io::YamlError / sim::ScenarioError naming the file, line and field.
CorridorExperimentConfig load_corridor_experiment(const std::string& path);

}  // namespace rsu::eval
