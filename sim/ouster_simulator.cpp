// SPDX-License-Identifier: Apache-2.0
#include "sim/ouster_simulator.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numeric>
#include <stdexcept>

#include "common/byte_order.h"
#include "common/random.h"
#include "lidar/ouster/ouster_geometry.h"
#include "sim/parallel_indices.h"

namespace rsu::sim {
namespace {

namespace ouster = lidar::ouster;

// Floor division for a possibly negative numerator and a positive denominator.
std::int64_t floor_div(std::int64_t a, std::int64_t b) {
  return a / b - ((a % b != 0) && (a < 0) ? 1 : 0);
}

struct Product {
  const char* line;         // the metadata's prod_line
  double vertical_fov_deg;  // beams evenly over it, centred on the horizontal
  double azimuth_deg[2];    // the four-beam stagger: +a1, +a0, -a0, -a1
  const char* serial;
};

Product product_of(const std::string& model, int& beams) {
  const auto dash = model.find('-');
  if (dash == std::string::npos)
    throw std::invalid_argument("Ouster model \"" + model +
                                "\": expected os0-, os1- or os2- and 16, 32, 64 or 128");
  const std::string family = model.substr(0, dash);
  beams = std::atoi(model.c_str() + dash + 1);
  if (beams != 16 && beams != 32 && beams != 64 && beams != 128)
    throw std::invalid_argument("Ouster model \"" + model + "\": 16, 32, 64 or 128 beams");
  // Fields of view from the product datasheets; the stagger is the real OS1-128's (its metadata's
  // beam_azimuth_angles: 4.21, 1.41, -1.40, -4.22, ...), narrower on the OS2 and wider on the OS0.
  if (family == "os0")
    return {"OS-0-", 90.0, {2.8, 8.4}, "990000000000"};
  if (family == "os1")
    return {"OS-1-", 45.0, {1.4, 4.2}, "991000000000"};
  if (family == "os2")
    return {"OS-2-", 22.5, {0.7, 2.1}, "992000000000"};
  throw std::invalid_argument("Ouster model \"" + model + "\": expected os0-, os1- or os2-");
}

std::string numbers(const std::vector<double>& v) {
  std::string out = "[";
  char text[32];
  for (std::size_t i = 0; i < v.size(); ++i) {
    std::snprintf(text, sizeof text, "%s%.4f", i ? ", " : "", v[i]);
    out += text;
  }
  return out + "]";
}

}  // namespace

std::string ouster_metadata_json(const OusterSpec& spec) {
  int beams = 0;
  const Product p = product_of(spec.model, beams);
  const auto x = spec.lidar_mode.find('x');
  const int columns = x == std::string::npos ? 0 : std::atoi(spec.lidar_mode.c_str());
  std::vector<double> altitude, azimuth;
  for (int r = 0; r < beams; ++r) {
    altitude.push_back(p.vertical_fov_deg * (0.5 - static_cast<double>(r) / (beams - 1)));
    const double stagger[4] = {p.azimuth_deg[1], p.azimuth_deg[0], -p.azimuth_deg[0], -p.azimuth_deg[1]};
    azimuth.push_back(stagger[r % 4]);
  }
  const std::string line = std::string(p.line) + std::to_string(beams);
  char text[1024];
  std::snprintf(
      text, sizeof text,
      "{\n  \"prod_line\": \"%s\",\n  \"prod_sn\": \"%s\",\n  \"build_rev\": \"v2.3.0 (simulated)\",\n"
      "  \"initialization_id\": 5001,\n  \"lidar_mode\": \"%s\",\n"
      "  \"data_format\": {\"columns_per_frame\": %d, \"columns_per_packet\": 16, "
      "\"pixels_per_column\": %d, \"column_window\": [0, %d], \"udp_profile_lidar\": \"%s\"},\n"
      "  \"lidar_to_sensor_transform\": [-1, 0, 0, 0, 0, -1, 0, 0, 0, 0, 1, 36.18, 0, 0, 0, 1],\n"
      "  \"udp_port_lidar\": %u,\n  \"udp_port_imu\": %u,\n",
      line.c_str(), p.serial, spec.lidar_mode.c_str(), columns, beams, columns - 1,
      std::string(ouster::to_string(spec.profile)).c_str(), static_cast<unsigned>(spec.udp_port_lidar),
      static_cast<unsigned>(spec.udp_port_lidar + 1));
  std::string json = text;
  json += "  \"beam_altitude_angles\": " + numbers(altitude) + ",\n";
  json += "  \"beam_azimuth_angles\": " + numbers(azimuth) + "\n}\n";
  // Read back as rsud will: a mode or profile the sensor does not offer is refused here.
  ouster::parse_metadata(json, "simulated " + line + " metadata");
  return json;
}

OusterSimulator::OusterSimulator(const ouster::Metadata& metadata, const Pose3& mount,
                                 const NoiseModel& noise, const Raycaster& raycaster, TimeNs t0)
    : metadata_(metadata),
      layout_(
          ouster::packet_layout(metadata.profile, metadata.pixels_per_column, metadata.columns_per_packet)),
      mount_(mount.to_isometry()),
      noise_(noise),
      raycaster_(&raycaster),
      t0_(t0) {
  if (!mount_.matrix().allFinite() || !(noise.range_sigma_m >= 0.0) || !(noise.angle_sigma_rad >= 0.0) ||
      !std::isfinite(noise.range_sigma_m) || !std::isfinite(noise.angle_sigma_rad))
    throw std::invalid_argument("OusterSimulator: mount and noise must be finite, sigmas >= 0");
  frame_period_ns_ = from_seconds(1.0 / metadata.frequency_hz);
  packets_per_frame_ = metadata.columns_per_frame / metadata.columns_per_packet;
  range_unit_mm_ = metadata.profile == ouster::UdpProfile::rng15_rfl8_nir8 ? 8 : 1;
  const double field_max_mm = metadata.profile == ouster::UdpProfile::legacy            ? 0xFFFFF
                              : metadata.profile == ouster::UdpProfile::rng15_rfl8_nir8 ? 0x7FFF * 8.0
                                                                                        : 0x7FFFF;
  max_range_m_ = std::min(200.0, field_max_mm * 1e-3);
  const ouster::BeamGeometry geometry(metadata);
  beams_.reserve(static_cast<std::size_t>(metadata.columns_per_frame * metadata.pixels_per_column));
  for (int c = 0; c < metadata.columns_per_frame; ++c) {
    for (int r = 0; r < metadata.pixels_per_column; ++r) {
      Beam b;
      b.origin = geometry.point(r, c, 0.0);
      b.direction = geometry.direction(r, c);
      b.across_a = b.direction.unitOrthogonal();
      b.across_b = b.direction.cross(b.across_a);
      beams_.push_back(b);
    }
  }
}

TimeNs OusterSimulator::column_time_ns(std::int64_t frame, int column) const {
  return t0_ + frame * frame_period_ns_ + frame_period_ns_ * column / metadata_.columns_per_frame;
}

TimeNs OusterSimulator::packet_time_ns(std::int64_t k) const {
  const std::int64_t frame = floor_div(k, packets_per_frame_);
  const auto p = static_cast<int>(k - frame * packets_per_frame_);
  return column_time_ns(frame, p * metadata_.columns_per_packet);
}

std::int64_t OusterSimulator::packet_index_at(TimeNs t) const {
  const std::int64_t frame = floor_div(t - t0_, frame_period_ns_);
  std::int64_t k = frame * packets_per_frame_ + packets_per_frame_ - 1;
  while (packet_time_ns(k) > t)
    --k;
  return k;
}

std::size_t OusterSimulator::packet(std::int64_t k, TimeNs clock_offset_ns, std::vector<std::uint8_t>& out,
                                    std::vector<std::uint32_t>* vehicles_hit) const {
  return packet(k, clock_offset_ns, out, scratch_, vehicles_hit);
}

std::size_t OusterSimulator::packets(std::int64_t first, TimeNs clock_offset_ns,
                                     std::span<std::vector<std::uint8_t>> out, int threads) const {
  // Each run of packets with its own buffers; every packet is the one packet() makes, whichever thread
  // made it. A run counts on its own stack and stores once: neighbouring counts share a cache line.
  std::vector<std::size_t> vehicle_returns(range_count(out.size(), threads), 0);
  run_ranges_in_parallel(out.size(), threads, [&](std::size_t run, std::size_t begin, std::size_t end) {
    Scratch scratch;
    std::size_t sum = 0;
    for (std::size_t i = begin; i < end; ++i)
      sum += packet(first + static_cast<std::int64_t>(i), clock_offset_ns, out[i], scratch, nullptr);
    vehicle_returns[run] = sum;
  });
  return std::accumulate(vehicle_returns.begin(), vehicle_returns.end(), std::size_t{0});
}

std::size_t OusterSimulator::packet(std::int64_t k, TimeNs clock_offset_ns, std::vector<std::uint8_t>& out,
                                    Scratch& scratch, std::vector<std::uint32_t>* vehicles_hit) const {
  const ouster::Metadata& m = metadata_;
  const bool legacy = m.profile == ouster::UdpProfile::legacy;
  const std::int64_t frame = floor_div(k, packets_per_frame_);
  const int first_column = static_cast<int>(k - frame * packets_per_frame_) * m.columns_per_packet;
  const auto frame_id = static_cast<std::uint16_t>(frame & 0xFFFF);
  out.assign(layout_.packet_bytes, 0);
  const std::span<std::uint8_t> bytes(out);
  if (!legacy) {
    store_le<std::uint16_t>(bytes, 0, ouster::kLidarPacketType);
    store_le<std::uint16_t>(bytes, 2, frame_id);
    const std::uint32_t init = m.initialization_id.value_or(0);
    const std::uint64_t serial = m.serial_number.value_or(0);
    for (int i = 0; i < 3; ++i)
      bytes[4 + static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(init >> (8 * i));
    for (int i = 0; i < 5; ++i)
      bytes[7 + static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(serial >> (8 * i));
  }
  // The packet's rays in column-major order (a column's beams side by side: coherent for Embree).
  const int rows = m.pixels_per_column;
  const auto n = static_cast<std::size_t>(m.columns_per_packet * rows);
  std::vector<Ray>& rays = scratch.rays;
  std::vector<RayHit>& hits = scratch.hits;
  std::vector<double>& range_noise = scratch.range_noise;
  rays.resize(n);
  hits.assign(n, RayHit{});
  range_noise.assign(n, 0.0);
  const Eigen::Matrix3d to_map = mount_.linear();
  const bool noisy = noise_.angle_sigma_rad > 0.0 || noise_.range_sigma_m > 0.0;
  for (int c = 0; c < m.columns_per_packet; ++c) {
    const int column = first_column + c;
    const TimeNs t = column_time_ns(frame, column);
    for (int r = 0; r < rows; ++r) {
      const std::size_t i = static_cast<std::size_t>(c * rows + r);
      const Beam& beam = beams_[static_cast<std::size_t>(column * rows + r)];
      Ray& ray = rays[i];
      Eigen::Vector3d d = beam.direction;
      if (noisy) {
        // Three variates keyed by the pixel (frame, column, row), as LidarSimulator keys its firings.
        const std::uint64_t key =
            mix64(noise_.seed ^
                  mix64(static_cast<std::uint64_t>(frame) ^
                        mix64(static_cast<std::uint64_t>(column) * 65536U + static_cast<std::uint64_t>(r))));
        const double across_a = normal_quantile(uniform_open01(mix64(key)));
        const double across_b = normal_quantile(uniform_open01(mix64(key ^ 0x632be59bd9b4e019ULL)));
        range_noise[i] =
            noise_.range_sigma_m * normal_quantile(uniform_open01(mix64(key ^ 0x8cb92ba72f3d8dd7ULL)));
        d = (d + noise_.angle_sigma_rad * (across_a * beam.across_a + across_b * beam.across_b)).normalized();
      }
      ray.origin = mount_ * beam.origin;
      ray.direction = to_map * d;
      ray.time_ns = t;
      ray.max_range = max_range_m_;
    }
  }
  raycaster_->cast_batch(rays, hits);
  std::size_t vehicle_returns = 0;
  if (vehicles_hit != nullptr)
    vehicles_hit->clear();

  for (int c = 0; c < m.columns_per_packet; ++c) {
    const int column = first_column + c;
    const std::size_t at = layout_.packet_header_bytes + static_cast<std::size_t>(c) * layout_.column_bytes;
    store_le<std::uint64_t>(bytes, at,
                            static_cast<std::uint64_t>(column_time_ns(frame, column) + clock_offset_ns));
    store_le<std::uint16_t>(bytes, at + 8, static_cast<std::uint16_t>(column));
    if (legacy) {
      store_le<std::uint16_t>(bytes, at + 10, frame_id);
      // Encoder count: 90112 ticks per turn.
      store_le<std::uint32_t>(bytes, at + 12,
                              static_cast<std::uint32_t>(90112LL * column / m.columns_per_frame));
      store_le<std::uint32_t>(bytes, at + layout_.column_bytes - 4, 0xFFFFFFFFU);
    } else {
      store_le<std::uint16_t>(bytes, at + 10, 1);  // status: valid
    }
    for (int r = 0; r < rows; ++r) {
      const std::size_t i = static_cast<std::size_t>(c * rows + r);
      const RayHit& hit = hits[i];
      if (!hit.hit())
        continue;
      const double range_m = hit.range + range_noise[i];
      if (!(range_m > 0.0) || range_m > max_range_m_)
        continue;  // no return
      if (hit.surface == SurfaceClass::kVehicle) {
        ++vehicle_returns;
        if (vehicles_hit != nullptr)
          vehicles_hit->push_back(hit.vehicle_id);
      }
      const auto range = static_cast<std::uint32_t>(std::lround(range_m * 1000.0 / range_unit_mm_));
      const double cos_incidence = std::abs(hit.normal.dot(rays[i].direction));
      const auto reflectivity =
          static_cast<std::uint8_t>(std::min(255.0 * hit.reflectivity * cos_incidence + 0.5, 255.0));
      const std::size_t px =
          at + layout_.column_header_bytes + static_cast<std::size_t>(r) * layout_.pixel_bytes;
      if (m.profile == ouster::UdpProfile::rng15_rfl8_nir8) {
        store_le<std::uint16_t>(bytes, px, static_cast<std::uint16_t>(range));
        bytes[px + 2] = reflectivity;
      } else {
        store_le<std::uint32_t>(bytes, px, range);
        if (legacy)
          store_le<std::uint16_t>(bytes, px + 4, reflectivity);
        else
          bytes[px + 4] = reflectivity;
        store_le<std::uint16_t>(bytes, px + 6,
                                reflectivity);  // signal: the return's strength, as reflectivity
      }
    }
  }
  if (vehicles_hit != nullptr) {
    std::sort(vehicles_hit->begin(), vehicles_hit->end());
    vehicles_hit->erase(std::unique(vehicles_hit->begin(), vehicles_hit->end()), vehicles_hit->end());
  }
  return vehicle_returns;
}

}  // namespace rsu::sim
