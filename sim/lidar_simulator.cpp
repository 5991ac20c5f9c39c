// SPDX-License-Identifier: Apache-2.0
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
#include "sim/parallel_indices.h"
#include "sim/trajectory.h"

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
  if (!std::isfinite(noise.range_sigma_m) || noise.range_sigma_m < 0.0 ||
      !std::isfinite(noise.angle_sigma_rad) || noise.angle_sigma_rad < 0.0) {
    throw std::invalid_argument("LidarSimulator: noise sigmas must be finite and >= 0");
  }
}

// Keyed by (seed, packet k, block, channel) in the counter-based way of common/random.h (its mix64
// and uniform_open01), so a firing's noise does not depend on what else is simulated or in which
// order. Inverse-CDF sampling instead of random.h's Box-Muller pairs: the log, sqrt and sincos of
// each pair made noise ~5 ms of a VLP-32C frame; this way it is ~1.5 ms (bench/sim).
FiringNoise firing_noise(std::uint64_t seed, std::int64_t k, const lidar::Firing& f) {
  const auto slot = static_cast<std::uint64_t>(f.block) * 65536U + static_cast<std::uint64_t>(f.channel);
  const std::uint64_t key = mix64(seed ^ mix64(static_cast<std::uint64_t>(k) ^ mix64(slot)));
  // Three decorrelated streams from one key (arbitrary odd constants, then the SplitMix64 mixer).
  return {normal_quantile(uniform_open01(mix64(key))),
          normal_quantile(uniform_open01(mix64(key ^ 0x632be59bd9b4e019ULL))),
          normal_quantile(uniform_open01(mix64(key ^ 0x8cb92ba72f3d8dd7ULL)))};
}

struct CosSin {
  double c;
  double s;
};

// cos and sin of a small angle: Taylor series below 0.01 rad, where the first omitted terms
// (d^6 / 720, d^7 / 5040) are below 1e-15 of the result; the library functions otherwise.
CosSin small_angle_cos_sin(double d) {
  if (std::abs(d) < 0.01) {
    const double d2 = d * d;
    constexpr double kInv6 = 1.0 / 6.0;
    constexpr double kInv24 = 1.0 / 24.0;
    constexpr double kInv120 = 1.0 / 120.0;
    return {1.0 - d2 * (0.5 - d2 * kInv24), d * (1.0 - d2 * (kInv6 - d2 * kInv120))};
  }
  return {std::cos(d), std::sin(d)};
}

}  // namespace

bool AzimuthSector::contains(double azimuth_rad) const {
  const double a = wrap_angle_positive(azimuth_rad);
  const double b = wrap_angle_positive(begin_rad);
  const double e = wrap_angle_positive(end_rad);
  return b <= e ? (a >= b && a <= e) : (a >= b || a <= e);
}

LidarSimulator::LidarSimulator(const lidar::SensorModel& model, const Pose3& mount, const NoiseModel& noise,
                               const Raycaster& raycaster, TimeNs schedule_t0, double start_azimuth_deg,
                               const Trajectory* carrier)
    : LidarSimulator(model, mount, noise, nullptr, &raycaster, schedule_t0, start_azimuth_deg, carrier) {}

LidarSimulator::LidarSimulator(const lidar::SensorModel& model, const Pose3& mount, const NoiseModel& noise,
                               const Scene& scene, TimeNs schedule_t0, double start_azimuth_deg)
    : LidarSimulator(model, mount, noise, std::make_shared<const Raycaster>(scene), nullptr, schedule_t0,
                     start_azimuth_deg, nullptr) {}

LidarSimulator::LidarSimulator(const lidar::SensorModel& model, const Pose3& mount, const NoiseModel& noise,
                               std::shared_ptr<const Raycaster> owned, const Raycaster* borrowed,
                               TimeNs schedule_t0, double start_azimuth_deg, const Trajectory* carrier)
    : owned_raycaster_(std::move(owned)),
      raycaster_(owned_raycaster_ ? owned_raycaster_.get() : borrowed),
      schedule_(model, schedule_t0, start_azimuth_deg),
      schedule_t0_(schedule_t0),
      mount_(mount),
      mount_to_map_(mount.to_isometry()),
      carrier_(carrier ? std::optional<Trajectory>(*carrier) : std::nullopt),
      noise_(noise) {
  validate(mount, noise);
  for (const double deg : model.elevation_deg) {
    // Same expression as the packet decoder (deg * pi / 180) so rebuilt points agree bit for bit.
    const double w = deg * std::numbers::pi / 180.0;
    elevation_rad_.push_back(w);
    cos_elevation_.push_back(std::cos(w));
    sin_elevation_.push_back(std::sin(w));
  }
  // The packet layout (which laser fires in which slot) is the same for every packet.
  const std::vector<lidar::Firing> layout = schedule_.firings(schedule_.packet(0));
  cast_order_.resize(layout.size());
  for (std::size_t i = 0; i < layout.size(); ++i) {
    cast_order_[i] = i;
  }
  std::stable_sort(cast_order_.begin(), cast_order_.end(), [&](std::size_t a, std::size_t b) {
    return elevation_rad_[layout[a].laser] < elevation_rad_[layout[b].laser];
  });
}

