// SPDX-License-Identifier: Apache-2.0
// Scenario files (YAML): the LiDAR, its mount, the scene and the vehicles (scenarios/*.yaml).
// Every error names the file, the line and the field, e.g.
//   scenarios/pilot.yaml:12: lidar.mount.z: expected a number, got "two"
#pragma once

#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

#include "common/pose.h"
#include "common/time.h"
#include "lidar/sensor_model.h"
#include "sim/scene.h"

namespace rsu::sim {

struct LidarConfig {
  std::string model_name = "vlp16";
  lidar::SensorModel model;  // resolved from model_name (and rpm)
  Pose3 mount;               // sensor pose in the map frame
  NoiseModel noise;
  double start_azimuth_deg = 0.0;
  // lidar.mount_motion: the sensor moved mid-run about where `mount` puts it (a bumped or leaning
  // pole): a trajectory (the vehicles' syntax) of its displacement x, y (m) and turn yaw_deg about the
  // vertical through it, in the map frame; nullopt: it stays. `rsu-sim stream` follows it; the
  // simulate command (backgrounds) does not.
  std::optional<Trajectory> mount_motion;
};

// The carrier trajectory and the mount on it (sim/lidar_simulator.h) that move the sensor by
// `lidar.mount_motion` about `lidar.mount`.
struct MovingMount {
  Trajectory carrier;
  Pose3 mount_on_carrier;
};
MovingMount moving_mount(const LidarConfig& lidar);

struct Scenario {
  std::string name;
  std::string source;  // file the scenario was read from
  LidarConfig lidar;
  Scene scene;
  TimeNs start_ns = 0;  // time of the first simulated frame
  int frames = 10;      // how many frames the main command simulates
};

class ScenarioError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Throws ScenarioError with "<source>:<line>: <field path>: <what is wrong>".
Scenario parse_scenario(std::string_view yaml_text, const std::string& source_name);
Scenario load_scenario_file(const std::string& path);

// A vehicle body on its own: a YAML map holding `shape:` with the scenario files' vehicle shape fields
// (length, width, height, belt_height, ...; sim/scene.h VehicleShape), and optionally `name:`.
// Throws ScenarioError located as above.
struct NamedVehicleShape {
  std::string name;
  VehicleShape shape;
};
NamedVehicleShape parse_vehicle_shape(std::string_view yaml_text, const std::string& source_name);
NamedVehicleShape load_vehicle_shape_file(const std::string& path);

}  // namespace rsu::sim
