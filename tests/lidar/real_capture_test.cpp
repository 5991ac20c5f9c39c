// SPDX-License-Identifier: Apache-2.0
// Golden tests against real recordings (tests/data/real/SOURCES.md): our decoder on real packets,
// judged by the independent reference decoder's output (nebula, Autoware's Velodyne driver), never by
// our own simulator, which shares our sensor tables.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "io/pcd_io.h"
#include "lidar/point_eigen.h"
#include "lidar/velodyne_decoder.h"
#include "real_data.h"

namespace rsu::lidar {
namespace {

double range_m(const LidarPoint& p) {
  return position_of(p).norm();
}

// Decodes every data packet of a capture (each resolved against its record time) and keeps the points
// within (min_range, max_range), as nebula's settings for its reference decode.
std::vector<LidarPoint> decode_capture(const SensorModel& model, const std::string& capture, double min_range,
                                       double max_range) {
  VelodyneDecoder decoder(model);
  std::vector<LidarPoint> all;
  for (const UdpDatagram& d : test::read_capture(capture)) {
    if (d.dst.port == kVelodyneDataPort) {
      EXPECT_TRUE(decoder.decode(d.payload, d.time_ns, all).is_data());
    }
  }
  std::vector<LidarPoint> kept;
  for (const LidarPoint& p : all) {
    const double r = range_m(p);
    if (r > min_range && r < max_range)
      kept.push_back(p);
  }
  return kept;
}

// nebula decoded the capture's first rotation (min range 0.4 m, max 50 m); the scene is static, so a
// point of any of our rotations may match. With the calibration files' rot_correction ADDED to the
// block azimuth (the old sign), 29 % of nebula's points have one of ours within 2 cm; subtracted, 99.6 %.
TEST(RealCapture, Vlp32cMatchesNebulasDecode) {
  const std::vector<LidarPoint> reference =
      io::read_pcd(test::real_data_path("nebula_vlp32c_decoded_gt_1713492677464078412.pcd"));
  ASSERT_EQ(reference.size(), 26216U);
  const SensorModel model = make_vlp32c();
  const std::vector<LidarPoint> ours = decode_capture(model, "nebula_vlp32c_5scans.pcap", 0.4, 50.0);
  const double share = test::share_matched(reference, ours, 0.02);
  RecordProperty("share_within_2cm", std::to_string(share));
  EXPECT_GE(share, 0.99);

  SensorModel wrong_sign = model;
  for (double& offset : wrong_sign.azimuth_offset_deg)
    offset = -offset;
  const double wrong = test::share_matched(
      reference, decode_capture(wrong_sign, "nebula_vlp32c_5scans.pcap", 0.4, 50.0), 0.02);
  RecordProperty("share_within_2cm_old_sign", std::to_string(wrong));
  EXPECT_LT(wrong, 0.5);  // the test tells the two signs apart
}

// nebula decoded the dual-return capture's 4th rotation with both returns (min range 0.3 m, max 300 m);
// the scene is static. Every one of nebula's points has one of ours (both returns) within 2 cm on
// 99.4 %; with one return kept, only that return's points are there.
TEST(RealCapture, Vlp16DualReturnMatchesNebulasDecode) {
  const std::vector<LidarPoint> reference =
      io::read_pcd(test::real_data_path("nebula_vlp16_decoded_gt_1673400472138016708.pcd"));
  ASSERT_EQ(reference.size(), 14831U);
  const std::vector<LidarPoint> ours =
      decode_capture(make_vlp16(), "nebula_vlp16_dual_4scans.pcap", 0.3, 300.0);
  const double share = test::share_matched(reference, ours, 0.02);
  RecordProperty("share_within_2cm", std::to_string(share));
  EXPECT_GE(share, 0.99);
  // Both echoes are tagged: last ones, strongest ones, and where there was one echo, both.
  std::size_t last_only = 0;
  std::size_t strongest_only = 0;
  std::size_t both = 0;
  for (const LidarPoint& p : ours) {
    last_only += p.echo == kLastReturn ? 1 : 0;
    strongest_only += p.echo == kStrongestReturn ? 1 : 0;
    both += p.echo == (kLastReturn | kStrongestReturn) ? 1 : 0;
  }
  EXPECT_GT(last_only, 100U);
  EXPECT_GT(strongest_only, 100U);
  EXPECT_GT(both, ours.size() / 2);
}

// The real VLP-32C capture runs with a limited field of view (270 -> 90 deg): 4 of its packets hold
// blocks from both sides of the 179 deg gap. Nothing is interpolated across it, the blocks after it
// are stamped when the rotor reached them (the next packet's own timestamp confirms it, to 0.2 ms; they
// were stamped 50 ms early before), and the rotation rate is measured (10.0 Hz, not assumed).
TEST(RealCapture, Vlp32cLimitedFieldOfViewIsNotInterpolatedAcross) {
  VelodyneDecoder decoder(make_vlp32c());
  const std::vector<UdpDatagram> datagrams = test::read_capture("nebula_vlp32c_5scans.pcap");
  int gap_packets = 0;
  double worst_ms = 0.0;  // the largest disagreement with the successor's timestamp
  for (std::size_t k = 0; k + 1 < datagrams.size(); ++k) {
    std::vector<LidarPoint> points;
    const PacketOutcome outcome = decoder.decode(datagrams[k].payload, datagrams[k].time_ns, points);
    ASSERT_TRUE(outcome.is_data());
    const std::uint64_t gaps_before = static_cast<std::uint64_t>(gap_packets);
    if (decoder.stats().field_of_view_gaps == gaps_before)
      continue;
    ++gap_packets;
    // Where its successor starts, by the successor's own timestamp.
    VelodyneDecoder peek(make_vlp32c());
    std::vector<LidarPoint> next_points;
    const PacketOutcome next = peek.decode(datagrams[k + 1].payload, datagrams[k + 1].time_ns, next_points);
    EXPECT_NEAR(static_cast<double>(outcome.next_ns - next.first_ns), 0.0, 0.2e6) << "packet " << k;
    worst_ms = std::max(worst_ms, std::abs(static_cast<double>(outcome.next_ns - next.first_ns)) / 1e6);
    EXPECT_GT(outcome.next_ns - outcome.first_ns, 45 * kNsPerMs);  // the packet spans the gap
    // No point in the gap: every azimuth within the field of view (with the lasers' +-4.2 deg offsets
    // and the manual's interpolation lead).
    for (const LidarPoint& p : points) {
      const double deg = static_cast<double>(p.azimuth_rad) * 180.0 / std::numbers::pi;
      EXPECT_TRUE(deg > 265.0 || deg < 96.0) << deg << " deg, packet " << k;
    }
  }
  EXPECT_EQ(gap_packets, 4);
  RecordProperty("worst_successor_disagreement_ms", std::to_string(worst_ms));
  EXPECT_NEAR(decoder.geometry().rotation_hz, 10.0, 0.05);
  const std::vector<std::string> notices = decoder.take_notices();
  ASSERT_EQ(notices.size(), 1U);
  EXPECT_NE(notices[0].find("limited field of view"), std::string::npos);
}

}  // namespace
}  // namespace rsu::lidar
