// SPDX-License-Identifier: Apache-2.0
// Fuzzes the Ouster metadata parser (lib/lidar/ouster/ouster_metadata.h): any text must give metadata
// or an io::YamlError naming the line and field, never a crash or another exception; metadata it
// accepts must make a decoder that takes a packet of its own size. Seeds: the real metadata files in
// tests/data/real/ouster (fuzz/corpus/ouster_metadata).
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <vector>

#include "io/yaml_field.h"
#include "lidar/ouster/ouster_decoder.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  rsu::lidar::ouster::Metadata m;
  try {
    m = rsu::lidar::ouster::parse_metadata(text, "fuzz.json");
  } catch (const rsu::io::YamlError&) {
    return 0;  // the documented failure
  }
  if (m.columns_in_window() < 1 || m.columns_in_window() > m.columns_per_frame ||
      m.beam_altitude_deg.size() != static_cast<std::size_t>(m.pixels_per_column)) {
    std::abort();
  }
  rsu::lidar::ouster::Decoder decoder(m);
  const std::vector<std::uint8_t> zeros(
      rsu::lidar::ouster::packet_layout(m.profile, m.pixels_per_column, m.columns_per_packet).packet_bytes);
  std::vector<rsu::lidar::LidarPoint> points;
  (void)decoder.decode(zeros, points);
  if (decoder.stats().packets() != 1) {
    std::abort();
  }
  return 0;
}
