// SPDX-License-Identifier: Apache-2.0
// Real Ouster captures (tests/data/real/ouster, SOURCES.md) through the decoder:
//  - every packet accounted for, every frame whole;
//  - point counts per frame equal to what the capture must give, counted here from the raw bytes by
//    the manual's layout (tests/lidar/ouster_test_packets.h): valid columns x pixels with a range of at
//    least the minimum;
//  - the range image equal to the Ouster SDK's own decode of the same capture (the MD5 digests the SDK
//    ships with its test captures);
//  - geometry: rings ordered by altitude, column times rising at 1 / (frequency x columns), no point
//    inside the sensor body, every point's azimuth following its measurement id;
//  - a golden summary (gpsd-style: recorded input in, text out, diffed against
//    tests/data/golden/ouster/<capture>.txt). After an intended change, regenerate with
//      RSU_UPDATE_GOLDEN=1 build/tests/lidar/ouster_tests --gtest_filter='OusterCapture*'
//    and review the diff.
#include <gtest/gtest.h>
#include <openssl/evp.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>

#include "common/angles.h"
#include "common/byte_order.h"
#include "io/yaml_field.h"
#include "lidar/ouster/ouster_decoder.h"
#include "lidar/pcap.h"
#include "lidar/point_eigen.h"
#include "tests/lidar/ouster_test_packets.h"
#include "tests/lidar/real_data.h"