TimeNs LidarSimulator::rotation_period_ns() const {
  return from_seconds(1.0 / model().rotation_hz());
}

std::int64_t LidarSimulator::packet_index_at(TimeNs t) const {
  return floor_div(t - schedule_t0_, schedule_.packet_period_ns());
}

void LidarSimulator::run_packet(std::int64_t k, TimeNs t_begin, TimeNs t_end,
                                const std::optional<AzimuthSector>& sector, PacketScratch& scratch) const {
  const lidar::SensorModel& m = model();
  const lidar::PacketBlocks blocks = schedule_.packet(k);
  lidar::beam_firings(m, blocks, lidar::packet_timing(m, blocks, lidar::nominal_degrees_per_us(m)),
                      scratch.firings);
  const std::vector<lidar::Firing>& firings = scratch.firings;
  std::vector<Outcome>& outcomes = scratch.outcomes;
  outcomes.assign(firings.size(), Outcome{});
  std::vector<Ray>& rays = scratch.rays;
  std::vector<std::size_t>& ray_outcome = scratch.ray_outcome;  // which outcome each ray belongs to
  rays.clear();
  ray_outcome.clear();
  const double sigma_a = noise_.angle_sigma_rad;
  const bool noisy = sigma_a > 0.0 || noise_.range_sigma_m > 0.0;
  // Rays may reach a little past max_range and still measure inside it once range noise is added.
  const double cast_limit = m.max_range_m + 6.0 * noise_.range_sigma_m + m.distance_unit_m;
  const Eigen::Vector3d origin = mount_to_map_.translation();
  const Eigen::Matrix3d to_map = mount_to_map_.linear();

  if (firings.size() != cast_order_.size()) {
    throw std::logic_error("LidarSimulator: packet layout changed");  // cannot happen: one model
  }
  // Rays are built in elevation order (cast_order_): 16-ray packets of neighbouring beams are
  // coherent, which doubles Embree's packet throughput (bench/sim). Outcomes stay in firing order.
  for (const std::size_t i : cast_order_) {
    const lidar::Firing& f = firings[i];
    Outcome& o = outcomes[i];
    if (f.time_ns < t_begin || f.time_ns >= t_end || (sector && !sector->contains(f.azimuth_rad))) {
      continue;
    }
    o.cast = true;
    // Nominal beam angles (also what the reported point uses, see to_point).
    o.cos_azimuth = std::cos(f.azimuth_rad);
    o.sin_azimuth = std::sin(f.azimuth_rad);
    double cos_w = cos_elevation_[f.laser];
    double sin_w = sin_elevation_[f.laser];
    double cos_a = o.cos_azimuth;
    double sin_a = o.sin_azimuth;
    if (noisy) {
      o.noise = firing_noise(noise_.seed, k, f);
    }
    if (sigma_a > 0.0) {
      // Perturbed angles w + dw, a + da by the angle-addition formulas: no further trigonometry of
      // the full angles, only of the small offsets.
      const CosSin dw = small_angle_cos_sin(sigma_a * o.noise.elevation);
      const CosSin da = small_angle_cos_sin(sigma_a * o.noise.azimuth);
      const double cw = cos_w * dw.c - sin_w * dw.s;
      sin_w = sin_w * dw.c + cos_w * dw.s;
      cos_w = cw;
      const double ca = cos_a * da.c - sin_a * da.s;
      sin_a = sin_a * da.c + cos_a * da.s;
      cos_a = ca;
    }
    // Sensor frame beam (lidar/sensor_model.h): (cos w cos a, -cos w sin a, sin w).
    const Eigen::Vector3d beam(cos_w * cos_a, -cos_w * sin_a, sin_w);
    Ray ray;
    if (carrier_) {
      // The carrier's pose at this firing: the sensor moves during the sweep.
      const Pose2 v = pose_at(*carrier_, f.time_ns);
      const Eigen::Isometry3d sensor_to_map =
          Pose3{v.x, v.y, 0.0, 0.0, 0.0, v.yaw}.to_isometry() * mount_to_map_;
      ray.origin = sensor_to_map.translation();
      ray.direction = sensor_to_map.linear() * beam;
    } else {
      ray.origin = origin;
      ray.direction = to_map * beam;
    }
    ray.time_ns = f.time_ns;
    ray.max_range = cast_limit;
    rays.push_back(ray);
    ray_outcome.push_back(i);
  }

  std::vector<RayHit>& hits = scratch.hits;
  hits.resize(rays.size());
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
    measured += noise_.range_sigma_m * o.noise.range;
    o.raw = lidar::quantize_distance(m, measured);  // 0 outside [min, max] range
    // Lambertian return: 255 * reflectivity * |cos(incidence)| (sim/scene.h).
    const double cos_incidence = std::abs(hit.normal.dot(rays[r].direction));
    // Rounded half up (the value is >= 0), clamped to the byte.
    const double intensity = std::min(255.0 * hit.reflectivity * cos_incidence + 0.5, 255.0);
    o.intensity = static_cast<std::uint8_t>(intensity);
  }
}

