// SPDX-License-Identifier: Apache-2.0
// Frames of the corridor scenario (scenarios/corridor.yaml) for the perception benchmarks: background
// frames with the vehicles removed, and a frame with the vehicle in view, all in the map frame.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "common/pose.h"
#include "lidar/point.h"
#include "lidar/point_eigen.h"
#include "lidar/sensor_model.h"
#include "sim/lidar_simulator.h"
#include "sim/scenario.h"
#include "sim/trajectory.h"

namespace rsu::bench {

struct CorridorFrames {
  std::string model_name;
  Eigen::Vector2d lidar_xy = Eigen::Vector2d::Zero();
  Eigen::Vector3d lidar_position = Eigen::Vector3d::Zero();
  std::vector<std::vector<lidar::LidarPoint>> background;  // frames without vehicles
  std::vector<lidar::LidarPoint> frame;                    // the vehicle in view
  Pose2 vehicle_pose;                                      // at the frame's middle
  sim::VehicleShape vehicle_shape;
};

inline std::vector<lidar::LidarPoint> to_map_frame(const lidar::LidarFrame& frame, const Pose3& mount) {
  const Eigen::Isometry3d t = mount.to_isometry();
  std::vector<lidar::LidarPoint> out = frame.points;
  for (auto& p : out) {
    const Eigen::Vector3d q = t * lidar::position_of(p);
    p.x = static_cast<float>(q.x());
    p.y = static_cast<float>(q.y());
    p.z = static_cast<float>(q.z());
  }
  return out;
}

// model_name: "vlp16", "vlp32c", "generic128", ...; frame_time_s: when the vehicle frame starts.
inline CorridorFrames make_corridor_frames(const std::string& model_name, double frame_time_s = 6.0,
                                           int background_frames = 3) {
  const sim::Scenario scenario = sim::load_scenario_file(RSU_SOURCE_DIR "/scenarios/corridor.yaml");
  CorridorFrames out;
  out.model_name = model_name;
  lidar::SensorModel model = *lidar::sensor_model_by_name(model_name);
  model.rpm = scenario.lidar.model.rpm;
  const Pose3& mount = scenario.lidar.mount;
  out.lidar_xy = Eigen::Vector2d(mount.x, mount.y);
  out.lidar_position = Eigen::Vector3d(mount.x, mount.y, mount.z);

  sim::Scene empty = scenario.scene;
  empty.vehicles.clear();
  const sim::LidarSimulator empty_sim(model, mount, scenario.lidar.noise, empty);
  for (int k = 0; k < background_frames; ++k) {
    // Frames 0.35 s apart: the firing azimuths differ from frame to frame, as in a real recording.
    const auto f = empty_sim.simulate_frame(from_seconds(1.0 + 0.35 * k));
    out.background.push_back(to_map_frame(f.frame, mount));
  }
  const sim::LidarSimulator sim(model, mount, scenario.lidar.noise, scenario.scene);
  const TimeNs start = from_seconds(frame_time_s);
  out.frame = to_map_frame(sim.simulate_frame(start).frame, mount);
  const auto& vehicle = scenario.scene.vehicles.front();
  out.vehicle_pose = sim::pose_at(vehicle.trajectory, start + sim.rotation_period_ns() / 2);
  out.vehicle_shape = vehicle.shape;
  return out;
}

}  // namespace rsu::bench
