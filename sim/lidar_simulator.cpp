#include "sim/lidar_simulator.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>
#include <utility>

#include "common/angles.h"
#include "common/random.h"

namespace rsu::sim {
namespace {

// Floor division for a possibly negative numerator and a positive denominator.
std::int64_t floor_div(std::int64_t a, std::int64_t b) {
  std::int64_t q = a / b;
  if ((a % b != 0) && (a < 0)) {
    --q;
  }
  return q;
}

bool pose_finite(const Pose3& p) {
  return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z) && std::isfinite(p.roll) &&
         std::isfinite(p.pitch) && std::isfinite(p.yaw);
}

void validate(const Pose3& mount, const NoiseModel& noise) {
  if (!pose_finite(mount)) {
    throw std::invalid_argument("LidarSimulator: mount pose must be finite");
  }
  if (!std::isfinite(noise.range_sigma_m) || noise.range_sigma_m < 0.0 || !std::isfinite(noise.angle_sigma_rad) ||
      noise.angle_sigma_rad < 0.0) {
    throw std::invalid_argument("LidarSimulator: noise sigmas must be finite and >= 0");
  }
}

// Noise key within a packet: one index per (block, channel), two draws each (angles, then range).
std::uint64_t noise_index(const Firing& f, bool range_draw) {
  const auto channel = static_cast<std::uint64_t>(f.block) * 65536U + static_cast<std::uint64_t>(f.channel);
  return 2U * channel + (range_draw ? 1U : 0U);
}

}  // namespace

bool AzimuthSector::contains(double azimuth_rad) const {
  const double a = wrap_angle_positive(azimuth_rad);
  const double b = wrap_angle_positive(begin_rad);
  const double e = wrap_angle_positive(end_rad);
  return b <= e ? (a >= b && a <= e) : (a >= b || a <= e);
}

LidarSimulator::LidarSimulator(const SensorModel& model, const Pose3& mount, const NoiseModel& noise,
                               const Raycaster& raycaster, TimeNs schedule_t0, double start_azimuth_deg)
    : LidarSimulator(model, mount, noise, nullptr, &raycaster, schedule_t0, start_azimuth_deg) {}

LidarSimulator::LidarSimulator(const SensorModel& model, const Pose3& mount, const NoiseModel& noise,
                               const Scene& scene, TimeNs schedule_t0, double start_azimuth_deg)
    : LidarSimulator(model, mount, noise, std::make_shared<const Raycaster>(scene), nullptr, schedule_t0,
                     start_azimuth_deg) {}

LidarSimulator::LidarSimulator(const SensorModel& model, const Pose3& mount, const NoiseModel& noise,
                               std::shared_ptr<const Raycaster> owned, const Raycaster* borrowed,
                               TimeNs schedule_t0, double start_azimuth_deg)
    : owned_raycaster_(std::move(owned)),
      raycaster_(owned_raycaster_ ? owned_raycaster_.get() : borrowed),
      schedule_(model, schedule_t0, start_azimuth_deg),
      schedule_t0_(schedule_t0),
      mount_(mount),
      mount_to_map_(mount.to_isometry()),
      noise_(noise) {
  validate(mount, noise);
  for (const double deg : model.elevation_deg) {
    // Same expression as the packet decoder (deg * pi / 180) so rebuilt points agree bit for bit.
    const double w = deg * std::numbers::pi / 180.0;
    elevation_rad_.push_back(w);
    cos_elevation_.push_back(std::cos(w));
    sin_elevation_.push_back(std::sin(w));
  }
}

TimeNs LidarSimulator::rotation_period_ns() const { return from_seconds(1.0 / model().rotation_hz()); }

std::int64_t LidarSimulator::packet_index_at(TimeNs t) const {
  return floor_div(t - schedule_t0_, schedule_.packet_period_ns());
}