lidar::LidarPoint LidarSimulator::to_point(const lidar::Firing& f, const Outcome& o) const {
  // The decoder's arithmetic (lidar/velodyne_packet.cpp), in the same order, so that the simulated
  // point equals the decoded one exactly.
  const double range = o.raw * model().distance_unit_m;
  const double horizontal = range * cos_elevation_[f.laser];
  lidar::LidarPoint p;
  p.x = static_cast<float>(horizontal * o.cos_azimuth);  // std::cos(azimuth), as the decoder
  p.y = static_cast<float>(-horizontal * o.sin_azimuth);
  p.z = static_cast<float>(range * sin_elevation_[f.laser]);
  p.intensity = o.intensity;
  p.ring = f.laser;
  const auto az = static_cast<float>(f.azimuth_rad);
  p.azimuth_rad = az >= static_cast<float>(2.0 * std::numbers::pi) ? 0.0F : az;
  p.time_ns = f.time_ns;
  return p;
}

lidar::PacketReturns LidarSimulator::simulate_packet(std::int64_t k,
                                                     const std::optional<AzimuthSector>& sector,
                                                     std::vector<std::uint32_t>* vehicles_hit) const {
  if (!model().has_packet_format()) {
    throw std::invalid_argument("LidarSimulator::simulate_packet: sensor model '" + model().name +
                                "' has no Velodyne packet format");
  }
  PacketScratch scratch;
  lidar::PacketReturns returns = packet_returns(k, sector, scratch);
  if (vehicles_hit != nullptr) {
    vehicles_hit->clear();
    for (const Outcome& o : scratch.outcomes) {
      if (o.raw != 0 && o.truth.surface == SurfaceClass::kVehicle)
        vehicles_hit->push_back(o.truth.vehicle_id);
    }
    std::sort(vehicles_hit->begin(), vehicles_hit->end());
    vehicles_hit->erase(std::unique(vehicles_hit->begin(), vehicles_hit->end()), vehicles_hit->end());
  }
  return returns;
}

void LidarSimulator::simulate_packets(std::int64_t first, std::span<lidar::PacketReturns> out,
                                      int threads) const {
  if (!model().has_packet_format()) {
    throw std::invalid_argument("LidarSimulator::simulate_packets: sensor model '" + model().name +
                                "' has no Velodyne packet format");
  }
  run_ranges_in_parallel(out.size(), threads, [&](std::size_t /*run*/, std::size_t begin, std::size_t end) {
    PacketScratch scratch;  // reused packet after packet
    for (std::size_t i = begin; i < end; ++i) {
      out[i] = packet_returns(first + static_cast<std::int64_t>(i), std::nullopt, scratch);
    }
  });
}

lidar::PacketReturns LidarSimulator::packet_returns(std::int64_t k,
                                                    const std::optional<AzimuthSector>& sector,
                                                    PacketScratch& scratch) const {
  lidar::PacketReturns out;
  out.blocks = schedule_.packet(k);
  run_packet(k, std::numeric_limits<TimeNs>::min(), std::numeric_limits<TimeNs>::max(), sector, scratch);
  for (std::size_t i = 0; i < scratch.firings.size(); ++i) {
    const lidar::Firing& f = scratch.firings[i];
    const Outcome& o = scratch.outcomes[i];
    const auto b = static_cast<std::size_t>(f.block);
    const auto c = static_cast<std::size_t>(f.channel);
    out.distance_raw[b][c] = o.raw;
    out.reflectivity[b][c] = o.raw != 0 ? o.intensity : 0;
  }
  return out;
}

