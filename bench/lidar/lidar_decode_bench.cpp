// SPDX-License-Identifier: Apache-2.0
// Decoding real Ouster captures (tests/data/real/ouster) into points, per profile, against a baseline
// in the same run: reading every pixel's range out of the same packets with no geometry (the least a
// decoder can do). Reports points (or pixels) per second.
//   build/bench/lidar/lidar_decode_bench
#include <benchmark/benchmark.h>

#include <string>
#include <vector>

#include "io/yaml_field.h"
#include "lidar/ouster/ouster_decoder.h"
#include "lidar/pcap.h"

namespace {

using rsu::lidar::ouster::Metadata;

struct Capture {
  Metadata metadata;
  std::vector<std::vector<std::uint8_t>> lidar_packets;
};

Capture load(const std::string& pcap, const std::string& json) {
  const std::string dir = std::string(RSU_SOURCE_DIR) + "/tests/data/real/ouster/";
  Capture c{rsu::lidar::ouster::parse_metadata(rsu::io::read_text_file(dir + json), json), {}};
  const std::string bytes = rsu::io::read_text_file(dir + pcap);
  for (rsu::lidar::UdpDatagram& d :
       rsu::lidar::parse_pcap(std::span(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()))
           .datagrams) {
    if (d.dst.port == c.metadata.udp_port_lidar) {
      c.lidar_packets.push_back(std::move(d.payload));
    }
  }
  return c;
}

const Capture& capture(int which) {
  static const Capture legacy = load("OS-1-32-G_v2.1.1_1024x10.pcap", "OS-1-32-G_v2.1.1_1024x10.json");
  static const Capture rng15 = load("OS-1-128_v2.3.0_1024x10_lb_n3.pcap", "OS-1-128_v2.3.0_1024x10.json");
  static const Capture rng19 = load("OS-2-128-U1_v2.3.0_1024x10.pcap", "OS-2-128-U1_v2.3.0_1024x10.json");
  return which == 0 ? legacy : which == 1 ? rng15 : rng19;
}

void label(benchmark::State& state, const Capture& c) {
  state.SetLabel(c.metadata.model_name() + " " +
                 std::string(rsu::lidar::ouster::to_string(c.metadata.profile)));
}

// A fresh decoder per pass over the capture (its frames repeat), points into a reused buffer.
void BM_OusterDecode(benchmark::State& state) {
  const Capture& c = capture(static_cast<int>(state.range(0)));
  std::vector<rsu::lidar::LidarPoint> points;
  std::size_t decoded = 0;
  for (auto _ : state) {
    rsu::lidar::ouster::Decoder decoder(c.metadata);
    for (const auto& packet : c.lidar_packets) {
      points.clear();
      decoder.decode(packet, points);
      decoded += points.size();
    }
    benchmark::DoNotOptimize(points.data());
  }
  state.counters["points/s"] = benchmark::Counter(static_cast<double>(decoded), benchmark::Counter::kIsRate);
  label(state, c);
}
BENCHMARK(BM_OusterDecode)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMicrosecond);

// Baseline: every pixel's range read into a range image, nothing else.
void BM_OusterRangesOnlyBaseline(benchmark::State& state) {
  const Capture& c = capture(static_cast<int>(state.range(0)));
  const Metadata& m = c.metadata;
  const rsu::lidar::ouster::PacketReader reader(m.profile, m.pixels_per_column, m.columns_per_packet);
  std::vector<std::uint32_t> image(static_cast<std::size_t>(m.pixels_per_column * m.columns_per_frame));
  std::size_t pixels = 0;
  for (auto _ : state) {
    for (const auto& packet : c.lidar_packets) {
      for (int col = 0; col < m.columns_per_packet; ++col) {
        const int id = reader.column(packet, col).measurement_id % m.columns_per_frame;
        for (int row = 0; row < m.pixels_per_column; ++row) {
          image[static_cast<std::size_t>(row * m.columns_per_frame + id)] =
              reader.pixel(packet, col, row).range_mm;
        }
      }
      pixels += static_cast<std::size_t>(m.columns_per_packet * m.pixels_per_column);
    }
    benchmark::DoNotOptimize(image.data());
  }
  state.counters["pixels/s"] = benchmark::Counter(static_cast<double>(pixels), benchmark::Counter::kIsRate);
  label(state, c);
}
BENCHMARK(BM_OusterRangesOnlyBaseline)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMicrosecond);

}  // namespace
