// SPDX-License-Identifier: Apache-2.0
// An Ouster OS0/OS1/OS2 simulated column by column (issue 16: a dense sensor's stream through the real
// rsud): its lidar packets in the metadata's profile, and the metadata JSON the sensor would report,
// which rsud reads (lidar.metadata) to decode them.
//
// Each pixel is one ray along the beam the metadata's geometry gives it (lidar/ouster/ouster_geometry.h,
// the same the decoder uses), cast at its column's time, so a moving vehicle is smeared as in a real
// sweep. The ray starts where the decoder measures ranges from (the beam origin less the beam offset),
// so that the decoded point lies on the surface hit. Noise as LidarSimulator's (the paper's model): the
// ray's direction is perturbed by angle_sigma_rad across it and the range by range_sigma_m, drawn per
// pixel from common/random.h keyed by (seed, frame, column, row); the packet reports the range along the
// nominal beam. Reflectivity is the Lambertian return 255 x reflectivity x |cos(incidence)|.
//
// Column m of frame f fires at t0 + f / frequency + m / (frequency x columns_per_frame); its timestamp is
// that time plus the caller's clock offset (a sensor synchronised by PTP reports the common clock).
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "common/pose.h"
#include "common/time.h"
#include "lidar/ouster/ouster_metadata.h"
#include "lidar/ouster/ouster_packet.h"
#include "sim/raycaster.h"
#include "sim/scene.h"

namespace rsu::sim {

// What to simulate: "os1-128" (os0, os1 or os2; 16, 32, 64 or 128 beams), a lidar_mode the sensor
// offers ("1024x20", "2048x10", ...) and a packet profile.
struct OusterSpec {
  std::string model = "os1-128";
  std::string lidar_mode = "1024x10";
  lidar::ouster::UdpProfile profile = lidar::ouster::UdpProfile::rng19_rfl8_sig16_nir16;
  std::uint16_t udp_port_lidar = lidar::ouster::kDefaultLidarPort;
};

// The flat-layout metadata JSON of a simulated sensor of `spec`: beams evenly over the product's
// vertical field of view (OS0 90 deg, OS1 45 deg, OS2 22.5 deg, top beam first) with the staggered
// azimuth offsets of the real sensors' four-beam pattern (+-1.4, +-4.2 deg on the OS1), its product
// line's beam offset and lidar_to_sensor transform, 16 columns per packet, every column, the profile.
// Throws std::invalid_argument for a model or mode outside those.
std::string ouster_metadata_json(const OusterSpec& spec);

class OusterSimulator {
 public:
  // `raycaster` must outlive the simulator; `mount` is the pose of the Ouster's sensor frame (the base,
  // ouster_geometry.h) in the map. Throws std::invalid_argument for non-finite noise or mount.
  OusterSimulator(const lidar::ouster::Metadata& metadata, const Pose3& mount, const NoiseModel& noise,
                  const Raycaster& raycaster, TimeNs t0 = 0);

  int packets_per_frame() const { return packets_per_frame_; }
  TimeNs frame_period_ns() const { return frame_period_ns_; }
  // The time of packet k's first column (k counts packets from frame 0's first).
  TimeNs packet_time_ns(std::int64_t k) const;
  // The packet whose first column is the last one at or before t.
  std::int64_t packet_index_at(TimeNs t) const;
  // Packet k's bytes (the metadata's profile), its column timestamps on the sensor clock
  // (simulation time + clock_offset_ns), into `out` (resized). Returns how many of its returns are a
  // vehicle's (the ray caster's truth: which packets hold a vehicle, for latency benchmarks);
  // vehicles_hit, when given, receives those vehicles' ids (ascending, each once).
  // Not thread-safe: it reuses the simulator's buffers (one simulator per thread).
  std::size_t packet(std::int64_t k, TimeNs clock_offset_ns, std::vector<std::uint8_t>& out,
                     std::vector<std::uint32_t>* vehicles_hit = nullptr) const;
  // Packets first, first + 1, ... into out[0], out[1], ..., each as packet() makes it, on `threads`
  // threads (the caller's among them; started per call: for a frame's packets, not one's). Returns
  // their vehicle returns summed. Throws std::invalid_argument for threads < 1.
  std::size_t packets(std::int64_t first, TimeNs clock_offset_ns, std::span<std::vector<std::uint8_t>> out,
                      int threads) const;

  const lidar::ouster::Metadata& metadata() const { return metadata_; }

 private:
  TimeNs column_time_ns(std::int64_t frame, int column) const;

  // Per pixel (column-major: column * rows + row), sensor frame: where its ray starts (the point of range
  // 0) and its nominal direction. Computed once: a 2048 x 128 sensor casts 2.6 M rays a second.
  struct Beam {
    Eigen::Vector3d origin;
    Eigen::Vector3d direction;
    Eigen::Vector3d across_a;  // two unit vectors across the beam, for the angle noise
    Eigen::Vector3d across_b;
  };
  struct Scratch {
    std::vector<Ray> rays;
    std::vector<RayHit> hits;
    std::vector<double> range_noise;  // m, per ray
  };

  std::size_t packet(std::int64_t k, TimeNs clock_offset_ns, std::vector<std::uint8_t>& out, Scratch& scratch,
                     std::vector<std::uint32_t>* vehicles_hit) const;

  lidar::ouster::Metadata metadata_;
  std::vector<Beam> beams_;
  mutable Scratch scratch_;  // packet()'s, reused packet after packet (one simulator per thread)
  lidar::ouster::PacketLayout layout_;
  Eigen::Isometry3d mount_;
  NoiseModel noise_;
  const Raycaster* raycaster_;
  TimeNs t0_;
  TimeNs frame_period_ns_ = 0;
  int packets_per_frame_ = 0;
  double max_range_m_ = 0.0;  // what the profile's range field can hold
  std::uint32_t range_unit_mm_ = 1;
};

}  // namespace rsu::sim
