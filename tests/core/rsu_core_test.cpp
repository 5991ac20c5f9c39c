// SPDX-License-Identifier: Apache-2.0
// RsuCore with hand-stepped time: announcements into the registry, real Velodyne packets of a
// simulated roadside VLP-16 into corrections, and every refusal counted by its reason.
#include "core/rsu_core.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <future>
#include <initializer_list>
#include <limits>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "common/angles.h"
#include "core_counter.h"
#include "sim_stream.h"
#include "v2i/wire_codec.h"

namespace rsu::core {
namespace {

using testing::announce;
using testing::counter;
using testing::SimStream;
using testing::static_vehicle;

constexpr int kEmptyRotations = 5;  // the scene without vehicles: enough for 3 whole learning frames

RsuCoreConfig test_config() {
  RsuCoreConfig c;
  c.rsu_id = 77;
  c.sensor_model = "vlp16";
  c.mount = testing::roadside_mount();
  c.background.learning_frames = 3;
  // These tests are about everything but signatures (rsu_core_security_test.cpp covers signed mode).
  c.security.mode = v2i::SecurityMode::kInsecure;
  return c;
}

SourceEndpoint from(const std::string& address) {
  return {address, 40000};
}

// Announces `pose` for vehicle `id` at 10 Hz from time t0 to t1 (sequence numbers from 1).
// A pose `forward` and `left` of the roadside mount (testing::roadside_mount), turned `yaw` from it.
Pose2 beside_mount(double forward, double left, double yaw) {
  const Pose3 m = testing::roadside_mount();
  const Eigen::Vector2d rel = Eigen::Rotation2Dd(m.yaw) * Eigen::Vector2d(forward, left);
  return Pose2{m.x + rel.x(), m.y + rel.y(), m.yaw + yaw};
}

void announce_between(RsuCore& core, std::uint64_t id, const Pose2& pose, const std::string& address,
                      TimeNs t0, TimeNs t1) {
  std::uint32_t seq = 1;
  for (TimeNs t = t0; t <= t1; t += 100 * kNsPerMs, ++seq) {
    const auto bytes = v2i::encode_v2i_message(announce(id, seq, t, pose, address));
    const DatagramOutcome out = core.on_datagram(bytes, from(address), t);
    ASSERT_TRUE(out.accepted()) << out.reason();
  }
}

double distance(const v2i::Correction& c, const Pose2& truth) {
  return std::hypot(c.pose.x - truth.x, c.pose.y - truth.y);
}

// At least `at_least` corrections, each within 0.10 m of the truth and fixed from the body (not a
// fragment of it).
void expect_fixed_from_the_body(const SimStream& stream, const Pose2& truth, std::size_t at_least) {
  ASSERT_GE(stream.corrections().size(), at_least);
  for (const auto& [out, emitted_at] : stream.corrections()) {
    EXPECT_LT(distance(out.correction, truth), 0.10) << out.correction.quality.points_used << " points";
    EXPECT_GT(out.correction.quality.points_used, 60U);
  }
}

TEST(RsuCore, AnnouncementsEnterTheRegistry) {
  RsuCore core(test_config());
  const TimeNs now = 5 * kNsPerSecond;
  const auto a = announce(42, 7, now, {10.0, 2.0, 0.5}, "192.0.2.5");
  const DatagramOutcome first = core.on_datagram(v2i::encode_v2i_message(a), from("192.0.2.5"), now);
  EXPECT_TRUE(first.accepted());
  EXPECT_EQ(first.upsert, v2i::UpsertOutcome::kAdded);
  EXPECT_EQ(first.vehicle_id, 42U);
  const v2i::RegisteredVehicle* v = core.registry().find(42, now);
  ASSERT_NE(v, nullptr);
  EXPECT_EQ(v->announcement.sequence, 7U);
  EXPECT_DOUBLE_EQ(v->announcement.pose.x, 10.0);
  EXPECT_EQ(v->announcement.reply_to.address, "192.0.2.5");

  // The same sequence again is a duplicate; a newer one updates.
  EXPECT_EQ(core.on_datagram(v2i::encode_v2i_message(a), from("192.0.2.5"), now + 1).reason(),
            "registry:duplicate_sequence");
  auto b = a;
  b.sequence = 8;
  b.pose.x = 11.0;
  EXPECT_EQ(core.on_datagram(v2i::encode_v2i_message(b), from("192.0.2.5"), now + 2).upsert,
            v2i::UpsertOutcome::kUpdated);
  EXPECT_DOUBLE_EQ(core.registry().find(42, now + 2)->announcement.pose.x, 11.0);

  // Silent beyond the registry timeout: gone.
  EXPECT_EQ(core.expire(now + 3 * kNsPerSecond), 1U);
  EXPECT_EQ(core.registry().find(42, now + 3 * kNsPerSecond), nullptr);
}

TEST(RsuCore, BadDatagramsAreCountedByReason) {
  RsuCore core(test_config());
  const TimeNs now = 5 * kNsPerSecond;
  const std::string host = "192.0.2.9";
  const auto good = v2i::encode_v2i_message(announce(5, 1, now, {10.0, 2.0, 0.5}, host));
  ASSERT_FALSE(good.empty());

  const std::vector<std::uint8_t> empty;
  const std::vector<std::uint8_t> garbage = {0xde, 0xad, 0xbe, 0xef, 0xff, 0xff, 0xff, 0xff, 0xff, 0x01};
  const std::vector<std::uint8_t> truncated(good.begin(),
                                            good.begin() + static_cast<std::ptrdiff_t>(good.size() / 2));
  const std::vector<std::uint8_t> oversized(4000, 0x08);
  auto version = announce(6, 1, now, {10.0, 2.0, 0.5}, host);
  version.protocol_version = 9;
  auto nan_size = announce(7, 1, now, {10.0, 2.0, 0.5}, host);
  nan_size.size.length_m = std::numeric_limits<double>::quiet_NaN();
  auto zero = announce(8, 1, now, {10.0, 2.0, 0.5}, host);
  zero.size.length_m = 0.0;
  auto huge = announce(9, 1, now, {10.0, 2.0, 0.5}, host);
  huge.size.length_m = 100.0;
  auto spoofed = announce(10, 1, now, {10.0, 2.0, 0.5}, "198.51.100.1");  // reply_to another host
  v2i::Correction not_an_announcement;
  not_an_announcement.vehicle_id = 3;

  struct Case {
    std::vector<std::uint8_t> bytes;
    std::string expected;
  };
  const std::vector<Case> cases = {
      {empty, "decode:empty"},
      {garbage, "decode:parse_error"},
      {truncated, "decode:parse_error"},
      {oversized, "decode:too_large"},
      {v2i::encode_v2i_message(version), "decode:unsupported_version"},
      {v2i::encode_v2i_message(nan_size), "validation:non_finite"},
      {v2i::encode_v2i_message(zero), "validation:length_out_of_range"},
      {v2i::encode_v2i_message(huge), "validation:length_out_of_range"},
      {v2i::encode_v2i_message(spoofed), "reply_to_mismatch:address"},
      {v2i::encode_v2i_message(not_an_announcement), "not_announcement"},
  };
  for (const Case& c : cases) {
    EXPECT_EQ(core.on_datagram(c.bytes, from(host), now).reason(), c.expected);
  }
  EXPECT_EQ(core.decode_counts().count(v2i::DecodeStatus::kParseError), 2U);
  EXPECT_EQ(core.decode_counts().count(v2i::DecodeStatus::kEmpty), 1U);
  EXPECT_EQ(core.decode_counts().count(v2i::DecodeStatus::kTooLarge), 1U);
  EXPECT_EQ(core.validation_counts().count(v2i::AnnouncementReason::kLengthOutOfRange), 2U);
  EXPECT_EQ(core.decode_counts().count(v2i::DecodeStatus::kUnsupportedVersion), 1U);
  EXPECT_EQ(core.datagram_stages().count(DatagramStage::kValidation), 3U);
  EXPECT_EQ(core.datagram_stages().count(DatagramStage::kReplyToMismatch), 1U);
  EXPECT_EQ(core.registry().size(), 0U);

  // A flood from one host: the pre-decode limit (burst 100) stops it; another host is still served.
  const std::string flooder = "192.0.2.66";
  std::uint64_t limited = 0;
  for (int i = 0; i < 1000; ++i) {
    limited += core.on_datagram(garbage, from(flooder), now + i).stage == DatagramStage::kFloodLimited;
  }
  EXPECT_GE(limited, 1000U - 101U);
  EXPECT_EQ(core.datagram_stages().count(DatagramStage::kFloodLimited), limited);
  EXPECT_TRUE(core.on_datagram(good, from(host), now + 2000).accepted());

  // Every counter is listed, and the listing agrees with the typed counts.
  bool found = false;
  for (const auto& [name, value] : core.counters()) {
    if (name == "datagram.flood_limited") {
      found = true;
      EXPECT_EQ(value, limited);
    }
  }
  EXPECT_TRUE(found);
}

// reply_to must be the datagram's source address AND port by default (a correction sent to another
// port is lost to a vehicle that listens on the one it announced from); match_address lets the port
// differ; use_source (NAT) takes the source instead. Each case counted as reply_to.<detail>.
TEST(RsuCore, ReplyToMustBeTheSourcesAddressAndPortUnlessConfigured) {
  const TimeNs now = 10 * kNsPerSecond;
  const std::string host = "192.0.2.10";
  auto other_port = announce(1, 1, now, {10.0, 2.0, 0.5}, host);
  other_port.reply_to.port = testing::kVehiclePort + 1;
  auto other_host = announce(2, 1, now, {20.0, 2.0, 0.5}, "10.0.0.5");

  RsuCore strict(test_config());
  EXPECT_EQ(strict.on_datagram(v2i::encode_v2i_message(other_port), from(host), now).reason(),
            "reply_to_mismatch:port");
  EXPECT_EQ(strict.on_datagram(v2i::encode_v2i_message(other_host), from(host), now).reason(),
            "reply_to_mismatch:address");
  EXPECT_EQ(counter(strict, "reply_to.port"), 1U);
  EXPECT_EQ(counter(strict, "reply_to.address"), 1U);
  EXPECT_EQ(counter(strict, "datagram.reply_to_mismatch"), 2U);
  EXPECT_EQ(strict.registry().size(), 0U);

  RsuCoreConfig loose = test_config();
  loose.reply_to = ReplyToPolicy::kMatchAddress;
  RsuCore address_only(loose);
  EXPECT_TRUE(address_only.on_datagram(v2i::encode_v2i_message(other_port), from(host), now).accepted());
  EXPECT_EQ(address_only.on_datagram(v2i::encode_v2i_message(other_host), from(host), now).reason(),
            "reply_to_mismatch:address");

  RsuCoreConfig nat = test_config();
  nat.reply_to = ReplyToPolicy::kUseSource;
  RsuCore behind_nat(nat);
  const SourceEndpoint mapped{"198.51.100.7", 61000};  // what the NAT made of the vehicle's address
  EXPECT_TRUE(behind_nat.on_datagram(v2i::encode_v2i_message(other_host), mapped, now).accepted());
  const v2i::RegisteredVehicle* v = behind_nat.registry().find(2, now);
  ASSERT_NE(v, nullptr);
  EXPECT_EQ(v->announcement.reply_to.address, mapped.address);
  EXPECT_EQ(v->announcement.reply_to.port, mapped.port);
  EXPECT_EQ(counter(behind_nat, "reply_to.replaced"), 1U);
}

// A vehicle whose announcements keep being refused learns why, at most once per vehicle per interval;
// a retransmission (the same sequence again) gets nothing.
TEST(RsuCore, RefusalNoticesAreRateLimitedPerVehicle) {
  const TimeNs now = 10 * kNsPerSecond;
  const std::string host = "192.0.2.10";
  RsuCore core(test_config());
  int notices = 0;
  for (int i = 0; i < 25; ++i) {  // 10 Hz for 2.5 s
    const TimeNs t = now + i * 100 * kNsPerMs;
    auto a = announce(1, static_cast<std::uint32_t>(i + 1), t, {10.0, 2.0, 0.5}, host);
    a.size.length_m = 40.0;
    const DatagramOutcome out = core.on_datagram(v2i::encode_v2i_message(a), from(host), t);
    EXPECT_EQ(out.reason(), "validation:length_out_of_range");
    if (out.refusal_notice.empty())
      continue;
    ++notices;
    const v2i::DecodedMessage m = v2i::decode_v2i_message(out.refusal_notice);
    ASSERT_EQ(m.status, v2i::DecodeStatus::kOk);
    const auto& notice = std::get<v2i::AnnouncementRefusal>(m.body);
    EXPECT_EQ(notice.reason, v2i::RefusalReason::kValidation);
    EXPECT_EQ(notice.detail, "length_out_of_range");
    EXPECT_EQ(notice.announcement_sequence, a.sequence);
    EXPECT_LT(out.refusal_notice.size(), v2i::encode_v2i_message(a).size());  // never an amplifier
  }
  EXPECT_EQ(notices, 3);  // at 0 s, about 1 s and about 2 s (one interval after the last)
  EXPECT_EQ(counter(core, "refusal.notices"), 3U);
  EXPECT_EQ(counter(core, "refusal.rate_limited"), 22U);

  // Accepted, then the same sequence again: a retransmission, no notice.
  const auto good = announce(2, 1, now, {20.0, 2.0, 0.5}, host);
  EXPECT_TRUE(core.on_datagram(v2i::encode_v2i_message(good), from(host), now).accepted());
  const DatagramOutcome again = core.on_datagram(v2i::encode_v2i_message(good), from(host), now);
  EXPECT_EQ(again.reason(), "registry:duplicate_sequence");
  EXPECT_TRUE(again.refusal_notice.empty());
}

TEST(RsuCore, LearnsTheBackgroundFromWholeRotationsThenReportsReady) {
  SimStream stream({}, 100);
  RsuCore core(test_config());
  int ready_steps = 0;
  TimeNs ready_at = -1;
  stream.run_until(core, 6 * stream.rotation_ns(), [&](const LidarStepResult& r, TimeNs now) {
    if (r.background_became_ready) {
      ++ready_steps;
      ready_at = now;
    }
  });
  EXPECT_EQ(ready_steps, 1);
  EXPECT_TRUE(core.background_ready());
  EXPECT_EQ(core.lidar_stats().background_frames, 3U);
  // The first (partial) rotation is not used: ready after rotation 4 ends, not before rotation 3 does.
  EXPECT_GT(ready_at, 3 * stream.rotation_ns());
  EXPECT_LT(ready_at, 5 * stream.rotation_ns());
  // The learned background is the scene: further empty rotations give no foreground clusters.
  stream.run_until(core, 8 * stream.rotation_ns());
  EXPECT_EQ(core.sweep_stats().clusters_released, 0U);
  EXPECT_TRUE(stream.corrections().empty());
}

TEST(RsuCore, RegisteredVehicleGetsCorrectionsNearTheTruth) {
  // A vehicle 15 m from the LiDAR, straddling the sensor's 0 deg azimuth (a frame cut).
  const Pose2 truth{17.0, 2.0, 0.4};
  SimStream stream({static_vehicle(1, truth)}, kEmptyRotations);
  RsuCore core(test_config());
  const TimeNs t_end = (kEmptyRotations + 4) * stream.rotation_ns();
  // The vehicle's own estimate is 0.6 m and 4 deg off.
  announce_between(core, 1, {truth.x + 0.4, truth.y - 0.45, truth.yaw + deg_to_rad(4.0)}, "192.0.2.10",
                   kEmptyRotations * stream.rotation_ns() - 200 * kNsPerMs,
                   kEmptyRotations * stream.rotation_ns());
  stream.run_until(core, t_end);

  ASSERT_GE(stream.corrections().size(), 3U);
  std::uint32_t expected_sequence = 0;
  for (const auto& [out, emitted_at] : stream.corrections()) {
    const v2i::Correction& c = out.correction;
    EXPECT_EQ(c.vehicle_id, 1U);
    EXPECT_EQ(c.rsu_id, 77U);
    EXPECT_EQ(c.sequence, expected_sequence++);
    EXPECT_EQ(out.destination.address, "192.0.2.10");
    EXPECT_EQ(out.destination.port, testing::kVehiclePort);
    EXPECT_LT(distance(c, truth), 0.10) << c.pose.x << ", " << c.pose.y;
    // The faces' direction fused with the vehicle's own, 4 deg off: a side seen between 0.8 m and the lower
    // body's height may be a glasshouse over a low belt line, so it counts less there (the first fix 2.0 deg
    // off, stating 4.0 deg; 0.1 deg off before it counted less).
    const double yaw_sigma = std::sqrt(c.pose_covariance(2, 2));
    EXPECT_LT(angle_distance(c.pose.yaw, truth.yaw), deg_to_rad(2.5));
    EXPECT_LT(angle_distance(c.pose.yaw, truth.yaw), 3.0 * yaw_sigma);
    // Swept in the last rotation before it was sent, and sent at most a few ms after.
    EXPECT_LE(c.sweep_time, emitted_at);
    EXPECT_GT(c.sweep_time, emitted_at - stream.rotation_ns());
    EXPECT_GT(c.quality.points_used, 50U);
    EXPECT_GE(c.quality.faces_seen, 1U);
    EXPECT_NEAR(c.quality.range_m, std::hypot(truth.x - 2.0, truth.y + 3.0), 3.0);
    EXPECT_GT(c.pose_covariance(0, 0), 0.0);
    // The bytes say the same.
    const v2i::DecodedMessage decoded = v2i::decode_v2i_message(out.bytes);
    ASSERT_EQ(decoded.status, v2i::DecodeStatus::kOk);
    const auto* d = std::get_if<v2i::Correction>(&decoded.body);
    ASSERT_NE(d, nullptr);
    EXPECT_EQ(d->sweep_time, c.sweep_time);
    EXPECT_DOUBLE_EQ(d->pose.x, c.pose.x);
  }
}

TEST(RsuCore, RoofFragmentIsFittedWithTheBodyNotInsteadOfIt) {
  // 15.5 m in front of a VLP-16 at 2 m: its -1 deg ring reaches the roof's far edge at ~17 m, metres
  // behind the visible faces, so the roof edge is a cluster of its own (~10 points) whose centre can
  // be nearer the vehicle's announced position than the body's. Every correction must use the body.
  const Pose3 m = testing::roadside_mount();
  const Eigen::Vector2d rel = Eigen::Rotation2Dd(m.yaw) * Eigen::Vector2d(15.0, 4.0);
  const Pose2 truth{m.x + rel.x(), m.y + rel.y(), m.yaw + deg_to_rad(20.0)};
  SimStream stream({static_vehicle(1, truth)}, kEmptyRotations);
  RsuCore core(test_config());
  const TimeNs t1 = kEmptyRotations * stream.rotation_ns();
  announce_between(core, 1, {truth.x + 0.4, truth.y - 0.3, truth.yaw + 0.05}, "192.0.2.10",
                   t1 - 100 * kNsPerMs, t1);
  stream.run_until(core, t1 + 11 * stream.rotation_ns());
  expect_fixed_from_the_body(stream, truth, 9);
  EXPECT_GT(core.lidar_stats().fragments_merged, 0U);  // the geometry does produce roof fragments
}

TEST(RsuCore, CorrectionLeavesSoonAfterTheSweepPassedTheVehicle) {
  // About 90 deg into the rotation (clockwise from the sensor's +x): a frame-based RSU would hold
  // the fix for ~75 ms until the rotation ends; the sector release sends it within a few ms.
  const double bearing = testing::roadside_mount().yaw - deg_to_rad(90.0);
  const Pose2 truth{2.0 + 15.0 * std::cos(bearing), -3.0 + 15.0 * std::sin(bearing), 1.0};
  SimStream stream({static_vehicle(1, truth)}, kEmptyRotations);
  RsuCore core(test_config());
  announce_between(core, 1, truth, "192.0.2.10", kEmptyRotations * stream.rotation_ns() - 100 * kNsPerMs,
                   kEmptyRotations * stream.rotation_ns());
  stream.run_until(core, (kEmptyRotations + 2) * stream.rotation_ns());
  ASSERT_FALSE(stream.corrections().empty());
  for (const auto& [out, emitted_at] : stream.corrections()) {
    EXPECT_LT(distance(out.correction, truth), 0.10);
    // The vehicle spans ~20 deg (5.5 ms of sweep) around its mean time: sent within ~10 ms of it.
    EXPECT_LT(emitted_at - out.correction.sweep_time, 10 * kNsPerMs);
  }
}

// The notices of one run, as the daemon would send them.
struct NoticesSent {
  std::vector<std::pair<OutgoingNotice, TimeNs>> sent;  // with the time each was emitted
  std::function<void(const LidarStepResult&, TimeNs)> recorder() {
    return [this](const LidarStepResult& r, TimeNs now) {
      for (const OutgoingNotice& n : r.withheld_notices)
        sent.emplace_back(n, now);
    };
  }
};

std::uint64_t withheld_notices_counted(const RsuCore& core) {
  std::uint64_t n = 0;
  for (const auto& [name, value] : core.counters())
    n += name.starts_with("withheld_notice.") ? value : 0;
  return n;
}

// Where the RSU cannot bound a seen vehicle's position it sends no fix and tells the vehicle why: the
// sigma the fix would have stated (the very one a twin RSU with the default bound sent, for the same
// sweep) against the bound, at most once a second (the rest counted as held back). The twin, which
// fixes the vehicle, tells it nothing.
TEST(RsuCore, UnboundedVehicleIsToldWhyOncePerSecondAFixedOneNothing) {
  const Pose2 truth{17.0, 2.0, 0.4};
  SimStream stream({static_vehicle(1, truth)}, kEmptyRotations);
  RsuCoreConfig strict = test_config();
  strict.perception.fix.correction.max_position_sigma_m = 0.001;  // no fix states that little
  RsuCore core(strict);
  RsuCore twin(test_config());
  const TimeNs t1 = kEmptyRotations * stream.rotation_ns();
  const TimeNs t_end = t1 + 25 * stream.rotation_ns();  // 2.5 s of the vehicle
  for (RsuCore* c : {&core, &twin})
    announce_between(*c, 1, truth, "192.0.2.10", t1 - 100 * kNsPerMs, t_end);
  NoticesSent notices;
  stream.run_until(core, &twin, t_end, notices.recorder());

  EXPECT_TRUE(stream.corrections().empty());
  ASSERT_GE(stream.twin_corrections().size(), 20U);
  EXPECT_EQ(withheld_notices_counted(twin), 0U);
  // One at the first rotation, then one a second: at about 1 s and 2 s.
  ASSERT_EQ(notices.sent.size(), 3U);
  const std::uint64_t withheld = core.lidar_stats().corrections_failed;
  EXPECT_GE(withheld, 20U);
  EXPECT_EQ(counter(core, "withheld_notice.position_unbounded"), 3U);
  EXPECT_EQ(counter(core, "withheld_notice.rate_limited.position_unbounded"), withheld - 3);
  for (std::size_t i = 0; i < notices.sent.size(); ++i) {
    const auto& [out, emitted_at] = notices.sent[i];
    const v2i::FixWithheld& n = out.notice;
    EXPECT_EQ(n.reason, v2i::FixWithheldReason::kPositionUnbounded);
    EXPECT_EQ(n.rsu_id, 77U);
    EXPECT_EQ(n.vehicle_id, 1U);
    EXPECT_EQ(n.announcement_sequence, core.registry().find(1, t_end)->announcement.sequence);
    EXPECT_EQ(out.destination.address, "192.0.2.10");
    EXPECT_EQ(out.destination.port, testing::kVehiclePort);
    EXPECT_LE(n.sweep_time, emitted_at);
    EXPECT_GT(n.sweep_time, emitted_at - stream.rotation_ns());
    if (i > 0) {
      EXPECT_GE(n.sweep_time - notices.sent[i - 1].first.notice.sweep_time, 900 * kNsPerMs);
    }
    EXPECT_EQ(n.max_position_sigma_m, 0.001);
    EXPECT_FALSE(n.packets_lost_nearby);
    EXPECT_EQ(n.mount_cause, v2i::FixesWithheld::kNone);
    const auto twin_fix = std::find_if(
        stream.twin_corrections().begin(), stream.twin_corrections().end(),
        [&](const SimStream::Received& r) { return r.correction.correction.sweep_time == n.sweep_time; });
    ASSERT_NE(twin_fix, stream.twin_corrections().end()) << "no fix of sweep " << n.sweep_time;
    perception::CorrectedPose stated;
    stated.covariance = twin_fix->correction.correction.pose_covariance;
    ASSERT_TRUE(n.position_sigma_m.has_value());
    EXPECT_DOUBLE_EQ(*n.position_sigma_m, perception::position_sigma_m(stated));
    // The bytes say the same, in a datagram no larger than the correction it stands for.
    const v2i::DecodedMessage m = v2i::decode_v2i_message(out.bytes);
    ASSERT_EQ(m.status, v2i::DecodeStatus::kOk);
    EXPECT_EQ(std::get<v2i::FixWithheld>(m.body).sweep_time, n.sweep_time);
    EXPECT_LT(out.bytes.size(), twin_fix->correction.bytes.size());
  }
}

TEST(RsuCore, UnregisteredVehicleGetsNothing) {
  SimStream stream({static_vehicle(1, {17.0, 2.0, 0.4})}, kEmptyRotations);
  RsuCore core(test_config());
  stream.run_until(core, (kEmptyRotations + 3) * stream.rotation_ns());
  EXPECT_TRUE(stream.corrections().empty());
  EXPECT_GE(core.lidar_stats().clusters_unmatched, 2U);  // it was seen, and matched nobody
}

TEST(RsuCore, RegisteredVehicleOutOfViewGetsNothing) {
  // Vehicle 2 is registered but not in the scene (announced 25 m away from the one that is).
  SimStream stream({static_vehicle(1, {17.0, 2.0, 0.4})}, kEmptyRotations);
  RsuCore core(test_config());
  announce_between(core, 2, {-20.0, -15.0, 0.0}, "192.0.2.20",
                   kEmptyRotations * stream.rotation_ns() - 100 * kNsPerMs,
                   kEmptyRotations * stream.rotation_ns());
  stream.run_until(core, (kEmptyRotations + 3) * stream.rotation_ns());
  EXPECT_TRUE(stream.corrections().empty());
  EXPECT_GE(core.lidar_stats().clusters_unmatched, 2U);
  EXPECT_GE(core.lidar_stats().vehicles_in_batches, 2U);  // it was offered, and matched nothing
  EXPECT_EQ(withheld_notices_counted(core), 0U);          // not seen: nothing to say
}

TEST(RsuCore, TwoVehiclesSideBySideAreNotSwapped) {
  // Adjacent lanes, 3.5 m apart; each vehicle's own estimate is 1 m off TOWARDS the other, so a
  // nearest-announcement choice would be close to a coin toss.
  const Pose2 a{18.0, 1.75, 0.05};
  const Pose2 b{18.5, 5.25, 0.05};
  SimStream stream({static_vehicle(1, a), static_vehicle(2, b)}, kEmptyRotations);
  RsuCore core(test_config());
  const TimeNs t0 = kEmptyRotations * stream.rotation_ns() - 100 * kNsPerMs;
  const TimeNs t1 = kEmptyRotations * stream.rotation_ns();
  announce_between(core, 1, {a.x, a.y + 1.0, a.yaw}, "192.0.2.1", t0, t1);
  announce_between(core, 2, {b.x, b.y - 1.0, b.yaw}, "192.0.2.2", t0, t1);
  stream.run_until(core, (kEmptyRotations + 3) * stream.rotation_ns());

  int for_a = 0;
  int for_b = 0;
  for (const auto& [out, emitted_at] : stream.corrections()) {
    const v2i::Correction& c = out.correction;
    const Pose2& truth = c.vehicle_id == 1 ? a : b;
    EXPECT_LT(distance(c, truth), 0.10) << "vehicle " << c.vehicle_id;
    EXPECT_EQ(out.destination.address, c.vehicle_id == 1 ? "192.0.2.1" : "192.0.2.2");
    (c.vehicle_id == 1 ? for_a : for_b) += 1;
  }
  EXPECT_GE(for_a, 2);
  EXPECT_GE(for_b, 2);
}

// The preparation tests' street: a VLP-32C 2 m up (test_config's mount) and two static cars, ids 1 and 2,
// each announced from just before it appears until `until`, 0.36 m off its place, to every core given.
RsuCoreConfig vlp32c_config() {
  RsuCoreConfig c = test_config();
  c.sensor_model = "vlp32c";
  return c;
}

SimStream two_car_stream(const Pose2& one, const Pose2& two) {
  return SimStream(testing::street_scene(), {static_vehicle(1, one), static_vehicle(2, two)},
                   lidar::make_vlp32c(), testing::roadside_mount(), sim::NoiseModel{}, kEmptyRotations);
}

void announce_two_cars(std::initializer_list<RsuCore*> cores, const Pose2& one, const Pose2& two,
                       const SimStream& stream, TimeNs until) {
  const TimeNs from = kEmptyRotations * stream.rotation_ns() - 100 * kNsPerMs;
  for (RsuCore* core : cores) {
    announce_between(*core, 1, {one.x + 0.3, one.y - 0.2, one.yaw}, "192.0.2.1", from, until);
    announce_between(*core, 2, {two.x - 0.2, two.y + 0.3, two.yaw}, "192.0.2.2", from, until);
  }
}

// Issue 16 (latency): a cluster every laser has swept past is fitted and fixed while the sweep covers the
// angle that closes it (RsuCoreConfig::prepare_fixes), and its release uses that fix only when its inputs
// are the same bit for bit: the corrections, and the packets they leave with, are those without it.
TEST(RsuCore, FixesPreparedAheadAreTheFixesOfTheRelease) {
  const Pose2 near_car =
      beside_mount(-1.5, 5.2, 0.1);  // 5.4 m: the sweep closes it ~10 deg after its last point
  const Pose2 far_car = beside_mount(12.0, -7.0, 0.6);
  RsuCoreConfig config = vlp32c_config();
  config.release_fixed_open = false;  // the preparation alone (released open: the tests below)
  RsuCore prepared(config);
  config.prepare_fixes = false;
  RsuCore computed(config);
  SimStream stream = two_car_stream(near_car, far_car);
  const TimeNs t1 = (kEmptyRotations + 4) * stream.rotation_ns();
  announce_two_cars({&prepared, &computed}, near_car, far_car, stream, t1);
  stream.run_until(prepared, &computed, t1);
  const auto& with = stream.corrections();
  const auto& without = stream.twin_corrections();
  ASSERT_EQ(with.size(), without.size());
  EXPECT_GE(with.size(), 6U);  // both vehicles, every rotation
  for (std::size_t i = 0; i < with.size(); ++i) {
    EXPECT_EQ(with[i].correction.bytes, without[i].correction.bytes) << "correction " << i;
    EXPECT_EQ(with[i].emitted_at, without[i].emitted_at) << "correction " << i;
    EXPECT_LT(distance(with[i].correction.correction,
                       with[i].correction.correction.vehicle_id == 1 ? near_car : far_car),
              0.10);
  }
  // The fixes were ready at the release (7 of 7 when written; the far car's cluster closes ~3 deg past
  // it, which may fall within the packet that swept it last).
  EXPECT_GE(prepared.lidar_stats().fixes_prepared_used, with.size() / 2);
  EXPECT_LE(prepared.lidar_stats().fixes_prepared_used, prepared.lidar_stats().fixes_prepared);
  EXPECT_EQ(computed.lidar_stats().fixes_prepared, 0U);
}

// The same preparation in two halves, prepared on another thread and recorded a packet late (rsud runs
// core::prepare on a thread of its own): the corrections, and the packets they leave with, are still those
// without it, and the prepared fixes are used. What a fixer that a reload replaced prepared is dropped.
TEST(RsuCore, FixesPreparedOnAnotherThreadAreTheFixesOfTheRelease) {
  const Pose2 near_car = beside_mount(-1.5, 5.2, 0.1);
  const Pose2 far_car = beside_mount(12.0, -7.0, 0.6);
  RsuCoreConfig config = vlp32c_config();
  config.release_fixed_open = false;  // the preparation alone (released open: the tests below)
  RsuCore split(config);
  config.prepare_fixes = false;
  RsuCore computed(config);
  SimStream stream = two_car_stream(near_car, far_car);
  const TimeNs t1 = (kEmptyRotations + 4) * stream.rotation_ns();
  const TimeNs t2 = t1 + 2 * stream.rotation_ns();
  announce_two_cars({&split, &computed}, near_car, far_car, stream, t2);
  std::future<Prepared> in_flight;
  std::size_t handed_out = 0;
  stream.run_until(split, &computed, t1, [&](const LidarStepResult&, TimeNs) {
    if (in_flight.valid())
      split.record_prepared(in_flight.get());  // what the previous packet's step handed out
    Preparation p = split.take_preparation();
    if (p.empty())
      return;
    handed_out += p.clusters.size() + p.vehicles.size();
    in_flight =
        std::async(std::launch::async, [p = std::move(p)]() mutable { return prepare(std::move(p)); });
  });
  const auto& with = stream.corrections();
  const auto& without = stream.twin_corrections();
  ASSERT_EQ(with.size(), without.size());
  EXPECT_GE(with.size(), 6U);
  for (std::size_t i = 0; i < with.size(); ++i) {
    EXPECT_EQ(with[i].correction.bytes, without[i].correction.bytes) << "correction " << i;
    EXPECT_EQ(with[i].emitted_at, without[i].emitted_at) << "correction " << i;
  }
  EXPECT_GT(handed_out, with.size());
  EXPECT_GE(split.lidar_stats().fixes_prepared_used, with.size() / 2);
  EXPECT_LE(split.lidar_stats().fixes_prepared_used, split.lidar_stats().fixes_prepared);

  // Handed out, then a reload: the new fixer may compute otherwise, so nothing of the old is kept.
  const std::uint64_t prepared_before = split.lidar_stats().fixes_prepared;
  Preparation late;
  stream.run_until(split, t2, [&](const LidarStepResult&, TimeNs) {
    if (!late.vehicles.empty())
      return;
    Preparation p = split.take_preparation();
    if (!p.empty() && p.vehicles.empty()) {
      split.record_prepared(prepare(std::move(p)));
      p = split.take_preparation();  // the vehicles its fits would release
    }
    if (!p.vehicles.empty())
      late = std::move(p);
  });
  ASSERT_FALSE(late.vehicles.empty());
  split.reload(split.config(), t2);
  split.record_prepared(prepare(std::move(late)));
  EXPECT_EQ(split.lidar_stats().fixes_prepared, 0U);  // a reload restarts the counters; none recorded
  EXPECT_GT(prepared_before, 0U);
}

// A car parked behind a nearer one: its fix is prepared while the nearer car's points, its occluders, are
// still arriving (the sweep holds it until it has passed its footprint), so they differ at the release.
// The prepared fix stands when they answer every question the fix asked of them alike (prepared_fixes.h);
// the corrections, and the packets they leave with, are still those computed at the release.
TEST(RsuCore, FixPreparedBehindAGrowingOccluderStandsWhenItAnswersAlike) {
  const Pose2 parked = beside_mount(15.0, 6.0, 0.0);  // 16 m out
  const Pose2 nearer = beside_mount(5.0, 1.0, 0.2);   // 5 m out, in its line of sight
  RsuCoreConfig config = vlp32c_config();
  config.release_fixed_open = false;  // the preparation alone (released open: the tests below)
  RsuCore prepared(config);
  config.prepare_fixes = false;
  RsuCore computed(config);
  SimStream stream = two_car_stream(parked, nearer);
  const TimeNs t1 = (kEmptyRotations + 4) * stream.rotation_ns();
  announce_two_cars({&prepared, &computed}, parked, nearer, stream, t1);
  stream.run_until(prepared, &computed, t1);
  const auto& with = stream.corrections();
  const auto& without = stream.twin_corrections();
  ASSERT_EQ(with.size(), without.size());
  for (std::size_t i = 0; i < with.size(); ++i) {
    EXPECT_EQ(with[i].correction.bytes, without[i].correction.bytes) << "correction " << i;
    EXPECT_EQ(with[i].emitted_at, without[i].emitted_at) << "correction " << i;
  }
  int for_parked = 0, for_nearer = 0;
  for (const auto& [out, emitted_at] : with) {
    const bool is_parked = out.correction.vehicle_id == 1;
    EXPECT_LT(distance(out.correction, is_parked ? parked : nearer), 0.10)
        << "vehicle " << out.correction.vehicle_id;
    (is_parked ? for_parked : for_nearer) += 1;
  }
  EXPECT_GE(for_parked, 3);
  EXPECT_GE(for_nearer, 3);
  // Every correction's fix was the one prepared (7 of 7 when written; 3 while a prepared fix stood only
  // with the same occluders bit for bit).
  EXPECT_GE(prepared.lidar_stats().fixes_prepared_used, with.size());
  EXPECT_LE(prepared.lidar_stats().fixes_prepared_used, prepared.lidar_stats().fixes_prepared);
}

// Released open (prepared_fixes.h): a near car's cluster goes once its fix is prepared and every laser has
// swept past the fix's box grown by 3 sigma, before the closing angle (10 deg at 5.4 m) has passed. Nothing
// else within the tolerance comes after it here, so each correction is the one the closed cluster gives,
// sent earlier.
TEST(RsuCore, ANearCarIsCorrectedBeforeItsClusterClosesWithTheSameFix) {
  const Pose2 near_car = beside_mount(-1.5, 5.2, 0.1);
  const Pose2 far_car = beside_mount(12.0, -7.0, 0.6);
  RsuCoreConfig config = vlp32c_config();
  RsuCore open(config);
  config.release_fixed_open = false;
  RsuCore closed(config);
  SimStream stream = two_car_stream(near_car, far_car);
  const TimeNs t1 = (kEmptyRotations + 4) * stream.rotation_ns();
  announce_two_cars({&open, &closed}, near_car, far_car, stream, t1);
  stream.run_until(open, &closed, t1);
  const auto& with = stream.corrections();
  const auto& without = stream.twin_corrections();
  ASSERT_EQ(with.size(), without.size());
  EXPECT_GE(with.size(), 6U);
  int near_sooner = 0;
  for (std::size_t i = 0; i < with.size(); ++i) {
    const v2i::Correction& a = with[i].correction.correction;
    const v2i::Correction& b = without[i].correction.correction;
    EXPECT_EQ(a.vehicle_id, b.vehicle_id) << "correction " << i;
    EXPECT_EQ(v2i::encode_v2i_message(a), v2i::encode_v2i_message(b)) << "correction " << i;
    EXPECT_LE(with[i].emitted_at, without[i].emitted_at) << "correction " << i;
    EXPECT_LT(distance(a, a.vehicle_id == 1 ? near_car : far_car), 0.10) << "correction " << i;
    if (a.vehicle_id == 1 && with[i].emitted_at < without[i].emitted_at)
      ++near_sooner;
  }
  EXPECT_GE(near_sooner, 3) << "the near car's corrections, sent before its cluster closed";
  EXPECT_GE(testing::counter(open, "sweep.clusters_released_open"), 3U);
  EXPECT_EQ(testing::counter(closed, "sweep.clusters_released_open"), 0U);
}

// The fault street (tests/integration/scenarios/fault_street.yaml): a VLP-16 2 m up, a lamp post 6.7 m
// away, an SUV 16 m away behind it. The post's shadow cuts the car's rear corner off as a fragment of
// ~13 points, which the sweep releases first; the shadow's edge is not the car's end. Fixed from it as if
// it were, the correction was 3.5 m off stating 0.19 m (fault_rsud_stream_restart): the static scene's
// objects hide parts of vehicles as the sweep's other objects do.
TEST(RsuCore, LampPostShadowIsNotTheVehiclesEnd) {
  sim::Scene scene;
  scene.ground.half_extent_m = 60.0;
  scene.buildings.push_back({.x = 0.0, .y = 22.0, .yaw = 0.0, .length = 50.0, .width = 8.0, .height = 10.0});
  scene.buildings.push_back({.x = 0.0, .y = -20.0, .yaw = 0.0, .length = 50.0, .width = 8.0, .height = 12.0});
  scene.poles.push_back({.x = -6.0, .y = 3.0, .radius = 0.15, .height = 6.0});
  scene.poles.push_back({.x = 9.0, .y = -3.0, .radius = 0.15, .height = 6.0});
  const Pose3 mount{.x = 0.0, .y = 0.0, .z = 2.0, .roll = 0.0, .pitch = 0.0, .yaw = 0.0};
  const Pose2 truth{-13.83, 8.0, 0.0};
  SimStream stream(scene, {static_vehicle(1, truth)}, lidar::make_vlp16(), mount,
                   sim::NoiseModel{.range_sigma_m = 0.02, .angle_sigma_rad = 0.001, .seed = 5},
                   kEmptyRotations);
  // The rotation's own fix (the footprint track off): the fragment is not taken for the car's end. With
  // the track (the twin) the fragment's rotation may be bounded by what the previous rotation saw of the
  // body: then it too must lie within 0.10 m.
  RsuCoreConfig config = test_config();
  config.mount = mount;
  config.footprint_track.enabled = false;
  RsuCore core(config);
  config.footprint_track.enabled = true;
  RsuCore tracked(config);
  const TimeNs t1 = kEmptyRotations * stream.rotation_ns();
  for (RsuCore* c : {&core, &tracked})
    announce_between(*c, 1, {truth.x + 0.3, truth.y - 0.2, truth.yaw + 0.03}, "192.0.2.10",
                     t1 - 100 * kNsPerMs, t1);
  stream.run_until(core, &tracked, t1 + 6 * stream.rotation_ns());
  expect_fixed_from_the_body(stream, truth, 4);
  EXPECT_GE(stream.twin_corrections().size(), stream.corrections().size());
  for (const auto& [out, emitted_at] : stream.twin_corrections())
    EXPECT_LT(distance(out.correction, truth), 0.10) << out.correction.quality.points_used << " points";
}

TEST(RsuCore, FlushReleasesTheClusterStillOpenAtShutdown) {
  const Pose2 truth{17.0, 2.0, 0.4};
  SimStream stream({static_vehicle(1, truth)}, kEmptyRotations);
  RsuCore core(test_config());
  announce_between(core, 1, truth, "192.0.2.10", kEmptyRotations * stream.rotation_ns() - 100 * kNsPerMs,
                   kEmptyRotations * stream.rotation_ns());
  // Stop the stream with the sweep in the middle of the vehicle (bearing ~1.4 deg CCW of the sensor's
  // +x, i.e. just before azimuth 360 deg at the end of the rotation): nothing was released yet.
  const TimeNs stop = (kEmptyRotations + 1) * stream.rotation_ns() - stream.rotation_ns() / 360 * 2;
  stream.run_until(core, stop);
  const std::size_t before = stream.corrections().size();
  const std::uint64_t refused_before = core.lidar_stats().corrections_inconsistent;
  const LidarStepResult drained = core.flush(stop);
  // Half a vehicle: it reaches the correction, which either sends it (the vehicle's, roughly right)
  // or refuses it with a counted reason when the half box does not decide the pose; it is not lost.
  ASSERT_LE(drained.corrections.size(), 1U);
  if (drained.corrections.empty()) {
    EXPECT_EQ(core.lidar_stats().corrections_inconsistent, refused_before + 1);
  } else {
    EXPECT_EQ(drained.corrections[0].correction.vehicle_id, 1U);
    EXPECT_LT(distance(drained.corrections[0].correction, truth), 1.0);
  }
  EXPECT_EQ(before + 0, stream.corrections().size());
}

TEST(RsuCore, ReloadKeepsTheRegistryAndTheLearnedBackground) {
  const Pose2 truth{17.0, 2.0, 0.4};
  SimStream stream({static_vehicle(1, truth)}, kEmptyRotations);
  RsuCore core(test_config());
  const TimeNs t1 = kEmptyRotations * stream.rotation_ns();
  announce_between(core, 1, truth, "192.0.2.10", t1 - 100 * kNsPerMs, t1);
  stream.run_until(core, t1);
  ASSERT_TRUE(core.background_ready());

  RsuCoreConfig next = test_config();
  next.rsu_id = 78;
  next.registry.capacity = 10;  // a registry change: vehicles are re-entered
  const ReloadSummary s = core.reload(next, t1);
  EXPECT_TRUE(s.background_kept);
  EXPECT_EQ(s.vehicles_before, 1U);
  EXPECT_EQ(s.vehicles_after, 1U);
  EXPECT_TRUE(core.background_ready());
  stream.run_until(core, t1 + 2 * stream.rotation_ns());
  ASSERT_FALSE(stream.corrections().empty());
  EXPECT_EQ(stream.corrections().back().correction.correction.rsu_id, 78U);
  EXPECT_LT(distance(stream.corrections().back().correction.correction, truth), 0.10);

  // A broken config is refused and changes nothing; moving the LiDAR drops the background.
  RsuCoreConfig broken = next;
  broken.sensor_model = "vlp99";
  EXPECT_THROW(core.reload(broken, t1), std::invalid_argument);
  EXPECT_EQ(core.config().rsu_id, 78U);
  RsuCoreConfig moved = next;
  moved.mount.x += 1.0;
  EXPECT_FALSE(core.reload(moved, t1).background_kept);
  EXPECT_FALSE(core.background_ready());
  EXPECT_NE(core.registry().find(1, t1), nullptr);
}

TEST(RsuCore, RejectsUnusableConfigurations) {
  RsuCoreConfig c = test_config();
  c.sensor_model = "generic64";  // no packet format
  EXPECT_THROW(RsuCore{c}, std::invalid_argument);
  c = test_config();
  c.mount.z = std::numeric_limits<double>::infinity();
  EXPECT_THROW(RsuCore{c}, std::invalid_argument);
}

// A packet of the VLP-16 with no returns, first firing at t (azimuths advancing as the sensor's would).
std::array<std::uint8_t, lidar::kPacketBytes> empty_packet(TimeNs t) {
  lidar::PacketReturns r;
  r.blocks.first_firing_ns = t;
  for (std::size_t b = 0; b < r.blocks.azimuth_cdeg.size(); ++b)
    r.blocks.azimuth_cdeg[b] = static_cast<std::uint16_t>(40 * b);
  std::array<std::uint8_t, lidar::kPacketBytes> payload{};
  lidar::encode_packet(*lidar::sensor_model_by_name("vlp16"), r, payload);
  return payload;
}

TEST(RsuCore, PacketsProcessedTooLateAreShedNotFixedFrom) {
  RsuCoreConfig config = test_config();
  config.max_packet_age = 150 * kNsPerMs;
  RsuCore core(config);
  const TimeNs t = 10 * kNsPerSecond;
  core.on_lidar_packet(empty_packet(t), t + 2 * kNsPerMs);                // on time
  core.on_lidar_packet(empty_packet(t + 1'327'000), t + 149 * kNsPerMs);  // behind, within the limit
  core.on_lidar_packet(empty_packet(t + 2'654'000), t + 2'654'000 + 151 * kNsPerMs);  // too late
  EXPECT_EQ(counter(core, "packet.accepted"), 3U);
  EXPECT_EQ(core.lidar_stats().packets_too_late, 1U);
  config.max_packet_age = 0;  // never shed
  RsuCore patient(config);
  patient.on_lidar_packet(empty_packet(t), t + 10 * kNsPerSecond);
  EXPECT_EQ(patient.lidar_stats().packets_too_late, 0U);
}

// A sensor whose clock is 52 s behind the host's (as in a real capture): with time_source sensor every
// packet is refused as clock_offset (not silently shed as too late) and one notice says so and what to
// do; with host_receive the packets are stamped by arrival and used.
TEST(RsuCore, ASensorClockFarOffIsRefusedLoudlyOrStampedByArrival) {
  const TimeNs offset = 52 * kNsPerSecond;
  const TimeNs t = 100 * kNsPerSecond;
  for (const TimeSource source : {TimeSource::kSensor, TimeSource::kHostReceive}) {
    RsuCoreConfig config = test_config();
    config.time_source = source;
    RsuCore core(config);
    for (int k = 0; k < 20; ++k) {
      const TimeNs first = t + k * 1'327'104;
      core.on_lidar_packet(empty_packet(first), first + offset + 2 * kNsPerMs);
    }
    const bool refused = source == TimeSource::kSensor;
    EXPECT_EQ(counter(core, "packet.accepted"), 20U);
    EXPECT_EQ(counter(core, "packet.clock_offset"), refused ? 20U : 0U);
    EXPECT_EQ(counter(core, "packet.too_late"), 0U);
    ASSERT_TRUE(core.sensor_clock().known);
    EXPECT_NEAR(static_cast<double>(core.sensor_clock().offset_ns),
                static_cast<double>(offset + 2 * kNsPerMs - 1'327'104), 1e3);
    EXPECT_TRUE(core.sensor_clock().beyond_tolerance);
    const std::vector<std::string> notices = core.take_lidar_notices();
    ASSERT_EQ(notices.size(), 1U);
    EXPECT_NE(notices[0].find("52.001 s behind the host's"), std::string::npos) << notices[0];
    EXPECT_EQ(notices[0].find("REFUSED") != std::string::npos, refused) << notices[0];
    EXPECT_TRUE(core.take_lidar_notices().empty());  // once
    // The sensor's clock is set right: said once more, and its packets are used.
    for (int k = 20; k < 25; ++k) {
      const TimeNs first = t + offset + k * 1'327'104;
      core.on_lidar_packet(empty_packet(first), first + 2 * kNsPerMs);
    }
    EXPECT_EQ(counter(core, "packet.clock_offset"), refused ? 20U : 0U);
    const std::vector<std::string> again = core.take_lidar_notices();
    ASSERT_EQ(again.size(), 1U);
    EXPECT_NE(again[0].find("within"), std::string::npos) << again[0];
  }
}

TEST(RsuCore, GarbageLidarPacketsAreCountedNotFatal) {
  RsuCore core(test_config());
  std::vector<std::uint8_t> short_packet(100, 0xff);
  std::vector<std::uint8_t> junk(lidar::kPacketBytes, 0x00);
  EXPECT_TRUE(core.on_lidar_packet(short_packet, 0).corrections.empty());
  EXPECT_TRUE(core.on_lidar_packet(junk, 0).corrections.empty());
  EXPECT_EQ(counter(core, "packet.wrong_size"), 1U);
  EXPECT_EQ(counter(core, "packet.unknown_product"), 1U);  // all zeros: product byte 0
  EXPECT_EQ(core.lidar_decoder().packets_seen(), 2U);
}

// A daemon too slow for its LiDAR loses packets in bursts (the kernel drops them at its full socket
// buffer): a rotation that lacked many of them is not checked by the mount monitor (mount.rotations_gappy)
// and never stops the fixes of a still sensor; one with a few lost (network loss) is checked on what it has.
TEST(RsuCore, RotationsLackingManyPacketsAreNoMountEvidence) {
  RsuCore core(test_config());
  const sim::LidarSimulator lidar(lidar::make_vlp16(), testing::roadside_mount(), sim::NoiseModel{},
                                  testing::street_scene());
  const std::int64_t per_rotation = lidar.packet_index_at(lidar.rotation_period_ns());  // 75
  std::array<std::uint8_t, lidar::kPacketBytes> payload{};
  int bursts = 0;
  for (std::int64_t k = 0; k < 16 * per_rotation; ++k) {
    const std::int64_t rotation = k / per_rotation;
    const std::int64_t at = k % per_rotation;
    // After learning and a whole rotation: every other rotation loses 40 % of its packets in one burst,
    // the others two.
    const bool burst =
        rotation >= 7 && rotation % 2 == 1 && at >= per_rotation / 4 && at < per_rotation * 13 / 20;
    const bool few = rotation >= 7 && rotation % 2 == 0 && (at == 10 || at == 40);
    if (burst || few) {
      bursts += burst && at == per_rotation / 4 ? 1 : 0;
      continue;
    }
    const lidar::PacketReturns r = lidar.simulate_packet(k);
    lidar::encode_packet(lidar.model(), r, payload);
    core.on_lidar_packet(payload, r.blocks.first_firing_ns + 1'400'000);
  }
  EXPECT_EQ(bursts, 5);
  EXPECT_GT(counter(core, "packet.lost"), 5U * 30U);
  // Each burst's rotation skipped (and at most the next, when the burst is counted late).
  EXPECT_GE(counter(core, "mount.rotations_gappy"), 4U);
  EXPECT_LE(counter(core, "mount.rotations_gappy"), 6U);
  EXPECT_GE(counter(core, "mount.rotations_checked"), 6U);  // the whole ones and those that lost two
  EXPECT_EQ(counter(core, "mount.rotations_mismatched"), 0U);
  EXPECT_EQ(counter(core, "mount.stops"), 0U);
  EXPECT_TRUE(core.mount_serving());
}

// A LiDAR remounted while rsud was down (issue 17): the background saved under the old mount is loaded as
// the reference, and the moved sensor's first rotations stop the fixes; the advertisement says so and
// why. The same sensor unmoved keeps serving and advertises that it does.
// Three rotations of the street seen from the roadside mount, as an earlier run saved them.
std::vector<std::vector<lidar::LidarPoint>> saved_background() {
  std::vector<std::vector<lidar::LidarPoint>> saved;
  const sim::LidarSimulator still(lidar::make_vlp16(), testing::roadside_mount(), sim::NoiseModel{},
                                  testing::street_scene());
  for (int k = 0; k < 3; ++k)
    saved.push_back(still.simulate_frame(k * still.rotation_period_ns()).frame.points);
  return saved;
}

TEST(RsuCore, RemountNoticedAtStartUpAndAdvertised) {
  const std::vector<std::vector<lidar::LidarPoint>> saved = saved_background();
  for (const double turn_deg : {0.0, 1.0}) {
    RsuCore core(test_config());
    core.load_background(saved);
    Pose3 now_at = testing::roadside_mount();
    now_at.yaw += deg_to_rad(turn_deg);
    SimStream stream(testing::street_scene(), {}, lidar::make_vlp16(), now_at, sim::NoiseModel{}, 100);
    const TimeNs end = 8 * stream.rotation_ns();
    stream.run_until(core, end);
    const v2i::DecodedMessage m = v2i::decode_v2i_message(core.advertisement(end));
    ASSERT_EQ(m.status, v2i::DecodeStatus::kOk);
    const auto& ad = std::get<v2i::RsuAdvertisement>(m.body);
    EXPECT_GT(counter(core, "mount.rotations_checked"), 5U);
    if (turn_deg == 0.0) {
      EXPECT_TRUE(core.mount_serving());
      EXPECT_EQ(ad.fixes_withheld, v2i::FixesWithheld::kNone);
      EXPECT_EQ(counter(core, "mount.stops"), 0U);
      continue;
    }
    EXPECT_FALSE(core.mount_serving());
    // This corner (one facade, one pole) cannot verify 5 cm at 50 m: the turn is suspected, not confirmed.
    EXPECT_EQ(ad.fixes_withheld, v2i::FixesWithheld::kMountSuspected);
    // Beyond the tolerance (0.05 m), though short of the truth (0.87 m at 50 m): the direction this
    // corner holds weakly is not estimated (mount_monitor.cpp, held_step).
    EXPECT_GT(ad.mount_error_at_radius_m, core.config().mount_monitor.max_position_error_m);
    EXPECT_LT(ad.mount_error_at_radius_m, 1.0);
    EXPECT_EQ(counter(core, "mount.stops"), 1U);
    const std::vector<std::string> notices = core.take_lidar_notices();
    ASSERT_FALSE(notices.empty());
    EXPECT_NE(notices.back().find("fixes stopped"), std::string::npos) << notices.back();
  }
}

// A vehicle fixed while the LiDAR has turned (the remount above) is told its fix is withheld for the
// mount, and why (the advertisement's cause), not the fix's sigma: that leaves the mount's error out.
TEST(RsuCore, VehicleWithheldForTheMountIsToldSo) {
  RsuCore core(test_config());
  core.load_background(saved_background());
  Pose3 turned = testing::roadside_mount();
  turned.yaw += deg_to_rad(1.0);
  const Pose2 truth{17.0, 2.0, 0.4};
  SimStream stream(testing::street_scene(), {static_vehicle(1, truth)}, lidar::make_vlp16(), turned,
                   sim::NoiseModel{}, 0);
  const TimeNs end = 12 * stream.rotation_ns();
  announce_between(core, 1, truth, "192.0.2.10", 0, end);
  NoticesSent notices;
  stream.run_until(core, end, notices.recorder());
  ASSERT_FALSE(core.mount_serving());
  EXPECT_GT(core.lidar_stats().corrections_withheld_mount, 0U);
  ASSERT_FALSE(notices.sent.empty());
  const v2i::FixWithheld& n = notices.sent.front().first.notice;
  EXPECT_EQ(n.reason, v2i::FixWithheldReason::kMount);
  EXPECT_EQ(n.mount_cause, v2i::FixesWithheld::kMountSuspected);
  EXPECT_FALSE(n.position_sigma_m.has_value());
  EXPECT_EQ(counter(core, "withheld_notice.mount"), notices.sent.size());
  // Sent before the stop (its first rotations), withheld after it: never both in one rotation.
  for (const auto& [out, emitted_at] : stream.corrections())
    EXPECT_LT(out.correction.sweep_time, n.sweep_time);
}

// The mount check in two halves, the rotations registered on another thread (rsud does so: issue 16's
// latency): the same verdicts as the check within the steps, and nothing recorded against a reference
// that a reload with a new mount has replaced.
MountChecks check_on_a_thread(MountRotations taken) {
  return std::async(std::launch::async, [&taken] { return check_mount_rotations(std::move(taken)); }).get();
}

TEST(RsuCore, MountCheckedOnAnotherThreadDecidesAsWithinTheSteps) {
  Pose3 turned = testing::roadside_mount();
  turned.yaw += deg_to_rad(1.0);
  RsuCore within(test_config());
  RsuCore split(test_config());
  within.load_background(saved_background());
  split.load_background(saved_background());
  SimStream a(testing::street_scene(), {}, lidar::make_vlp16(), turned, sim::NoiseModel{}, 100);
  SimStream b(testing::street_scene(), {}, lidar::make_vlp16(), turned, sim::NoiseModel{}, 100);
  const TimeNs end = 8 * a.rotation_ns();
  a.run_until(within, end);
  within.check_mount_pending();
  std::size_t taken_rotations = 0;
  b.run_until(split, end, [&](const LidarStepResult&, TimeNs) {
    MountRotations taken = split.take_mount_rotations();
    // A job (a reference or a source: rsud submits one for either) only with rotations to check.
    EXPECT_EQ(taken.rotations.empty(), !taken.reference && !taken.source);
    if (taken.rotations.empty())
      return;
    taken_rotations += taken.rotations.size();
    split.record_mount_checks(check_on_a_thread(std::move(taken)));
  });
  EXPECT_EQ(split.take_mount_rotations().rotations.size(), 0U);  // nothing left for the steps
  EXPECT_GT(taken_rotations, 5U);
  EXPECT_EQ(counter(split, "mount.rotations_checked"), taken_rotations);
  EXPECT_EQ(counter(split, "mount.rotations_checked"), counter(within, "mount.rotations_checked"));
  EXPECT_EQ(counter(split, "mount.stops"), 1U);
  EXPECT_EQ(counter(within, "mount.stops"), 1U);
  EXPECT_FALSE(split.mount_serving());
  EXPECT_EQ(split.mount_monitor()->last().error_at_radius_m,
            within.mount_monitor()->last().error_at_radius_m);

  // A rotation taken, then a reload with another mount (a recalibration: a new reference to come).
  RsuCore remounted(test_config());
  remounted.load_background(saved_background());
  SimStream c(testing::street_scene(), {}, lidar::make_vlp16(), turned, sim::NoiseModel{}, 100);
  MountRotations taken;
  c.run_until(remounted, end, [&](const LidarStepResult&, TimeNs) {
    if (taken.rotations.empty())
      taken = remounted.take_mount_rotations();
  });
  ASSERT_FALSE(taken.rotations.empty());
  RsuCoreConfig next = test_config();
  next.mount.yaw += deg_to_rad(1.0);
  remounted.reload(next, end);
  remounted.record_mount_checks(check_on_a_thread(std::move(taken)));
  EXPECT_EQ(counter(remounted, "mount.rotations_checked"), 0U);  // dropped, not recorded
}

// A reference saved by an earlier run may belong to a LiDAR that has moved while rsud was down: no fix
// goes out before a rotation has been checked against it and read within the tolerance
// (RsuCore::mount_unverified_). Before, a restarted rsud sent the fixes of the rotations before its first
// check, from a LiDAR leaned 0.36 deg since: one 3.1 sigma off (rsud_faults.py mount_lean under load).
// The same sensor unmoved is served from then on.
TEST(RsuCore, SavedReferenceServesOnceChecked) {
  RsuCore core(test_config());
  core.load_background(saved_background(), true);
  EXPECT_FALSE(core.mount_serving());
  const Pose2 truth{17.0, 2.0, 0.4};
  SimStream stream(testing::street_scene(), {static_vehicle(1, truth)}, lidar::make_vlp16(),
                   testing::roadside_mount(), sim::NoiseModel{}, 0);
  const TimeNs end = 8 * stream.rotation_ns();
  announce_between(core, 1, truth, "192.0.2.10", 0, end);
  std::vector<std::uint64_t> checked_when_sent;
  stream.run_until(core, end, [&](const LidarStepResult& r, TimeNs) {
    if (!r.corrections.empty())
      checked_when_sent.push_back(counter(core, "mount.rotations_checked"));
  });
  EXPECT_TRUE(core.mount_serving());
  EXPECT_EQ(counter(core, "mount.stops"), 0U);
  ASSERT_GE(checked_when_sent.size(), 4U);  // still: served
  EXPECT_GE(checked_when_sent.front(), 1U);
  EXPECT_GT(core.lidar_stats().corrections_withheld_mount, 0U);  // the vehicle's fix before the check
}

}  // namespace
}  // namespace rsu::core
