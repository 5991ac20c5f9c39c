// SPDX-License-Identifier: Apache-2.0
#include "eval/corridor/placement_study.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <span>
#include <sstream>
#include <stdexcept>

#include "common/angles.h"
#include "common/random.h"
#include "eval/consistency.h"
#include "lidar/point_eigen.h"
#include "lidar/sensor_model.h"
#include "perception/pipeline.h"
#include "perception/vehicle_fix.h"
#include "sim/lidar_simulator.h"
#include "sim/parallel_indices.h"
#include "sim/trajectory.h"

namespace rsu::eval {
namespace {

// A return of a simulated rotation that may hide part of a vehicle or is one (map frame): a vehicle's
// (vehicle_id its id) or a static object's above the road (vehicle_id 0).
struct Hit {
  Eigen::Vector3d xyz;
  TimeNs time_ns = 0;
  std::uint32_t vehicle_id = 0;
};

// The vehicles' returns and the static scene's at least min_static_z high: rsud passes each fix the
// background's returns that high (the static scene's objects) as occluders, beside the sweep's other
// detections (core/sweep_occluders.h). Without them a lamp post 1.1 m from a VLP-32C 6 m up hid a car's
// rear half and the front half's end was taken for its rear: 2.33 m off at NEES 216 (the corridor's
// north sidewalk), a fix rsud does not send.
std::vector<Hit> frame_hits(const sim::SimulatedFrame& frame, const Eigen::Isometry3d& to_map,
                            double min_static_z) {
  std::vector<Hit> hits;
  for (std::size_t i = 0; i < frame.frame.points.size(); ++i) {
    const sim::SurfaceClass surface = frame.truth[i].surface;
    if (surface == sim::SurfaceClass::kNone || surface == sim::SurfaceClass::kGround)
      continue;
    const lidar::LidarPoint& p = frame.frame.points[i];
    const Eigen::Vector3d xyz = to_map * lidar::position_of(p);
    const bool vehicle = surface == sim::SurfaceClass::kVehicle;
    if (vehicle || xyz.z() >= min_static_z)
      hits.push_back({xyz, p.time_ns, vehicle ? frame.truth[i].vehicle_id : 0U});
  }
  return hits;
}

double percentile(std::vector<double> v, double q) {
  if (v.empty())
    return std::numeric_limits<double>::quiet_NaN();
  std::sort(v.begin(), v.end());
  const auto rank = static_cast<std::size_t>(std::ceil(q * static_cast<double>(v.size())));
  return v[std::min(v.size(), std::max<std::size_t>(rank, 1)) - 1];
}

struct Placement {
  std::string model, lateral;
  double height_m = 0, y_m = 0;
};

// One vehicle's points in the rotation the sweep passes it in (from the three frames around it: a
// vehicle the frame cut falls on is whole in the window centred on it, as rsud's streaming sweep
// sees it), the other vehicles' and the static objects' returns of that window, and the fix.
PlacementSample score_vehicle(const sim::Vehicle& v, const std::vector<const std::vector<Hit>*>& frames,
                              TimeNs window_begin, TimeNs window_end,
                              const perception::LidarGeometry& lidar_in, const PlacementStudyConfig& config,
                              const perception::VehicleFixConfig& fix_config, std::uint64_t key) {
  std::vector<Eigen::Vector3d> points;
  std::vector<TimeNs> times;
  std::vector<Eigen::Vector2d> others, statics;
  for (const auto* hits : frames) {
    for (const Hit& h : *hits) {
      if (h.time_ns < window_begin || h.time_ns >= window_end)
        continue;
      if (h.vehicle_id == v.id) {
        points.push_back(h.xyz);
        times.push_back(h.time_ns);
      } else {
        (h.vehicle_id == 0 ? statics : others).push_back(h.xyz.head<2>());
      }
    }
  }
  TimeNs t = window_begin + (window_end - window_begin) / 2;
  if (!times.empty()) {
    std::nth_element(times.begin(), times.begin() + static_cast<std::ptrdiff_t>(times.size() / 2),
                     times.end());
    t = times[times.size() / 2];
  }
  const Pose2 truth = sim::pose_at(v.trajectory, t);
  PlacementSample s;
  s.vehicle_id = v.id;
  s.along_road_m = truth.x - lidar_in.position.x();
  s.lane_y_m = truth.y;
  s.points = points.size();

  // The vehicle's true outline (corners and edge midpoints), its azimuth span seen from the LiDAR, and
  // the other vehicles' returns within that span nearer than its far side: what may hide part of it
  // (passed to the fix as rsud passes the sweep's other detections). It counts as occluded when one of
  // them lies on the line of sight to a point of its outline (LidarGeometry::occluded).
  const Eigen::Vector2d lidar_xy = lidar_in.xy();
  const Eigen::Vector2d centre(truth.x, truth.y);
  const double centre_dir = std::atan2(centre.y() - lidar_xy.y(), centre.x() - lidar_xy.x());
  const double c = std::cos(truth.yaw), sn = std::sin(truth.yaw);
  std::vector<Eigen::Vector2d> outline;
  for (const double a : {-0.5, 0.0, 0.5}) {
    for (const double b : {-0.5, 0.0, 0.5}) {
      if (a != 0.0 || b != 0.0)
        outline.push_back(centre + Eigen::Vector2d(c * a * v.shape.length - sn * b * v.shape.width,
                                                   sn * a * v.shape.length + c * b * v.shape.width));
    }
  }
  double lo = 0, hi = 0, far = 0;
  for (const Eigen::Vector2d& p : outline) {
    const Eigen::Vector2d d = p - lidar_xy;
    const double rel = wrap_angle(std::atan2(d.y(), d.x()) - centre_dir);
    lo = std::min(lo, rel);
    hi = std::max(hi, rel);
    far = std::max(far, d.norm());
  }
  const double margin = 2.0 * lidar_in.azimuth_step_rad;
  perception::LidarGeometry lidar = lidar_in;
  const auto add_in_view = [&](std::span<const Eigen::Vector2d> objects) {
    for (const Eigen::Vector2d& o : objects) {
      const Eigen::Vector2d d = o - lidar_xy;
      const double rel = wrap_angle(std::atan2(d.y(), d.x()) - centre_dir);
      if (rel >= lo - margin && rel <= hi + margin && d.norm() < far)
        lidar.occluders.push_back(o);
    }
  };
  add_in_view(others);
  constexpr double kOutlineMarginM = 0.3;  // an occluder this much nearer than the outline point
  for (const Eigen::Vector2d& p : outline)
    s.occluded = s.occluded || lidar.occluded(p, kOutlineMarginM);
  // The static objects hide it from the fix too (frame_hits); `occluded` counts the traffic's doing.
  add_in_view(statics);

  perception::AnnouncedVehicle announced;
  announced.size = {v.shape.length, v.shape.width, v.shape.height};
  const double u = 2.0 * uniform_open01(key) - 1.0;
  announced.yaw_prior = perception::YawPrior{truth.yaw + deg_to_rad(config.prior_error_deg) * u,
                                             deg_to_rad(config.prior_error_deg)};
  const perception::VehicleFix fix = perception::fix_vehicle(points, announced, lidar, fix_config);
  s.status = std::string(perception::to_string(fix.status()));
  s.fixed = fix.ok();
  if (s.fixed) {
    const Eigen::Vector2d e(fix.corrected.pose.x - truth.x, fix.corrected.pose.y - truth.y);
    s.error_m = e.norm();
    s.nees = position_nees(e, fix.corrected.covariance.topLeftCorner<2, 2>());
  }
  return s;
}

void summarise(PlacementResult& r, const PlacementStudyConfig& config) {
  const int bins = static_cast<int>(std::lround(2.0 * config.coverage_radius_m / config.coverage_bin_m));
  std::vector<int> in_bin(static_cast<std::size_t>(bins), 0), good_in_bin(static_cast<std::size_t>(bins), 0);
  std::vector<double> errors;
  for (const PlacementSample& s : r.samples) {
    ++r.vehicle_rotations;
    const bool accurate = s.fixed && s.error_m < config.accurate_m;
    if (s.fixed) {
      ++r.fixes;
      errors.push_back(s.error_m);
      r.accurate += accurate ? 1 : 0;
      const bool beyond = s.nees > kChi2TwoDof3Sigma;
      r.beyond_3sigma += beyond ? 1 : 0;
      r.hmi += beyond && s.error_m > config.hmi_m ? 1 : 0;
    }
    if (s.occluded) {
      ++r.occluded;
      r.occlusion_losses += accurate ? 0 : 1;
    }
    const int b =
        static_cast<int>(std::floor((s.along_road_m + config.coverage_radius_m) / config.coverage_bin_m));
    if (b >= 0 && b < bins) {
      ++in_bin[static_cast<std::size_t>(b)];
      good_in_bin[static_cast<std::size_t>(b)] += accurate ? 1 : 0;
    }
  }
  r.bin_share.assign(static_cast<std::size_t>(bins), std::numeric_limits<double>::quiet_NaN());
  for (std::size_t b = 0; b < r.bin_share.size(); ++b) {
    if (in_bin[b] == 0)
      continue;
    r.bin_share[b] = static_cast<double>(good_in_bin[b]) / in_bin[b];
    r.coverage_m += r.bin_share[b] >= config.bin_covered_share ? config.coverage_bin_m : 0.0;
  }
  double sum = 0;
  for (const double e : errors)
    sum += e;
  r.mae_m =
      errors.empty() ? std::numeric_limits<double>::quiet_NaN() : sum / static_cast<double>(errors.size());
  r.p95_m = percentile(errors, 0.95);
}

PlacementResult run_placement(const sim::Scenario& scenario, const Placement& p,
                              const PlacementStudyConfig& config) {
  const auto start = std::chrono::steady_clock::now();
  const auto model = lidar::sensor_model_by_name(p.model);
  if (!model)
    throw std::invalid_argument("placement study: unknown LiDAR model " + p.model);
  Pose3 mount = scenario.lidar.mount;
  mount.y = p.y_m;
  mount.z = p.height_m;
  mount.roll = mount.pitch = 0.0;
  const sim::LidarSimulator simulator(*model, mount, scenario.lidar.noise, scenario.scene);
  const Eigen::Isometry3d to_map = mount.to_isometry();

  perception::LidarGeometry lidar;
  lidar.position = {mount.x, mount.y, mount.z};
  for (const double e : model->elevation_deg)
    lidar.elevations_rad.push_back(deg_to_rad(e));
  lidar.azimuth_step_rad = deg_to_rad(model->azimuth_step_deg());
  const perception::PerceptionConfig perception;  // rsud's
  const perception::VehicleFixConfig& fix_config = perception.fix;
  const double min_static_z = perception.ground.ground_z + perception.ground.min_height;

  const TimeNs period = simulator.rotation_period_ns();
  const int rotations = static_cast<int>(std::floor(config.duration_s / to_seconds(period)));
  PlacementResult r;
  r.model = p.model;
  r.lateral = p.lateral;
  r.height_m = p.height_m;
  r.mount_y_m = p.y_m;
  std::vector<std::vector<Hit>> window(3);  // frames k-1, k, k+1
  for (int k = 0; k < 2 && k < rotations; ++k)
    window[static_cast<std::size_t>(k + 1)] =
        frame_hits(simulator.simulate_frame(k * period), to_map, min_static_z);
  for (int k = 1; k + 1 < rotations; ++k) {
    std::rotate(window.begin(), window.begin() + 1, window.end());
    window[2] = frame_hits(simulator.simulate_frame((k + 1) * period), to_map, min_static_z);
    if ((k - 1) % std::max(1, config.rotation_stride) != 0)
      continue;
    const TimeNs frame_start = k * period;
    const std::vector<const std::vector<Hit>*> frames = {&window[0], &window[1], &window[2]};
    for (const sim::Vehicle& v : scenario.scene.vehicles) {
      const Pose2 mid = sim::pose_at(v.trajectory, frame_start + period / 2);
      if (std::abs(mid.x - mount.x) > config.coverage_radius_m)
        continue;
      // When the sweep passes the vehicle's centre in this rotation (azimuth clockwise from the sensor's
      // +x, the frame starting at azimuth 0): the window is the rotation centred there.
      const Eigen::Vector3d in_sensor = to_map.inverse() * Eigen::Vector3d(mid.x, mid.y, 0.0);
      const double azimuth = wrap_angle_positive(std::atan2(-in_sensor.y(), in_sensor.x()));
      const TimeNs t_c =
          frame_start + static_cast<TimeNs>(azimuth / (2.0 * kPi) * static_cast<double>(period));
      const std::uint64_t key =
          mix64(config.seed ^ mix64(0x706c6163ULL + v.id * 1000003ULL + static_cast<std::uint64_t>(k)));
      PlacementSample s =
          score_vehicle(v, frames, t_c - period / 2, t_c + period / 2, lidar, config, fix_config, key);
      if (std::abs(s.along_road_m) <= config.coverage_radius_m)
        r.samples.push_back(std::move(s));
    }
  }
  summarise(r, config);
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return r;
}

std::string fmt(double v, int precision) {
  if (!std::isfinite(v))
    return "-";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.*f", precision, v);
  return buf;
}

std::string share(std::size_t n, std::size_t of) {
  return of == 0 ? "-" : fmt(100.0 * static_cast<double>(n) / static_cast<double>(of), 1) + " %";
}

}  // namespace

std::vector<PlacementResult> run_placement_study(const sim::Scenario& scenario,
                                                 const PlacementStudyConfig& config) {
  std::vector<Placement> placements;
  for (const std::string& m : config.models) {
    for (const auto& [name, y] : config.laterals) {
      for (const double h : config.heights_m)
        placements.push_back({m, name, h, y});
    }
  }
  std::vector<PlacementResult> results(placements.size());
  sim::run_indices_in_parallel(placements.size(), config.threads, [&](std::size_t i) {
    results[i] = run_placement(scenario, placements[i], config);
    std::fprintf(
        stderr, "placement %zu/%zu: %s %s %.0f m: %zu vehicle-rotations, coverage %.0f m, HMI %zu (%.0f s)\n",
        i + 1, placements.size(), results[i].model.c_str(), results[i].lateral.c_str(), results[i].height_m,
        results[i].vehicle_rotations, results[i].coverage_m, results[i].hmi, results[i].seconds);
  });
  return results;
}

std::string placement_csv(const std::vector<PlacementResult>& results) {
  std::ostringstream out;
  out << "model,lateral,mount_y_m,height_m,vehicle_rotations,fixes,accurate,coverage_m,mae_m,p95_m,beyond_"
         "3sigma,"
         "hmi,occluded,occlusion_losses,seconds,bin_shares\n";
  for (const PlacementResult& r : results) {
    out << r.model << ',' << r.lateral << ',' << r.mount_y_m << ',' << r.height_m << ','
        << r.vehicle_rotations << ',' << r.fixes << ',' << r.accurate << ',' << r.coverage_m << ','
        << fmt(r.mae_m, 4) << ',' << fmt(r.p95_m, 4) << ',' << r.beyond_3sigma << ',' << r.hmi << ','
        << r.occluded << ',' << r.occlusion_losses << ',' << fmt(r.seconds, 1) << ',';
    for (std::size_t b = 0; b < r.bin_share.size(); ++b)
      out << (b ? ";" : "") << fmt(r.bin_share[b], 3);
    out << '\n';
  }
  return out.str();
}

std::string placement_samples_csv(const std::vector<PlacementResult>& results) {
  std::ostringstream out;
  out << "model,lateral,height_m,vehicle_id,along_road_m,lane_y_m,points,occluded,status,error_m,nees\n";
  for (const PlacementResult& r : results) {
    for (const PlacementSample& s : r.samples) {
      out << r.model << ',' << r.lateral << ',' << r.height_m << ',' << s.vehicle_id << ','
          << fmt(s.along_road_m, 2) << ',' << fmt(s.lane_y_m, 2) << ',' << s.points << ','
          << (s.occluded ? 1 : 0) << ',' << s.status << ',' << (s.fixed ? fmt(s.error_m, 4) : "") << ','
          << (s.fixed ? fmt(s.nees, 2) : "") << '\n';
    }
  }
  return out.str();
}

std::string placement_table(const std::vector<PlacementResult>& results, const PlacementStudyConfig& config) {
  std::ostringstream out;
  out << "| LiDAR | lateral | height | coverage (m of " << fmt(2 * config.coverage_radius_m, 0)
      << ") | fixed | < " << fmt(config.accurate_m, 2)
      << " m | MAE | p95 | > 3σ | HMI | occluded | occlusion losses |\n";
  out << "|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const PlacementResult& r : results) {
    out << "| " << r.model << " | " << r.lateral << " (y " << fmt(r.mount_y_m, 1) << ") | "
        << fmt(r.height_m, 0) << " m | " << fmt(r.coverage_m, 0) << " | "
        << share(r.fixes, r.vehicle_rotations) << " | " << share(r.accurate, r.vehicle_rotations) << " | "
        << fmt(r.mae_m, 3) << " | " << fmt(r.p95_m, 3) << " | " << share(r.beyond_3sigma, r.fixes) << " | "
        << r.hmi << " | " << r.occluded << " | " << r.occlusion_losses << " |\n";
  }
  return out.str();
}

