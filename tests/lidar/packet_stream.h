// SPDX-License-Identifier: Apache-2.0
// Test helper: packets encoded from a FiringSchedule with random ranges, as a sensor would send them.
#pragma once

#include <array>
#include <cstdint>
#include <random>
#include <vector>

#include "lidar/firing_schedule.h"
#include "lidar/velodyne_packet.h"

namespace rsu::lidar::test {

struct EncodedPacket {
  PacketReturns returns;
  std::vector<Firing> firings;       // the schedule's firings, channel order
  std::vector<double> true_range_m;  // per firing; 0 where the packet says "no return"
  std::array<std::uint8_t, kPacketBytes> bytes{};
};

// Packet k of `schedule`: every firing gets a uniform range in [min, max] and a random reflectivity,
// except a `no_return_fraction` share that gets distance 0.
inline EncodedPacket make_packet(const FiringSchedule& schedule, std::int64_t k, std::mt19937_64& rng,
                                 double no_return_fraction) {
  const SensorModel& model = schedule.model();
  EncodedPacket p;
  p.returns.blocks = schedule.packet(k);
  p.firings = schedule.firings(p.returns.blocks);
  std::uniform_real_distribution<double> range(model.min_range_m, model.max_range_m);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::uniform_int_distribution<int> byte(0, 255);
  for (const Firing& f : p.firings) {
    const auto b = static_cast<std::size_t>(f.block);
    const auto c = static_cast<std::size_t>(f.channel);
    double r = 0.0;
    if (unit(rng) >= no_return_fraction) {
      r = range(rng);
      p.returns.distance_raw[b][c] = quantize_distance(model, r);
    }
    p.true_range_m.push_back(r);
    p.returns.reflectivity[b][c] = static_cast<std::uint8_t>(byte(rng));
  }
  encode_packet(model, p.returns, p.bytes);
  return p;
}

}  // namespace rsu::lidar::test