void LidarSimulator::write_packets(std::int64_t k_begin, std::int64_t k_end, TimeNs start, TimeNs end,
                                   const std::optional<AzimuthSector>& sector, SimulatedFrame& frame,
                                   RunResult& run) const {
  PacketScratch scratch;  // reused packet after packet
  std::size_t at = run.first_point;
  for (std::int64_t k = k_begin; k < k_end; ++k) {
    run_packet(k, start, end, sector, scratch);
    for (std::size_t i = 0; i < scratch.firings.size(); ++i) {
      const lidar::Firing& f = scratch.firings[i];
      const Outcome& o = scratch.outcomes[i];
      const TimeNs t = f.time_ns;
      if (t < start || t >= end) {
        continue;
      }
      ++run.counts.firings;
      run.start_ns = std::min(run.start_ns, t);
      run.end_ns = std::max(run.end_ns, t);
      if (!o.cast) {
        ++run.counts.outside_sector;
      } else if (o.truth.surface == SurfaceClass::kNone) {
        ++run.counts.no_hit;
      } else if (o.raw == 0) {
        ++run.counts.out_of_range;
      } else {
        ++run.counts.returns;
        frame.frame.points[at] = to_point(f, o);
        frame.truth[at] = o.truth;
        ++at;
      }
    }
  }
}

SimulatedFrame LidarSimulator::simulate_frame(TimeNs start, const std::optional<AzimuthSector>& sector,
                                              int threads) const {
  const TimeNs end = start + rotation_period_ns();
  // One packet of margin each side: packet starts are rounded to whole microseconds.
  const std::int64_t k_first = packet_index_at(start) - 1;
  const auto packets = static_cast<std::size_t>(packet_index_at(end) + 2 - k_first);
  // Room for every firing of every packet, allocated once here: each run of packets writes its points
  // from its first packet's place on, and the runs are then joined in packet order in place. The threads
  // allocate nothing large: fresh memory per frame (a thread's own buffers, a vector grown by joining)
  // cost page faults that took more time than the second thread saved (bench/sim).
  const std::size_t per_packet = cast_order_.size();
  SimulatedFrame result;
  result.frame.points.resize(packets * per_packet);
  result.truth.resize(packets * per_packet);
  std::vector<RunResult> runs(range_count(packets, threads));
  run_ranges_in_parallel(packets, threads, [&](std::size_t r, std::size_t begin, std::size_t stop) {
    // Counted on this thread's stack and stored once: neighbouring runs' counts share a cache line.
    RunResult run;
    run.first_point = begin * per_packet;
    write_packets(k_first + static_cast<std::int64_t>(begin), k_first + static_cast<std::int64_t>(stop),
                  start, end, sector, result, run);
    runs[r] = run;
  });
  result.frame.start_ns = std::numeric_limits<TimeNs>::max();
  result.frame.end_ns = std::numeric_limits<TimeNs>::min();
  std::size_t n = 0;
  auto& points = result.frame.points;
  auto& truth = result.truth;
  for (const RunResult& run : runs) {
    const auto from = static_cast<std::ptrdiff_t>(run.first_point);
    const auto count = static_cast<std::ptrdiff_t>(run.counts.returns);
    const auto to = static_cast<std::ptrdiff_t>(n);
    if (from != to) {  // leftwards: a forward copy is safe
      std::copy(points.begin() + from, points.begin() + from + count, points.begin() + to);
      std::copy(truth.begin() + from, truth.begin() + from + count, truth.begin() + to);
    }
    n += run.counts.returns;
    result.counts.firings += run.counts.firings;
    result.counts.outside_sector += run.counts.outside_sector;
    result.counts.no_hit += run.counts.no_hit;
    result.counts.out_of_range += run.counts.out_of_range;
    result.counts.returns += run.counts.returns;
    result.frame.start_ns = std::min(result.frame.start_ns, run.start_ns);
    result.frame.end_ns = std::max(result.frame.end_ns, run.end_ns);
  }
  points.resize(n);
  truth.resize(n);
  if (result.counts.firings == 0) {
    result.frame.start_ns = start;
    result.frame.end_ns = start;
  }
  return result;
}

}  // namespace rsu::sim
