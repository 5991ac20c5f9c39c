// SPDX-License-Identifier: Apache-2.0
// Several RSUs sharing announcements (RsuCore::on_peer_announcement), with hand-stepped time: two
// RsuCore instances exchange, through the test, what each accepted from a vehicle, as two rsud do over
// the data bus. The vehicle announces to the first RSU only and is corrected by both across the handover.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "common/angles.h"
#include "core/rsu_core.h"
#include "sim_stream.h"
#include "v2i/wire_codec.h"

namespace rsu::core {
namespace {

using testing::announce;

constexpr std::uint64_t kWest = 11;
constexpr std::uint64_t kEast = 12;

RsuCoreConfig config_for(std::uint64_t rsu_id, const Pose3& mount) {
  RsuCoreConfig c;
  c.rsu_id = rsu_id;
  c.sensor_model = "vlp16";
  c.mount = mount;
  c.background.learning_frames = 3;
  // Unsigned: these tests are about sharing (rsu_core_security_test.cpp verifies signed shared ones).
  c.security.mode = v2i::SecurityMode::kInsecure;
  return c;
}

RsuCoreConfig west_config() {
  return config_for(kWest, {.x = 0.0, .y = -6.0, .z = 2.0});
}

// A vehicle's announcement datagram as it left the vehicle.
std::vector<std::uint8_t> datagram(std::uint64_t id, std::uint32_t sequence, TimeNs now,
                                   const std::string& host) {
  return v2i::encode_v2i_message(announce(id, sequence, now, {10.0, 0.0, 0.0}, host));
}

PeerProvenance shared_by(std::uint64_t origin, const std::string& vehicle_host) {
  return {.origin_rsu_id = origin, .sender = {vehicle_host, 40000}};
}

TEST(PeerAnnouncement, SharedAnnouncementRegistersTheVehicleWithItsOwnReplyAddress) {
  RsuCore west(west_config());
  RsuCore east(config_for(kEast, {.x = 30.0, .y = -6.0, .z = 2.0}));
  const TimeNs now = 5 * kNsPerSecond;
  const std::vector<std::uint8_t> bytes = datagram(7, 1, now, "192.0.2.7");
  ASSERT_TRUE(west.on_datagram(bytes, {"192.0.2.7", 40000}, now).accepted());

  // The east RSU gets the same bytes from the bus a few ms later.
  const DatagramOutcome out =
      east.on_peer_announcement(bytes, shared_by(kWest, "192.0.2.7"), now + 3 * kNsPerMs);
  EXPECT_TRUE(out.accepted()) << out.reason();
  EXPECT_EQ(out.upsert, v2i::UpsertOutcome::kAdded);
  EXPECT_EQ(out.vehicle_id, 7U);
  const v2i::RegisteredVehicle* v = east.registry().find(7, now + 3 * kNsPerMs);
  ASSERT_NE(v, nullptr);
  EXPECT_EQ(v->announcement.reply_to.address, "192.0.2.7");
  EXPECT_EQ(v->source, "192.0.2.7");  // the vehicle, not the peer: its rate limit follows the vehicle
  // Counted as a peer announcement, not as a datagram.
  EXPECT_EQ(east.peer_stages().count(DatagramStage::kAccepted), 1U);
  EXPECT_EQ(east.datagram_stages().total(), 0U);
  EXPECT_EQ(west.peer_stages().total(), 0U);
}

TEST(PeerAnnouncement, OwnShareComingBackFromTheBusIsIgnored) {
  RsuCore west(west_config());
  const TimeNs now = 5 * kNsPerSecond;
  const auto bytes = datagram(7, 1, now, "192.0.2.7");
  EXPECT_EQ(west.on_peer_announcement(bytes, shared_by(kWest, "192.0.2.7"), now).stage,
            DatagramStage::kFromSelf);
  EXPECT_EQ(west.registry().size(), 0U);
  EXPECT_EQ(west.peer_stages().count(DatagramStage::kFromSelf), 1U);
}

TEST(PeerAnnouncement, OnlyFresherAnnouncementsReachTheRegistry) {
  RsuCore east(config_for(kEast, {.x = 30.0, .y = -6.0, .z = 2.0}));
  const TimeNs now = 5 * kNsPerSecond;
  const std::string host = "192.0.2.7";
  // The vehicle announced sequence 5 here directly; a peer shares 5 (the same) and then 4 (older).
  ASSERT_TRUE(east.on_datagram(datagram(7, 5, now, host), {host, 40000}, now).accepted());
  EXPECT_EQ(east.on_peer_announcement(datagram(7, 5, now, host), shared_by(kWest, host), now + 1).stage,
            DatagramStage::kNotFresher);
  EXPECT_EQ(east.on_peer_announcement(datagram(7, 4, now, host), shared_by(kWest, host), now + 2).stage,
            DatagramStage::kNotFresher);
  EXPECT_EQ(east.registry().find(7, now + 2)->announcement.sequence, 5U);
  // Neither touched the registry (no duplicate or stale count, no rate-limit token taken).
  EXPECT_EQ(east.registry().stats().outcomes.total(), 1U);
  // A newer one does.
  const DatagramOutcome newer =
      east.on_peer_announcement(datagram(7, 6, now, host), shared_by(kWest, host), now + 3);
  EXPECT_EQ(newer.upsert, v2i::UpsertOutcome::kUpdated);
  EXPECT_EQ(east.registry().find(7, now + 3)->announcement.sequence, 6U);
  EXPECT_EQ(east.peer_stages().count(DatagramStage::kNotFresher), 2U);
}

TEST(PeerAnnouncement, BadSharedContentIsRefusedByReason) {
  RsuCore east(config_for(kEast, {.x = 30.0, .y = -6.0, .z = 2.0}));
  const TimeNs now = 5 * kNsPerSecond;
  const std::vector<std::uint8_t> garbage = {0xde, 0xad, 0xbe, 0xef, 0xff, 0xff, 0xff, 0xff, 0xff, 0x01};
  auto zero = announce(8, 1, now, {10.0, 0.0, 0.0}, "192.0.2.8");
  zero.size.length_m = 0.0;
  EXPECT_EQ(east.on_peer_announcement(garbage, shared_by(kWest, "192.0.2.8"), now).reason(),
            "decode:parse_error");
  EXPECT_EQ(
      east.on_peer_announcement(v2i::encode_v2i_message(zero), shared_by(kWest, "192.0.2.8"), now).reason(),
      "validation:length_out_of_range");
  // reply_to must be the address the origin RSU heard the vehicle from (no reflection through a peer).
  EXPECT_EQ(east.on_peer_announcement(datagram(9, 1, now, "198.51.100.1"), shared_by(kWest, "192.0.2.9"), now)
                .reason(),
            "reply_to_mismatch:address");
  v2i::Correction not_an_announcement;
  not_an_announcement.vehicle_id = 3;
  EXPECT_EQ(east.on_peer_announcement(v2i::encode_v2i_message(not_an_announcement),
                                      shared_by(kWest, "192.0.2.3"), now)
                .reason(),
            "not_announcement");
  EXPECT_EQ(east.registry().size(), 0U);
  EXPECT_EQ(east.peer_stages().total(), 4U);
  // The shared decoder and validator count them too.
  EXPECT_EQ(east.decode_counts().count(v2i::DecodeStatus::kParseError), 1U);
  EXPECT_EQ(east.validation_counts().count(v2i::AnnouncementReason::kLengthOutOfRange), 1U);
}

TEST(PeerAnnouncement, FloodFromOnePeerIsLimitedAndOtherPeersAreStillHeard) {
  RsuCore east(config_for(kEast, {.x = 30.0, .y = -6.0, .z = 2.0}));
  const TimeNs now = 5 * kNsPerSecond;
  const std::vector<std::uint8_t> garbage(40, 0xff);
  const double burst = east.config().peers.flood.bucket.burst;
  std::uint64_t limited = 0;
  for (int i = 0; i < 3000; ++i) {
    limited += east.on_peer_announcement(garbage, shared_by(99, "192.0.2.99"), now + i).stage ==
               DatagramStage::kFloodLimited;
  }
  // 3000 in 3 us: the burst passes (and is refused later as garbage), the rest is cut off.
  EXPECT_EQ(limited, 3000U - static_cast<std::uint64_t>(burst));
  EXPECT_EQ(east.decode_counts().count(v2i::DecodeStatus::kParseError), static_cast<std::uint64_t>(burst));
  EXPECT_TRUE(
      east.on_peer_announcement(datagram(7, 1, now, "192.0.2.7"), shared_by(kWest, "192.0.2.7"), now + 5000)
          .accepted());
  const auto counters = east.counters();
  const auto it = std::find_if(counters.begin(), counters.end(),
                               [](const auto& c) { return c.first == "peer.flood_limited"; });
  ASSERT_NE(it, counters.end());
  EXPECT_EQ(it->second, limited);
}

// The handover: two roadside VLP-16s 30 m apart, each correcting within 20 m (an overlap of ~8 m along
// the road), and a vehicle driving past both at 10 m/s that announces to the west RSU only.
TEST(PeerAnnouncement, VehicleAnnouncingToOneRsuIsCorrectedByBothAcrossTheHandover) {
  sim::Scene scene;
  scene.ground.half_extent_m = 90.0;
  scene.buildings.push_back(
      {.x = 15.0, .y = 25.0, .yaw = 0.0, .length = 70.0, .width = 10.0, .height = 12.0});
  scene.poles.push_back({.x = 15.0, .y = -7.0, .radius = 0.15, .height = 6.0});
  const Pose3 west_mount{.x = 0.0, .y = -6.0, .z = 2.0};
  const Pose3 east_mount{.x = 30.0, .y = -6.0, .z = 2.0};
  constexpr double kSpeed = 10.0;
  constexpr double kX0 = -10.0;
  constexpr int kRotationsWithoutVehicles = 5;
  const TimeNs t0 = 700 * kNsPerMs;  // the drive starts after the background rotations
  const TimeNs t1 = t0 + 5 * kNsPerSecond;
  // The truth, on a straight lane along +x at y = 0.
  const auto truth_at = [&](TimeNs t) {
    return Pose2{kX0 + kSpeed * to_seconds(std::clamp(t, t0, t1) - t0), 0.0, 0.0};
  };
  sim::Vehicle vehicle;
  vehicle.id = 1;
  vehicle.trajectory = sim::Waypoints{{{t0, truth_at(t0)}, {t1, truth_at(t1)}}};

  RsuCoreConfig west_cfg = config_for(kWest, west_mount);
  RsuCoreConfig east_cfg = config_for(kEast, east_mount);
  west_cfg.coverage_radius_m = east_cfg.coverage_radius_m = 20.0;
  RsuCore west(west_cfg);
  RsuCore east(east_cfg);
  testing::SimStream west_lidar(scene, {vehicle}, lidar::make_vlp16(), west_mount, sim::NoiseModel{},
                                kRotationsWithoutVehicles);
  testing::SimStream east_lidar(scene, {vehicle}, lidar::make_vlp16(), east_mount, sim::NoiseModel{},
                                kRotationsWithoutVehicles);

  const std::string host = "192.0.2.50";
  std::uint32_t sequence = 0;
  std::uint64_t shared = 0;
  for (TimeNs t = t0 - 200 * kNsPerMs; t < t1; t += 100 * kNsPerMs) {
    // The vehicle's own estimate is 0.3 m off; it announces its speed.
    const Pose2 truth = truth_at(t);
    auto a = announce(1, ++sequence, t, {truth.x + 0.25, truth.y - 0.15, truth.yaw + 0.03}, host);
    a.speed_mps = t >= t0 ? kSpeed : 0.0;
    const auto bytes = v2i::encode_v2i_message(a);
    if (west.on_datagram(bytes, {host, 40000}, t).accepted()) {
      ++shared;  // rsud shares what it accepted; it arrives at the peer a few ms later
      ASSERT_TRUE(east.on_peer_announcement(bytes, shared_by(kWest, host), t + 2 * kNsPerMs).accepted());
    }
    west_lidar.run_until(west, t + 100 * kNsPerMs);
    east_lidar.run_until(east, t + 100 * kNsPerMs);
  }
  EXPECT_EQ(shared, sequence);
  EXPECT_EQ(east.datagram_stages().total(), 0U);  // the east RSU never heard the vehicle itself

  struct Fix {
    v2i::Correction c;
    std::string destination;
  };
  std::vector<Fix> fixes;
  for (const auto* lidar : {&west_lidar, &east_lidar}) {
    for (const auto& [out, emitted_at] : lidar->corrections())
      fixes.push_back({out.correction, out.destination.address});
  }
  std::sort(fixes.begin(), fixes.end(),
            [](const Fix& a, const Fix& b) { return a.c.sweep_time < b.c.sweep_time; });
  ASSERT_FALSE(fixes.empty());
  std::size_t from_west = 0;
  std::size_t from_east = 0;
  for (const Fix& f : fixes) {
    const Pose2 truth = truth_at(f.c.sweep_time);
    EXPECT_EQ(f.destination, host);  // each RSU sends to the vehicle directly
    EXPECT_LT(std::hypot(f.c.pose.x - truth.x, f.c.pose.y - truth.y), 0.15)
        << "rsu " << f.c.rsu_id << " at x = " << truth.x;
    EXPECT_LT(angle_distance(f.c.pose.yaw, truth.yaw), deg_to_rad(3.0));
    // Each RSU corrects only within its coverage (fitted centre within 20 m, the truth within ~20.2 m).
    const Pose3& mount = f.c.rsu_id == kWest ? west_mount : east_mount;
    EXPECT_LT(std::hypot(truth.x - mount.x, truth.y - mount.y), 20.3);
    ASSERT_TRUE(f.c.rsu_id == kWest || f.c.rsu_id == kEast);
    (f.c.rsu_id == kWest ? from_west : from_east) += 1;
  }
  // Both corrected it for about their stretch of the 50 m drive (10 Hz), and in the overlap both did.
  EXPECT_GE(from_west, 25U);
  EXPECT_GE(from_east, 25U);
  const auto in_overlap = [&](const Fix& f) {
    const double x = truth_at(f.c.sweep_time).x;
    return x > 12.0 && x < 18.0;
  };
  EXPECT_GE(std::count_if(fixes.begin(), fixes.end(),
                          [&](const Fix& f) { return in_overlap(f) && f.c.rsu_id == kWest; }),
            4);
  EXPECT_GE(std::count_if(fixes.begin(), fixes.end(),
                          [&](const Fix& f) { return in_overlap(f) && f.c.rsu_id == kEast; }),
            4);
  // No gap in the corrections over the whole drive: from the first (once registered) to the last.
  EXPECT_LT(fixes.front().c.sweep_time - t0, 200 * kNsPerMs);
  EXPECT_GT(fixes.back().c.sweep_time, t1 - 200 * kNsPerMs);
  for (std::size_t i = 1; i < fixes.size(); ++i) {
    EXPECT_LE(fixes[i].c.sweep_time - fixes[i - 1].c.sweep_time, 200 * kNsPerMs)
        << "gap at x = " << truth_at(fixes[i].c.sweep_time).x;
  }
  EXPECT_EQ(east.peer_stages().count(DatagramStage::kAccepted), shared);
}

}  // namespace
}  // namespace rsu::core