namespace rsu::lidar::ouster {
namespace {

struct Capture {
  const char* pcap;
  const char* metadata;
  const char* digest;  // the SDK's digest of the same capture, or nullptr
  int frames;          // whole frames in it
  std::size_t imu_packets;
};

const Capture kCaptures[] = {
    {"OS-1-32-G_v2.1.1_1024x10.pcap", "OS-1-32-G_v2.1.1_1024x10.json", "OS-1-32-G_v2.1.1_1024x10_digest.json",
     1, 0},
    {"OS-1-128_v2.3.0_1024x10_lb_n3.pcap", "OS-1-128_v2.3.0_1024x10.json", nullptr, 3, 30},
    {"OS-2-32-U0_v2.0.0_1024x10.pcap", "OS-2-32-U0_v2.0.0_1024x10.json",
     "OS-2-32-U0_v2.0.0_1024x10_digest.json", 1, 0},
    {"OS-0-128-U1_v2.3.0_1024x10.pcap", "OS-0-128-U1_v2.3.0_1024x10.json",
     "OS-0-128-U1_v2.3.0_1024x10_digest.json", 1, 10},
    {"OS-2-128-U1_v2.3.0_1024x10.pcap", "OS-2-128-U1_v2.3.0_1024x10.json",
     "OS-2-128-U1_v2.3.0_1024x10_digest.json", 1, 10},
};

std::string ouster_data_path(const std::string& name) {
  return ::rsu::lidar::test::real_data_path("ouster/" + name);
}

std::vector<UdpDatagram> datagrams_of(const Capture& c) {
  return ::rsu::lidar::test::read_capture(std::string("ouster/") + c.pcap);
}

Metadata metadata_of(const Capture& c) {
  return parse_metadata(io::read_text_file(ouster_data_path(c.metadata)), c.metadata);
}

// One decoded frame and, from the raw bytes, what it must hold.
struct Frame {
  std::uint16_t frame_id = 0;
  std::vector<LidarPoint> points;
  std::map<int, std::uint64_t> column_time;                 // measurement id -> timestamp (valid columns)
  std::map<std::uint64_t, int> time_column;                 // and back
  std::map<int, std::vector<std::uint32_t>> column_ranges;  // measurement id -> range per row, mm
  std::size_t expected_points = 0;
  std::size_t no_return = 0;
};

struct Decoded {
  Metadata metadata;
  DecoderStats stats;
  std::vector<Frame> frames;
  std::size_t lidar_packets = 0;
  std::size_t imu_packets = 0;
};

// Every datagram of the capture (IMU ones too) through one decoder, cut into frames where the
// decoder says a frame begins.
Decoded decode_capture(const Capture& c) {
  Decoded out{metadata_of(c), {}, {}, 0, 0};
  const Metadata& m = out.metadata;
  const auto min_range_mm = static_cast<std::uint32_t>(std::lround(DecoderConfig{}.min_range_m * 1000));
  Decoder decoder(m);
  std::vector<LidarPoint> points;
  for (const UdpDatagram& d : datagrams_of(c)) {
    (d.dst.port == m.udp_port_imu ? out.imu_packets : out.lidar_packets) += 1;
    points.clear();
    const PacketResult r = decoder.decode(d.payload, points);
    if (r != PacketResult::accepted) {
      continue;
    }
    if (decoder.last_packet().begins_frame) {
      out.frames.emplace_back();
      out.frames.back().frame_id = decoder.last_packet().frame_id;
    }
    Frame& f = out.frames.back();
    f.points.insert(f.points.end(), points.begin(), points.end());
    for (const test::RawColumn& col : test::raw_columns(m, d.payload)) {
      if (!col.valid) {
        continue;
      }
      f.column_time[col.measurement_id] = col.timestamp_ns;
      f.time_column[col.timestamp_ns] = col.measurement_id;
      f.column_ranges[col.measurement_id] = col.range_mm;
      for (const std::uint32_t range : col.range_mm) {
        f.expected_points += range >= min_range_mm ? 1 : 0;
        f.no_return += range == 0 ? 1 : 0;
      }
    }
  }
  out.stats = decoder.stats();
  return out;
}

TEST(OusterCapture, EveryPacketAccountedForAndEveryFrameWhole) {
  for (const Capture& c : kCaptures) {
    SCOPED_TRACE(c.pcap);
    const Decoded d = decode_capture(c);
    EXPECT_EQ(d.imu_packets, c.imu_packets);
    EXPECT_EQ(d.stats.accepted, d.lidar_packets);   // nothing refused
    EXPECT_EQ(d.stats.imu_packets, d.imu_packets);  // recognised, not counted as broken
    EXPECT_EQ(d.stats.rejected(), 0U);
    EXPECT_EQ(d.stats.packets(), d.lidar_packets + d.imu_packets);
    EXPECT_EQ(d.lidar_packets * static_cast<std::size_t>(d.metadata.columns_per_packet),
              static_cast<std::size_t>(c.frames * d.metadata.columns_per_frame));
    EXPECT_EQ(d.stats.frames, static_cast<std::uint64_t>(c.frames));
    EXPECT_EQ(d.stats.frames_complete, static_cast<std::uint64_t>(c.frames));
    EXPECT_EQ(d.stats.columns_skipped, 0U);
    EXPECT_EQ(d.stats.columns_invalid, 0U);
    ASSERT_EQ(d.frames.size(), static_cast<std::size_t>(c.frames));
    for (std::size_t i = 0; i < d.frames.size(); ++i) {
      const Frame& f = d.frames[i];
      EXPECT_EQ(f.column_time.size(), static_cast<std::size_t>(d.metadata.columns_per_frame));
      EXPECT_EQ(f.points.size(), f.expected_points) << "frame " << f.frame_id;
      EXPECT_GT(f.points.size(),
                static_cast<std::size_t>(d.metadata.columns_per_frame * d.metadata.pixels_per_column / 2));
      if (i > 0) {
        EXPECT_EQ(f.frame_id, static_cast<std::uint16_t>(d.frames[i - 1].frame_id + 1));
      }
    }
  }
}

std::string md5_hex(std::span<const std::uint8_t> bytes) {
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int n = 0;
  EXPECT_EQ(EVP_Digest(bytes.data(), bytes.size(), digest, &n, EVP_md5(), nullptr), 1);
  std::string hex;
  for (unsigned int i = 0; i < n; ++i) {
    constexpr char kHex[] = "0123456789abcdef";
    hex += kHex[digest[i] >> 4];
    hex += kHex[digest[i] & 15];
  }
  return hex;
}

// The SDK digests each frame's range image: rows x columns_per_frame uint32 (mm), row-major, columns
// in measurement-id order, 0 where no valid column came. Ours from PacketReader must hash the same.
TEST(OusterCapture, RangeImageEqualsTheSdkDecode) {
  int compared = 0;
  for (const Capture& c : kCaptures) {
    if (c.digest == nullptr) {
      continue;
    }
    SCOPED_TRACE(c.pcap);
    const Metadata m = metadata_of(c);
    const PacketReader reader(m.profile, m.pixels_per_column, m.columns_per_packet);
    const auto w = static_cast<std::size_t>(m.columns_per_frame);
    std::vector<std::uint8_t> image(static_cast<std::size_t>(m.pixels_per_column) * w * 4, 0);
    for (const UdpDatagram& d : datagrams_of(c)) {
      if (d.payload.size() != reader.layout().packet_bytes) {
        continue;  // IMU
      }
      for (int col = 0; col < m.columns_per_packet; ++col) {
        const ColumnHeader h = reader.column(d.payload, col);
        ASSERT_TRUE(h.valid());
        for (int row = 0; row < m.pixels_per_column; ++row) {
          store_le<std::uint32_t>(image, (static_cast<std::size_t>(row) * w + h.measurement_id) * 4,
                                  reader.pixel(d.payload, col, row).range_mm);
        }
      }
    }
    const YAML::Node digest = io::parse_yaml(io::read_text_file(ouster_data_path(c.digest)), c.digest);
    const YAML::Node frames = digest["scans"] ? digest["scans"] : digest["frames"];
    ASSERT_EQ(frames.size(), 1U);
    EXPECT_EQ(md5_hex(image), frames[0]["RANGE"].as<std::string>());
    ++compared;
  }
  EXPECT_EQ(compared, 4);
}

double wrapped(double a) {
  return std::remainder(a, 2.0 * kPi);
}

void check_frame_geometry(const Metadata& m, const Frame& f) {
  const BeamGeometry g(m);
  const Eigen::Vector3d origin = g.lidar_origin_m();
  const double beam = std::hypot(m.beam_origin_x_mm, m.beam_origin_z_mm) * 1e-3;
  const double min_range = DecoderConfig{}.min_range_m;
  std::map<int, std::pair<double, int>> elevation_by_ring;  // sum, count
  double nearest = 1e9;
  for (const LidarPoint& p : f.points) {
    const int column = f.time_column.at(static_cast<std::uint64_t>(p.time_ns));  // time is a column's
    const double range = f.column_ranges.at(column).at(p.ring) * 1e-3;
    const Eigen::Vector3d v = position_of(p) - origin;
    const double dist = v.norm();
    nearest = std::min(nearest, dist);
    // The range is measured from |beam| behind the beam origin, itself |beam| from the lidar origin.
    ASSERT_GE(dist, range - 2 * beam - 1e-4);
    ASSERT_LE(dist, range + 1e-4);
    const double slack = std::asin(std::min(1.0, 2 * beam / dist)) + 1e-4;
    const double altitude = m.beam_altitude_deg.at(p.ring) * kPi / 180;
    ASSERT_NEAR(std::asin(v.z() / dist), altitude, slack) << "ring " << p.ring;
    // Azimuth (clockwise from +x) follows the measurement id: 2 pi m / W + pi + the beam's offset.
    const double azimuth =
        2 * kPi * column / m.columns_per_frame + kPi + m.beam_azimuth_deg[p.ring] * kPi / 180;
    ASSERT_NEAR(wrapped(static_cast<double>(p.azimuth_rad) - azimuth), 0.0, 1e-5);
    const double seen = std::atan2(-v.y(), v.x());
    ASSERT_NEAR(wrapped(seen - azimuth), 0.0,
                std::asin(std::min(1.0, 2 * beam / (dist * std::cos(altitude)))) + 1e-4);
    auto& [sum, n] = elevation_by_ring[p.ring];
    sum += std::asin(v.z() / dist);
    ++n;
  }
  // No point inside the sensor body (a few cm): the nearest is beyond the minimum range, less the offsets.
  EXPECT_GE(nearest, min_range - 2 * beam);
  // Rings are pixel rows, top beam first: altitudes fall with the ring, in the table and in the points.
  for (std::size_t r = 1; r < m.beam_altitude_deg.size(); ++r) {
    EXPECT_LT(m.beam_altitude_deg[r], m.beam_altitude_deg[r - 1]);
  }
  double previous = 10.0;
  for (const auto& [ring, stats] : elevation_by_ring) {
    const double mean = stats.first / stats.second;
    EXPECT_LT(mean, previous) << "ring " << ring;
    previous = mean;
  }
  EXPECT_EQ(elevation_by_ring.size(), static_cast<std::size_t>(m.pixels_per_column));
}

// Column times rise with the measurement id at 1 / (frequency x columns): 0.1 % on average over the
// frame, each step within 20 % (measured on these captures: 0.063 % and 12-14 %).
void check_frame_timing(const Metadata& m, const Frame& f) {
  const double nominal = 1e9 / (m.frequency_hz * static_cast<double>(m.columns_per_frame));
  ASSERT_FALSE(f.column_time.empty());
  auto previous = f.column_time.begin();
  for (auto it = std::next(previous); it != f.column_time.end(); previous = it++) {
    ASSERT_EQ(it->first, previous->first + 1);
    const double step = static_cast<double>(it->second) - static_cast<double>(previous->second);
    ASSERT_GT(step, 0.8 * nominal) << "column " << it->first;
    ASSERT_LT(step, 1.2 * nominal) << "column " << it->first;
  }
  const auto& first = *f.column_time.begin();
  const auto& last = *f.column_time.rbegin();
  const double mean = static_cast<double>(last.second - first.second) / (last.first - first.first);
  EXPECT_NEAR(mean / nominal, 1.0, 1e-3);
}

TEST(OusterCapture, GeometryAndTiming) {
  for (const Capture& c : kCaptures) {
    SCOPED_TRACE(c.pcap);
    const Decoded d = decode_capture(c);
    for (const Frame& f : d.frames) {
      SCOPED_TRACE("frame " + std::to_string(f.frame_id));
      check_frame_geometry(d.metadata, f);
      check_frame_timing(d.metadata, f);
    }
  }
}

// Each point's distance, binned by azimuth (one bin per column), per ring; `flip` applies the beams'
// azimuth offsets with the opposite sign.
std::map<int, std::vector<double>> ring_profiles(const Metadata& m, const Frame& f, bool flip) {
  std::map<int, std::vector<double>> out;
  const int w = m.columns_per_frame;
  for (const LidarPoint& p : f.points) {
    double azimuth = static_cast<double>(p.azimuth_rad);
    if (flip) {
      azimuth -= 2 * m.beam_azimuth_deg[p.ring] * kPi / 180;
    }
    const int bin = static_cast<int>(std::lround(azimuth / (2 * kPi) * w)) % w;
    auto& profile = out[p.ring];
    profile.resize(static_cast<std::size_t>(w), 0.0);
    profile[static_cast<std::size_t>((bin + w) % w)] = position_of(p).norm();
  }
  return out;
}

double median_difference(const std::vector<double>& a, const std::vector<double>& b) {
  std::vector<double> d;
  for (std::size_t i = 0; i < a.size() && i < b.size(); ++i) {
    if (a[i] > 0 && b[i] > 0) {
      d.push_back(std::abs(a[i] - b[i]));
    }
  }
  if (d.empty()) {
    return 0.0;
  }
  std::nth_element(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2), d.end());
  return d[d.size() / 2];
}

// The sign of the beams' azimuth offsets, from the scene itself: neighbouring rows whose offsets
// differ (by 2.8 deg or more) see the same surfaces where their points' azimuths say, and not where
// the opposite sign would put them. (The Velodyne decoder's sign error, issue 11, was of this kind.)
TEST(OusterCapture, NeighbouringRingsSeeTheSameSurfacesAtTheirAzimuths) {
  int pairs = 0;
  int agree = 0;
  std::vector<double> ratios;
  for (const Capture& c : kCaptures) {
    const Decoded d = decode_capture(c);
    const Metadata& m = d.metadata;
    for (const Frame& f : d.frames) {
      const auto right = ring_profiles(m, f, false);
      const auto flipped = ring_profiles(m, f, true);
      for (int r = 0; r + 1 < m.pixels_per_column; ++r) {
        if (std::abs(m.beam_azimuth_deg[r] - m.beam_azimuth_deg[r + 1]) < 2.0 || !right.contains(r) ||
            !right.contains(r + 1)) {
          continue;
        }
        const double ours = median_difference(right.at(r), right.at(r + 1));
        const double opposite = median_difference(flipped.at(r), flipped.at(r + 1));
        ++pairs;
        agree += ours < opposite ? 1 : 0;
        ratios.push_back(ours / std::max(opposite, 1e-6));
      }
    }
  }
  ASSERT_GT(pairs, 300);
  EXPECT_GE(agree, pairs * 9 / 10);
  std::nth_element(ratios.begin(), ratios.begin() + static_cast<std::ptrdiff_t>(ratios.size() / 2),
                   ratios.end());
  EXPECT_LT(ratios[ratios.size() / 2], 0.2);
  std::cout << "neighbouring rows: " << agree << " of " << pairs << " agree better at their azimuths; median "
            << "difference ratio ours / opposite sign " << ratios[ratios.size() / 2] << "\n";
}

std::string fixed(double v, int decimals) {
  std::ostringstream out;
  out.setf(std::ios::fixed);
  out.precision(decimals);
  out << (std::abs(v) < 0.5 * std::pow(10.0, -decimals) ? 0.0 : v);  // no "-0.000"
  return out.str();
}

// The golden text: what was decoded, per frame and per ring, and a sample of points (mm).
std::string summary(const Capture& c, const Decoded& d) {
  const Metadata& m = d.metadata;
  std::ostringstream out;
  out << "capture " << c.pcap << "\nsensor " << m.prod_line << " (" << m.model_name() << "), " << m.lidar_mode
      << ", " << to_string(m.profile) << ", " << m.pixels_per_column << " beams\n";
  const DecoderStats& s = d.stats;
  out << "packets " << s.packets() << ": accepted " << s.accepted << ", imu " << s.imu_packets << ", refused "
      << s.rejected() << "\nframes " << s.frames << ", complete " << s.frames_complete << ", columns decoded "
      << s.columns_decoded << ", skipped " << s.columns_skipped << ", points " << s.points << ", no return "
      << s.no_return << ", too close " << s.too_close << "\n";
  for (const Frame& f : d.frames) {
    out << "frame " << f.frame_id << ": columns " << f.column_time.size() << ", points " << f.points.size()
        << ", time " << f.column_time.begin()->second << " .. " << f.column_time.rbegin()->second << " ns\n";
    std::map<int, std::pair<int, double>> rings;  // points, sum of distance
    for (const LidarPoint& p : f.points) {
      auto& [n, sum] = rings[p.ring];
      ++n;
      sum += position_of(p).norm();
    }
    for (const auto& [ring, r] : rings) {
      out << "  ring " << ring << ": " << r.first << " points, mean distance " << fixed(r.second / r.first, 3)
          << " m\n";
    }
    const std::size_t step = f.points.size() / 25 + 1;
    for (std::size_t i = 0; i < f.points.size(); i += step) {
      const LidarPoint& p = f.points[i];
      const Eigen::Vector3d mm = position_of(p) * 1e3;
      out << "  point " << i << ": ring " << p.ring << " t " << p.time_ns << " azimuth "
          << fixed(static_cast<double>(p.azimuth_rad) * 180 / kPi, 2) << " deg, xyz " << fixed(mm.x(), 0)
          << " " << fixed(mm.y(), 0) << " " << fixed(mm.z(), 0) << " mm, intensity " << p.intensity << "\n";
    }
  }
  return out.str();
}

TEST(OusterCapture, GoldenSummaries) {
  const bool update = std::getenv("RSU_UPDATE_GOLDEN") != nullptr;
  for (const Capture& c : kCaptures) {
    SCOPED_TRACE(c.pcap);
    const std::string text = summary(c, decode_capture(c));
    std::string name = c.pcap;
    name = name.substr(0, name.rfind('.')) + ".txt";
    const std::string path = std::string(RSU_SOURCE_DIR) + "/tests/data/golden/ouster/" + name;
    if (update) {
      std::ofstream(path) << text;
      continue;
    }
    std::ifstream in(path);
    ASSERT_TRUE(in) << path << " missing: regenerate with RSU_UPDATE_GOLDEN=1 (see the file comment)";
    std::ostringstream golden;
    golden << in.rdbuf();
    EXPECT_EQ(text, golden.str()) << "decoding " << c.pcap << " changed; if intended, regenerate " << path;
  }
}

}  // namespace
}  // namespace rsu::lidar::ouster