std::string placement_json(const std::vector<PlacementResult>& results, const PlacementStudyConfig& config,
                           const std::string& scenario_source) {
  std::ostringstream out;
  out << "{\n  \"scenario\": \"" << scenario_source << "\",\n"
      << "  \"fix_configuration\": \"rsud's: perception::PerceptionConfig defaults (deploy/rsud.yaml keeps "
         "them), "
         "improved correction\",\n"
      << "  \"segmentation\": \"perfect (the simulator's per-return vehicle id); other vehicles' and the "
         "static "
         "objects' returns (0.2 m or more above the road) as occluders\",\n"
      << "  \"coverage_radius_m\": " << config.coverage_radius_m
      << ", \"coverage_bin_m\": " << config.coverage_bin_m
      << ", \"bin_covered_share\": " << config.bin_covered_share << ", \"accurate_m\": " << config.accurate_m
      << ", \"hmi_m\": " << config.hmi_m << ", \"rotation_stride\": " << config.rotation_stride
      << ",\n  \"placements\": [";
  for (std::size_t i = 0; i < results.size(); ++i) {
    const PlacementResult& r = results[i];
    out << (i ? "," : "") << "\n    {\"model\": \"" << r.model << "\", \"lateral\": \"" << r.lateral
        << "\", \"mount_y_m\": " << r.mount_y_m << ", \"height_m\": " << r.height_m
        << ", \"vehicle_rotations\": " << r.vehicle_rotations << ", \"fixes\": " << r.fixes
        << ", \"accurate\": " << r.accurate << ", \"coverage_m\": " << r.coverage_m
        << ", \"mae_m\": " << (std::isfinite(r.mae_m) ? fmt(r.mae_m, 4) : "null")
        << ", \"p95_m\": " << (std::isfinite(r.p95_m) ? fmt(r.p95_m, 4) : "null")
        << ", \"beyond_3sigma\": " << r.beyond_3sigma << ", \"hmi\": " << r.hmi
        << ", \"occluded\": " << r.occluded << ", \"occlusion_losses\": " << r.occlusion_losses << "}";
  }
  out << "\n  ]\n}\n";
  return out.str();
}

}  // namespace rsu::eval
