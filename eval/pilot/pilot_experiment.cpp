// SPDX-License-Identifier: Apache-2.0
#include "eval/pilot/pilot_experiment.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include <Eigen/Core>

#include "common/angles.h"
#include "common/random.h"
#include "eval/consistency.h"
#include "eval/pilot/outline_observability.h"
#include "lidar/point_eigen.h"
#include "lidar/sensor_model.h"
#include "perception/ground_height_filter.h"
#include "sim/lidar_simulator.h"
#include "sim/parallel_indices.h"
#include "sim/trajectory.h"
#include "sim/vehicle_mesh.h"

namespace rsu::eval {
namespace {

// Angle between two box axes: boxes have no front, so mod 180 deg, in [0, 90].
double axis_error_deg(double a, double b) {
  double d = std::fmod(std::abs(a - b), kPi);
  return rad_to_deg(std::min(d, kPi - d));
}

// The LiDAR faces away from the vehicle (mount yaw 180 deg) so that the vehicle, on the map's +x axis,
// is swept in the middle of each rotation rather than split across the frame cut at azimuth 0.
Pose3 pilot_mount(const PilotConfig& config) {
  Pose3 mount;
  mount.z = config.lidar_height_m;
  mount.yaw = kPi;
  return mount;
}

// Only the azimuths around the vehicle are cast: the rest of the empty scene is ground, which the
// pilot's filter removes anyway. Saves 80-95 % of the rays; noise is keyed per firing, so the cast rays
// see exactly the noise they would in a full frame.
std::optional<sim::AzimuthSector> vehicle_sector(const Pose3& mount, double distance,
                                                 const sim::VehicleShape& shape) {
  const double radius = 0.5 * std::hypot(shape.length, shape.width) + 0.5;
  if (radius >= distance)
    return std::nullopt;
  const Eigen::Vector3d in_sensor = mount.to_isometry().inverse() * Eigen::Vector3d(distance, 0, 0);
  const double centre = wrap_angle_positive(std::atan2(-in_sensor.y(), in_sensor.x()));  // clockwise
  const double half = std::asin(radius / distance);
  return sim::AzimuthSector{wrap_angle_positive(centre - half), wrap_angle_positive(centre + half)};
}

struct DistanceRun {
  std::vector<PilotCell> cells;
  std::uint64_t rays = 0;
};

// A method's fix scored against the truth.
MethodCell score(const perception::VehicleFix& fix, const Pose2& truth) {
  MethodCell m;
  m.status = std::string(perception::to_string(fix.status()));
  if (!fix.ok())
    return m;
  const Pose2& pose = fix.corrected.pose;
  const Eigen::Vector2d error(pose.x - truth.x, pose.y - truth.y);
  const Eigen::Matrix2d position_cov = fix.corrected.covariance.topLeftCorner<2, 2>();
  m.center_err_m = error.norm();
  m.yaw_err_deg = axis_error_deg(pose.yaw, truth.yaw);
  m.sigma_m = perception::position_sigma_m(fix.corrected);
  m.yaw_sigma_deg = rad_to_deg(std::sqrt(std::max(0.0, fix.corrected.covariance(2, 2))));
  m.position_nees = position_nees(error, position_cov);
  return m;
}

// The raw L-shape box: the paper takes its centre, and the yaw from the longer edge (Sec. 3.1).
MethodCell score_lshape(const perception::RectangleFit& fit, const Pose2& truth) {
  MethodCell m;
  m.status = fit.ok() ? "ok" : std::string(perception::to_string(fit.status));
  if (!fit.ok())
    return m;
  m.center_err_m = (fit.center - Eigen::Vector2d(truth.x, truth.y)).norm();
  m.yaw_err_deg = axis_error_deg(fit.length0 >= fit.length1 ? fit.yaw : fit.yaw + kPi / 2, truth.yaw);
  return m;
}

// The vehicle's points of one frame: the non-ground points near it, in the map frame.
// The paper drops zero-height points and is left with "only vehicle points" (Sec. 3.1). Here far ground
// returns at grazing incidence rise above any height threshold under beam-angle noise
// (ground_height_filter.h), and clustering would split an end-on car whose roof and rear face lie more
// than the tolerance apart (as it does in a real pipeline). The pilot measures the fix, not the
// segmentation, so it keeps the non-ground points near the vehicle: a region of interest of the
// vehicle's bounding circle plus 1 m around its true centre.
std::vector<Eigen::Vector3d> vehicle_points(const sim::SimulatedFrame& frame, const Eigen::Isometry3d& to_map,
                                            const PilotConfig& config, double distance,
                                            std::vector<TimeNs>& times) {
  const perception::GroundHeightFilter ground({.ground_z = 0.0, .min_height = config.ground_filter_height_m});
  const double roi_radius = 0.5 * std::hypot(config.vehicle.length, config.vehicle.width) + 1.0;
  std::vector<lidar::LidarPoint> map_points;
  map_points.reserve(frame.frame.points.size());
  for (const lidar::LidarPoint& p : frame.frame.points) {
    const Eigen::Vector3d m = to_map * lidar::position_of(p);
    lidar::LidarPoint q = p;
    q.x = static_cast<float>(m.x());
    q.y = static_cast<float>(m.y());
    q.z = static_cast<float>(m.z());
    map_points.push_back(q);
  }
  std::vector<Eigen::Vector3d> out;
  times.clear();
  for (std::uint32_t i : ground.select_foreground(map_points).indices) {
    const lidar::LidarPoint& p = map_points[i];
    if (std::hypot(static_cast<double>(p.x) - distance, static_cast<double>(p.y)) > roi_radius)
      continue;
    out.push_back(lidar::position_of(p));
    times.push_back(p.time_ns);
  }
  return out;
}

DistanceRun run_distance(const PilotConfig& config, const lidar::SensorModel& model, int distance_index,
                         double distance, int frames_per_turn) {
  const TimeNs period = from_seconds(60.0 / model.rpm);
  const TimeNs t0 = static_cast<TimeNs>(distance_index) * frames_per_turn * period;

  sim::Scene scene;
  scene.ground.half_extent_m = config.distance_max_m + 20.0;
  sim::Vehicle vehicle;
  vehicle.id = 1;
  vehicle.shape = config.vehicle;
  vehicle.trajectory = sim::Spin{distance, 0.0, 0.0, deg_to_rad(config.spin_rate_deg_s), t0};
  scene.vehicles.push_back(vehicle);

  const Pose3 mount = pilot_mount(config);
  const Eigen::Isometry3d to_map = mount.to_isometry();
  perception::LidarGeometry lidar;
  lidar.position = {mount.x, mount.y, mount.z};
  for (const double e : model.elevation_deg)
    lidar.elevations_rad.push_back(deg_to_rad(e));
  lidar.azimuth_step_rad = deg_to_rad(model.azimuth_step_deg());
  const sim::LidarSimulator simulator(model, mount, config.noise, scene);
  const auto sector = vehicle_sector(mount, distance, config.vehicle);
  perception::VehicleFixConfig improved_config = config.fix;
  improved_config.method = perception::CorrectionMethod::improved;
  perception::VehicleFixConfig alg1_config = config.fix;
  alg1_config.method = perception::CorrectionMethod::algorithm1;
  perception::AnnouncedVehicle announced;
  announced.size = {config.vehicle.length, config.vehicle.width, config.vehicle.height};

  DistanceRun run;
  std::vector<TimeNs> times;
  for (int j = 0; j < frames_per_turn; ++j) {
    const sim::SimulatedFrame frame = simulator.simulate_frame(t0 + j * period, sector);
    run.rays += frame.counts.firings - frame.counts.outside_sector;
    const std::vector<Eigen::Vector3d> points = vehicle_points(frame, to_map, config, distance, times);

    PilotCell cell;
    cell.distance_m = distance;
    cell.frame_in_turn = j;
    cell.points = points.size();
    if (!times.empty()) {
      std::nth_element(times.begin(), times.begin() + static_cast<std::ptrdiff_t>(times.size() / 2),
                       times.end());
      cell.sweep_ns = times[times.size() / 2];
    } else {
      cell.sweep_ns = t0 + j * period + period / 2;
    }
    const Pose2 truth = sim::pose_at(vehicle.trajectory, cell.sweep_ns);
    cell.yaw_deg = rad_to_deg(wrap_angle_positive(truth.yaw));
    cell.outline_seen = observe_outline(points, truth, config.vehicle.length, config.vehicle.width).seen();

    // The vehicle's own yaw estimate: the truth plus a uniform error in [-bound, +bound], drawn per cell.
    const std::uint64_t key = mix64(
        config.noise.seed ^ mix64(0x70696c6f74ULL + static_cast<std::uint64_t>(distance_index) * 100000ULL +
                                  static_cast<std::uint64_t>(j)));
    const double u = 2.0 * uniform_open01(key) - 1.0;
    announced.yaw_prior = perception::YawPrior{truth.yaw + deg_to_rad(config.prior_error_deg) * u,
                                               deg_to_rad(config.prior_sigma_deg)};

    const perception::VehicleFix improved =
        perception::fix_vehicle(points, announced, lidar, improved_config);
    const perception::VehicleFix alg1 = perception::fix_vehicle(points, announced, lidar, alg1_config);
    cell.fit_ok = alg1.fit.ok();
    if (cell.fit_ok)
      cell.area_err_m2 = alg1.fit.length0 * alg1.fit.length1 - config.vehicle.length * config.vehicle.width;
    cell.methods[static_cast<std::size_t>(PilotMethod::lshape)] = score_lshape(alg1.fit, truth);
    cell.methods[static_cast<std::size_t>(PilotMethod::algorithm1)] = score(alg1, truth);
    cell.methods[static_cast<std::size_t>(PilotMethod::improved)] = score(improved, truth);
    cell.improved_resolution =
        improved.fit.ok() ? std::string(perception::to_string(improved.corrected.resolution)) : "no_fit";
    run.cells.push_back(std::move(cell));
  }
  return run;
}

// Spinning at `distance`, the vehicle would reach into a LiDAR mounted lower than its roof.
bool vehicle_reaches_lidar(const PilotConfig& config, double distance) {
  const double reach = 0.5 * std::hypot(config.vehicle.length, config.vehicle.width) + 0.3;
  return reach >= distance && config.vehicle.height + 0.1 >= config.lidar_height_m;
}

}  // namespace

const char* to_string(PilotMethod method) {
  switch (method) {
    case PilotMethod::lshape:
      return "lshape";
    case PilotMethod::algorithm1:
      return "algorithm1";
    case PilotMethod::improved:
      return "improved";
  }
  return "unknown";
}

PilotResult run_pilot(const PilotConfig& config) {
  const auto model = lidar::sensor_model_by_name(config.model_name);
  if (!model)
    throw std::invalid_argument("unknown LiDAR model " + config.model_name);
  if (!(config.distance_step_m > 0) || config.distance_max_m < config.distance_min_m ||
      config.distance_min_m <= 0)
    throw std::invalid_argument("pilot: need 0 < distance_min <= distance_max and a positive step");
  const double period_s = 60.0 / model->rpm;
  PilotResult result;
  result.config = config;
  result.frames_per_turn = static_cast<int>(std::lround(360.0 / (config.spin_rate_deg_s * period_s)));
  if (result.frames_per_turn < 1 || result.frames_per_turn > 36000)
    throw std::invalid_argument("pilot: bad spin rate");
  const int steps = static_cast<int>(std::floor(
                        (config.distance_max_m - config.distance_min_m) / config.distance_step_m + 1e-9)) +
                    1;
  // Each distance keeps its index in the full list (its time and the prior's random draws), so that a
  // skipped one changes no other.
  std::vector<int> indices;
  for (int i = 0; i < steps; ++i) {
    const double d = config.distance_min_m + i * config.distance_step_m;
    if (vehicle_reaches_lidar(config, d)) {
      result.skipped_distances.push_back(d);
    } else {
      result.distances.push_back(d);
      indices.push_back(i);
    }
  }
  sim::validate_vehicle_shape(config.vehicle);

  const auto wall_start = std::chrono::steady_clock::now();
  std::vector<DistanceRun> runs(result.distances.size());
  sim::run_indices_in_parallel(runs.size(), config.threads, [&](std::size_t i) {
    runs[i] = run_distance(config, *model, indices[i], result.distances[i], result.frames_per_turn);
  });
  for (auto& r : runs) {
    result.rays_cast += r.rays;
    result.cells.insert(result.cells.end(), r.cells.begin(), r.cells.end());
  }
  result.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  return result;
}

}  // namespace rsu::eval
