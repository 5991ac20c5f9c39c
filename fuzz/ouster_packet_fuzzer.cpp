// SPDX-License-Identifier: Apache-2.0
// Fuzzes the Ouster lidar packet decoder (lib/lidar/ouster/ouster_lidar_decoder.h) in each profile: whatever
// arrives on the lidar port must be accepted, recognised as an IMU packet or refused with a counted
// reason, and every point it yields must be finite, of a real ring and a proper azimuth.
//
// Input: u8 format (mod 4, below), then records (u16 LE length + bytes), each one packet. The seeds
// (fuzz/corpus/ouster_packet) are packets of the real captures in tests/data/real/ouster.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <numbers>
#include <vector>

#include "fuzz_input.h"
#include "lidar/ouster/ouster_lidar_decoder.h"

namespace {

using rsu::lidar::ouster::Metadata;
using rsu::lidar::ouster::UdpProfile;

// 0: LEGACY, 32 beams, 1024x10 (the OS-1-32-G capture's format); 1: RNG15_RFL8_NIR8, 128 beams,
// 1024x10, the OS-1-128 capture's serial and initialization id; 2: RNG19_RFL8_SIG16_NIR16, 16 beams,
// 512x20, an azimuth window across column 0; 3: LEGACY, 16 beams, 2048x10, 8 columns per packet.
Metadata format(std::uint8_t which) {
  Metadata m;
  m.prod_line = "OS-1-32";
  const int beams[] = {32, 128, 16, 16};
  const int columns[] = {1024, 1024, 512, 2048};
  const int choice = which % 4;
  m.pixels_per_column = beams[choice];
  m.columns_per_frame = columns[choice];
  m.frequency_hz = choice == 2 ? 20 : 10;
  m.columns_per_packet = choice == 3 ? 8 : 16;
  m.profile = choice == 1   ? UdpProfile::rng15_rfl8_nir8
              : choice == 2 ? UdpProfile::rng19_rfl8_sig16_nir16
                            : UdpProfile::legacy;
  m.column_window_first = choice == 2 ? 400 : 0;
  m.column_window_last = choice == 2 ? 100 : m.columns_per_frame - 1;
  if (choice == 1) {
    m.serial_number = 122201000998ULL;
    m.initialization_id = 7109750U;
  }
  for (int r = 0; r < m.pixels_per_column; ++r) {
    m.beam_altitude_deg.push_back(20.0 - 40.0 * r / m.pixels_per_column);
    m.beam_azimuth_deg.push_back((r % 4 - 1.5) * 2.8);
  }
  m.beam_origin_x_mm = 15.806;
  m.lidar_to_sensor(0, 0) = -1.0;
  m.lidar_to_sensor(1, 1) = -1.0;
  m.lidar_to_sensor(2, 3) = 36.18;
  return m;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  rsu::fuzz::FuzzInput in(data, size);
  const Metadata m = format(in.u8());
  rsu::lidar::ouster::OusterLidarDecoder decoder(m, "fuzz.json");  // through the decoder seam
  std::vector<rsu::lidar::LidarPoint> points;
  std::uint64_t fed = 0;
  while (!in.empty()) {
    const std::size_t before = points.size();
    const rsu::lidar::PacketOutcome outcome = decoder.decode(in.record(), 0, points);
    if (!outcome.is_data() && points.size() != before) {
      std::abort();  // points only from data packets
    }
    ++fed;
    for (std::size_t i = before; i < points.size(); ++i) {
      const rsu::lidar::LidarPoint& p = points[i];
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z) ||
          p.ring >= m.pixels_per_column ||
          !(p.azimuth_rad >= 0.0F && p.azimuth_rad < static_cast<float>(2 * std::numbers::pi)) ||
          p.time_ns < 0) {
        std::abort();
      }
    }
  }
  if (decoder.packets_seen() != fed || decoder.decoder().stats().packets() != fed ||
      decoder.decoder().stats().points != points.size()) {
    std::abort();  // every packet counted once; every point counted
  }
  return 0;
}
