// SPDX-License-Identifier: Apache-2.0
#include "eval/corridor/vehicle_ndt_run.h"

#include <cmath>

#include "common/angles.h"
#include "eval/corridor/map_sampling.h"
#include "fusion/vehicle_ekf.h"
#include "lidar/point_eigen.h"
#include "sim/lidar_simulator.h"
#include "sim/raycaster.h"
#include "sim/trajectory.h"

namespace rsu::eval {
namespace {

const sim::Vehicle& find_vehicle(const sim::Scene& scene, std::uint32_t id) {
  for (const auto& v : scene.vehicles) {
    if (v.id == id)
      return v;
  }
  throw std::invalid_argument("no vehicle " + std::to_string(id));
}

// Moves each point from where the sensor was at its firing time to where it is at t_ref, assuming the
// vehicle moved at constant speed and yaw rate (in its own frame) over the sweep.
void deskew(std::vector<lidar::LidarPoint>& points, TimeNs t_ref, double speed, double yaw_rate,
            const Pose3& mount) {
  const Eigen::Isometry3d sensor_to_vehicle = mount.to_isometry();
  const Eigen::Isometry3d vehicle_to_sensor = sensor_to_vehicle.inverse();
  for (lidar::LidarPoint& p : points) {
    const double dt = to_seconds(p.time_ns - t_ref);  // <= 0
    const double dyaw = yaw_rate * dt;
    Eigen::Isometry3d motion = Eigen::Isometry3d::Identity();  // vehicle at t_i seen from vehicle at t_ref
    motion.linear() = Eigen::AngleAxisd(dyaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    motion.translation() =
        Eigen::Vector3d(speed * dt * std::cos(dyaw / 2), speed * dt * std::sin(dyaw / 2), 0.0);
    const Eigen::Vector3d q = vehicle_to_sensor * motion * sensor_to_vehicle * lidar::position_of(p);
    p.x = static_cast<float>(q.x());
    p.y = static_cast<float>(q.y());
    p.z = static_cast<float>(q.z());
  }
}

}  // namespace

std::vector<NdtSample> run_vehicle_ndt(const CorridorExperimentConfig& config, int threads,
                                       const std::function<void(int, int)>& progress) {
  const sim::Scene& scene = config.scenario.scene;
  const sim::Vehicle& vehicle = find_vehicle(scene, config.vehicle_id);
  const sim::Raycaster raycaster(scene);

  const std::vector<Eigen::Vector3f> map = sample_static_map(raycaster, config.map_spacing_m, config.seed);
  NdtLocalizer ndt(config.ndt, map, config.seed);

  const auto model = *lidar::sensor_model_by_name(config.vehicle_lidar_model);
  const sim::LidarSimulator lidar(model, config.vehicle_lidar_mount, config.vehicle_lidar_noise, raycaster, 0,
                                  0.0, &vehicle.trajectory);
  const TimeNs period = lidar.rotation_period_ns();
  const int frames = static_cast<int>(std::floor(config.duration_s / to_seconds(period)));

  // Start: localized and moving (the paper's vehicle drove into the street already localized). As in
  // Autoware, an EKF fed by NDT alone (no GNSS, no IMU) predicts each scan's initial guess and the
  // velocity the scan is de-skewed with; a raw difference of the last two NDT poses would feed every NDT
  // correction straight back into the speed.
  const TimeNs t_first = period;  // the first scan ends one rotation into the drive
  Pose2 start_pose = sim::pose_at(vehicle.trajectory, t_first);
  start_pose.x += config.initial_pose_error.x;
  start_pose.y += config.initial_pose_error.y;
  start_pose.yaw += config.initial_pose_error.yaw;
  const auto v0 = sim::velocity_at(vehicle.trajectory, t_first);
  fusion::VehicleEkf ekf;
  fusion::StateEstimate start_state;
  start_state.time = t_first - period;
  start_state.state << start_pose.x, start_pose.y, start_pose.yaw, std::hypot(v0.vx, v0.vy), v0.yaw_rate;
  start_state.state.head<2>() -= period * 1e-9 * std::hypot(v0.vx, v0.vy) *
                                 Eigen::Vector2d(std::cos(start_pose.yaw), std::sin(start_pose.yaw));
  start_state.covariance = fusion::StateMatrix::Identity() * 1e-4;
  ekf.initialize(start_state);

  std::vector<NdtSample> samples;
  for (int f = 0; f < frames; ++f) {
    const TimeNs start = f * period;
    const TimeNs t_ref = start + period;
    const auto predicted = ekf.estimate_at(t_ref);
    const Pose2 guess = predicted ? predicted->pose() : start_pose;
    const double speed = predicted ? predicted->state(fusion::kSpeed) : 0.0;
    const double yaw_rate = predicted ? predicted->state(fusion::kYawRate) : 0.0;

    sim::SimulatedFrame frame = lidar.simulate_frame(start, std::nullopt, threads);
    deskew(frame.frame.points, t_ref, speed, yaw_rate, config.vehicle_lidar_mount);
    const NdtResult r = ndt.align(frame.frame.points, config.vehicle_lidar_mount, guess);
    // The guess's predictor keeps the fixed covariance it is tuned with, whichever NDT reports: the poses
    // (and so the NDT baseline) do not depend on how their uncertainty is stated.
    ekf.add(fusion::PoseMeasurement{t_ref, fusion::MeasurementSource::kNdt, r.pose, r.fixed_covariance});

    NdtSample s;
    s.time_ns = t_ref;
    s.pose = r.pose;
    s.covariance = r.covariance;
    s.converged = r.converged;
    s.iterations = r.iterations;
    s.fitness = r.fitness;
    s.degeneracy = r.degeneracy;
    s.weak_axis_rad = r.weak_axis_rad;
    s.truth = sim::pose_at(vehicle.trajectory, t_ref);
    samples.push_back(s);
    if (progress)
      progress(f + 1, frames);
  }
  return samples;
}

}  // namespace rsu::eval
