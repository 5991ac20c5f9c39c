// SPDX-License-Identifier: Apache-2.0
// The decoder seam (lidar/lidar_decoder.h): the factory picks the configured sensor's decoder, every
// payload is counted once, and the geometry downstream needs is there before any packet arrives.
#include "lidar/lidar_decoder.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>

#include "packet_stream.h"
#include "published_tables.h"

namespace rsu::lidar {
namespace {

TEST(LidarDecoderSeam, FactoryKnowsTheVelodyneModels) {
  for (const char* name : {"vlp16", "vlp32c", "hdl32e"}) {
    EXPECT_TRUE(is_decodable_model(name)) << name;
    const auto decoder = make_lidar_decoder(name, {});
    EXPECT_EQ(decoder->model_name(), name);
    EXPECT_EQ(decoder->default_ports().data, 2368);
    EXPECT_EQ(decoder->default_ports().auxiliary, 8308);
    EXPECT_EQ(decoder->packets_seen(), 0U);
  }
  for (const char* name : {"generic64", "vlp64", "", "VLP16"}) {
    EXPECT_FALSE(is_decodable_model(name)) << name;
    EXPECT_THROW((void)make_lidar_decoder(name, {}), std::invalid_argument) << name;
  }
}

TEST(LidarDecoderSeam, GeometryBeforeAnyPacketIsTheNominalSweep) {
  LidarDecoderOptions options;
  options.rotation_start_azimuth_deg = 180.0;
  const auto vlp32c = make_lidar_decoder("vlp32c", options);
  const SweepGeometry& g = vlp32c->geometry();
  EXPECT_DOUBLE_EQ(g.rotation_hz, 10.0);
  ASSERT_EQ(g.ring_azimuth_offset_rad.size(), 32U);
  for (std::size_t i = 0; i < 32; ++i) {
    EXPECT_NEAR(g.ring_azimuth_offset_rad[i], -test::kVlp32cRotCorrectionDeg[i] * std::numbers::pi / 180.0,
                1e-12);
  }
  EXPECT_EQ(g.packet_period_ns, 663'552);
  EXPECT_NEAR(g.rotation_start_azimuth_rad, std::numbers::pi, 1e-12);
  // The manual's precision azimuth puts the last pair 15 x 2.304 us ahead of its firing: 0.124 deg.
  EXPECT_NEAR(g.azimuth_lead_rad * 180.0 / std::numbers::pi, 15 * 2.304e-6 * 3600.0, 1e-9);
  EXPECT_EQ(make_lidar_decoder("hdl32e", {})->geometry().packet_period_ns, 552'960);
  EXPECT_EQ(make_lidar_decoder("vlp16", {})->geometry().azimuth_lead_rad, 0.0);
}

TEST(LidarDecoderSeam, ReturnSelectionNames) {
  for (const ReturnSelection s : {ReturnSelection::both, ReturnSelection::strongest, ReturnSelection::last}) {
    EXPECT_EQ(return_selection_by_name(to_string(s)), s);
  }
  EXPECT_FALSE(return_selection_by_name("dual").has_value());
}

// Every payload is counted once, under "accepted", an auxiliary kind or a refusal reason; the
// informational "note." counts are not packets.
TEST(LidarDecoderSeam, EveryPayloadIsCountedOnce) {
  const auto decoder = make_lidar_decoder("vlp16", {});
  std::mt19937_64 rng(8);
  const FiringSchedule schedule(make_vlp16(), 0);
  std::vector<LidarPoint> points;
  for (std::int64_t k = 0; k < 5; ++k) {
    const test::EncodedPacket packet = test::make_packet(schedule, k, rng, 0.5);
    const PacketOutcome outcome = decoder->decode(packet.bytes, 0, points);
    EXPECT_EQ(outcome.kind, PacketKind::data);
    EXPECT_EQ(outcome.first_ns, packet.returns.blocks.first_firing_ns);
    // One packet period later; the next packet's own stamp is rounded to the microsecond.
    EXPECT_EQ(outcome.next_ns, outcome.first_ns + 1'327'104);
    EXPECT_NEAR(static_cast<double>(outcome.next_ns),
                static_cast<double>(schedule.packet(k + 1).first_firing_ns), 1000.0);
  }
  std::vector<std::uint8_t> position(512, 0);  // a position packet without GPS: timestamp 0
  EXPECT_EQ(decoder->decode(position, 0, points).kind, PacketKind::auxiliary);
  std::vector<std::uint8_t> junk(77, 1);
  EXPECT_EQ(decoder->decode(junk, 0, points).kind, PacketKind::refused);
  EXPECT_EQ(decoder->packets_seen(), 7U);
  std::uint64_t notes = 0;
  for (const auto& [name, value] : decoder->counters()) {
    if (name == "accepted") {
      EXPECT_EQ(value, 5U);
    }
    if (name == "position" || name == "wrong_size") {
      EXPECT_EQ(value, 1U) << name;
    }
    if (name == "note.points") {
      notes = value;
    }
  }
  EXPECT_EQ(notes, points.size());
}

}  // namespace
}  // namespace rsu::lidar
