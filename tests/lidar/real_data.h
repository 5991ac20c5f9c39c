// SPDX-License-Identifier: Apache-2.0
// The real captures in tests/data/real (SOURCES.md there) as the tests use them: file bytes, the UDP
// datagrams of a pcap, and the share of a reference cloud matched by a decoded one.
#pragma once

#include <cstdint>
#include <fstream>
#include <iterator>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "lidar/pcap.h"
#include "lidar/point.h"

namespace rsu::lidar::test {

inline std::string real_data_path(const std::string& name) {
  return std::string(RSU_SOURCE_DIR) + "/tests/data/real/" + name;
}

inline std::vector<std::uint8_t> read_file_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw std::runtime_error("cannot open " + path);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// Every UDP datagram of a real capture; throws if the file is not a clean pcap.
inline std::vector<UdpDatagram> read_capture(const std::string& name) {
  const std::vector<std::uint8_t> bytes = read_file_bytes(real_data_path(name));
  PcapParseResult parsed = parse_pcap(bytes);
  if (!parsed.ok())
    throw std::runtime_error(name + ": " + std::string(to_string(parsed.error)));
  return std::move(parsed.datagrams);
}

// The share of `reference` points that have a point of `ours` within `radius` (3D), by a hash grid of
// cell `radius` searched over the 27 cells around each reference point.
double share_matched(std::span<const LidarPoint> reference, std::span<const LidarPoint> ours, double radius);

}  // namespace rsu::lidar::test