std::vector<LidarSimulator::Outcome> LidarSimulator::run_packet(std::int64_t k, TimeNs t_begin, TimeNs t_end,
                                                                const std::optional<AzimuthSector>& sector) const {
  const SensorModel& m = model();
  const std::vector<Firing> firings = schedule_.firings(schedule_.packet(k));
  std::vector<Outcome> outcomes(firings.size());
  std::vector<Ray> rays;
  std::vector<std::size_t> ray_outcome;  // which outcome each ray belongs to
  rays.reserve(firings.size());
  ray_outcome.reserve(firings.size());
  const double sigma_a = noise_.angle_sigma_rad;
  // Rays may reach a little past max_range and still measure inside it once range noise is added.
  const double cast_limit = m.max_range_m + 6.0 * noise_.range_sigma_m + m.distance_unit_m;
  const Eigen::Vector3d origin = mount_to_map_.translation();
  const Eigen::Matrix3d to_map = mount_to_map_.linear();

  for (std::size_t i = 0; i < firings.size(); ++i) {
    const Firing& f = firings[i];
    Outcome& o = outcomes[i];
    o.firing = f;
    if (f.time_ns < t_begin || f.time_ns >= t_end || (sector && !sector->contains(f.azimuth_rad))) {
      continue;
    }
    o.cast = true;
    double w = elevation_rad_[f.laser];
    double a = f.azimuth_rad;
    if (sigma_a > 0.0) {
      const NormalPair n = standard_normal_pair(noise_.seed, static_cast<std::uint64_t>(k), noise_index(f, false));
      w += sigma_a * n.a;
      a += sigma_a * n.b;
    }
    const double cos_w = std::cos(w);
    const Eigen::Vector3d beam(cos_w * std::cos(a), -cos_w * std::sin(a), std::sin(w));
    Ray ray;
    ray.origin = origin;
    ray.direction = to_map * beam;
    ray.time_ns = f.time_ns;
    ray.max_range = cast_limit;
    rays.push_back(ray);
    ray_outcome.push_back(i);
  }

  std::vector<RayHit> hits(rays.size());
  raycaster_->cast_batch(rays, hits);

  for (std::size_t r = 0; r < rays.size(); ++r) {
    Outcome& o = outcomes[ray_outcome[r]];
    const RayHit& hit = hits[r];
    if (!hit.hit()) {
      continue;
    }
    o.truth.surface = hit.surface;
    o.truth.vehicle_id = hit.vehicle_id;
    o.truth.true_range_m = hit.range;
    double measured = hit.range;
    if (noise_.range_sigma_m > 0.0) {
      const NormalPair n = standard_normal_pair(noise_.seed, static_cast<std::uint64_t>(k), noise_index(o.firing, true));
      measured += noise_.range_sigma_m * n.a;
    }
    o.raw = quantize_distance(m, measured);  // 0 outside [min, max] range
    // Lambertian return: 255 * reflectivity * |cos(incidence)| (sim/scene.h).
    const double cos_incidence = std::abs(hit.normal.dot(rays[r].direction));
    o.intensity = static_cast<std::uint8_t>(std::clamp(std::round(255.0 * hit.reflectivity * cos_incidence), 0.0, 255.0));
  }
  return outcomes;
}

LidarPoint LidarSimulator::to_point(const Outcome& o) const {
  // The decoder's arithmetic (lidar/velodyne_packet.cpp), in the same order, so that the simulated
  // point equals the decoded one exactly.
  const double range = o.raw * model().distance_unit_m;
  const double horizontal = range * cos_elevation_[o.firing.laser];
  LidarPoint p;
  p.x = static_cast<float>(horizontal * std::cos(o.firing.azimuth_rad));
  p.y = static_cast<float>(-horizontal * std::sin(o.firing.azimuth_rad));
  p.z = static_cast<float>(range * sin_elevation_[o.firing.laser]);
  p.intensity = o.intensity;
  p.ring = o.firing.laser;
  const auto az = static_cast<float>(o.firing.azimuth_rad);
  p.azimuth_rad = az >= static_cast<float>(2.0 * std::numbers::pi) ? 0.0F : az;
  p.time_ns = o.firing.time_ns;
  return p;
}

PacketReturns LidarSimulator::simulate_packet(std::int64_t k, const std::optional<AzimuthSector>& sector) const {
  if (!model().has_packet_format()) {
    throw std::invalid_argument("LidarSimulator::simulate_packet: sensor model '" + model().name +
                                "' has no Velodyne packet format");
  }
  PacketReturns out;
  out.blocks = schedule_.packet(k);
  const auto outcomes = run_packet(k, std::numeric_limits<TimeNs>::min(), std::numeric_limits<TimeNs>::max(), sector);
  for (const Outcome& o : outcomes) {
    const auto b = static_cast<std::size_t>(o.firing.block);
    const auto c = static_cast<std::size_t>(o.firing.channel);
    out.distance_raw[b][c] = o.raw;
    out.reflectivity[b][c] = o.raw != 0 ? o.intensity : 0;
  }
  return out;
}

SimulatedFrame LidarSimulator::simulate_frame(TimeNs start, const std::optional<AzimuthSector>& sector) const {
  const TimeNs end = start + rotation_period_ns();
  SimulatedFrame result;
  result.frame.start_ns = std::numeric_limits<TimeNs>::max();
  result.frame.end_ns = std::numeric_limits<TimeNs>::min();
  // One packet of margin each side: packet starts are rounded to whole microseconds.
  const std::int64_t k_first = packet_index_at(start) - 1;
  const std::int64_t k_last = packet_index_at(end) + 1;
  const auto expected = static_cast<std::size_t>(model().laser_count() * model().sequences_per_rotation());
  result.frame.points.reserve(expected);
  result.truth.reserve(expected);
  for (std::int64_t k = k_first; k <= k_last; ++k) {
    for (const Outcome& o : run_packet(k, start, end, sector)) {
      const TimeNs t = o.firing.time_ns;
      if (t < start || t >= end) {
        continue;
      }
      ++result.counts.firings;
      result.frame.start_ns = std::min(result.frame.start_ns, t);
      result.frame.end_ns = std::max(result.frame.end_ns, t);
      if (!o.cast) {
        ++result.counts.outside_sector;
      } else if (o.truth.surface == SurfaceClass::kNone) {
        ++result.counts.no_hit;
      } else if (o.raw == 0) {
        ++result.counts.out_of_range;
      } else {
        ++result.counts.returns;
        result.frame.points.push_back(to_point(o));
        result.truth.push_back(o.truth);
      }
    }
  }
  if (result.counts.firings == 0) {
    result.frame.start_ns = start;
    result.frame.end_ns = start;
  }
  return result;
}

}  // namespace rsu::sim
