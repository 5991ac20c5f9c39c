// SPDX-License-Identifier: Apache-2.0
#include "v2i/announcement_validation.h"

#include <gtest/gtest.h>

#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "test_announcement.h"

namespace rsu::v2i {
namespace {

constexpr TimeNs kNow = 1'700'000'000 * kNsPerSecond;

struct Case {
  std::string name;
  std::function<void(VehicleAnnouncement&)> mutate;
  AnnouncementReason expected;
};

TEST(AnnouncementValidation, PlausibleAnnouncementIsValid) {
  const VehicleAnnouncement a = testing::make_announcement(7, 1, kNow - 50 * kNsPerMs);
  EXPECT_EQ(validate_announcement(a, kNow), AnnouncementReason::kValid);
  VehicleAnnouncement no_motion = a;
  no_motion.speed_mps.reset();
  no_motion.yaw_rate_rps.reset();
  EXPECT_EQ(validate_announcement(no_motion, kNow), AnnouncementReason::kValid);
  VehicleAnnouncement ipv6 = a;
  ipv6.reply_to.address = "2001:db8::17";
  EXPECT_EQ(validate_announcement(ipv6, kNow), AnnouncementReason::kValid);
}

TEST(AnnouncementValidation, EachDefectHasItsReason) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  using R = AnnouncementReason;
  const std::vector<Case> cases = {
      {"version 0 (absent)", [](auto& a) { a.protocol_version = 0; }, R::kUnsupportedVersion},
      {"version 1", [](auto& a) { a.protocol_version = 1; }, R::kUnsupportedVersion},
      {"version 3", [](auto& a) { a.protocol_version = 3; }, R::kUnsupportedVersion},
      {"id 0", [](auto& a) { a.vehicle_id = 0; }, R::kMissingVehicleId},
      {"NaN x", [nan](auto& a) { a.pose.x = nan; }, R::kNonFinite},
      {"inf length", [inf](auto& a) { a.size.length_m = inf; }, R::kNonFinite},
      {"NaN covariance", [nan](auto& a) { a.pose_covariance(1, 2) = nan; }, R::kNonFinite},
      {"NaN speed", [nan](auto& a) { a.speed_mps = nan; }, R::kNonFinite},
      {"NaN offset", [nan](auto& a) { a.reference_offset.y() = nan; }, R::kNonFinite},
      {"length 0.5", [](auto& a) { a.size.length_m = 0.5; }, R::kLengthOutOfRange},
      {"length 30", [](auto& a) { a.size.length_m = 30.0; }, R::kLengthOutOfRange},
      {"negative length", [](auto& a) { a.size.length_m = -4.0; }, R::kLengthOutOfRange},
      {"width 0.2", [](auto& a) { a.size.width_m = 0.2; }, R::kWidthOutOfRange},
      {"width 6",
       [](auto& a) {
         a.size.width_m = 6.0;
         a.size.length_m = 12.0;
       },
       R::kWidthOutOfRange},
      {"height 9", [](auto& a) { a.size.height_m = 9.0; }, R::kHeightOutOfRange},
      {"wider than long",
       [](auto& a) {
         a.size.length_m = 2.0;
         a.size.width_m = 2.5;
         a.reference_offset = {0.0, 0.0};
       },
       R::kWiderThanLong},
      {"offset beyond the bumper",
       [](auto& a) {
         a.reference_offset = {-3.5, 0.0};
       },
       R::kReferenceOffsetOutsideBox},
      {"offset beside the car",
       [](auto& a) {
         a.reference_offset = {0.0, 1.6};
       },
       R::kReferenceOffsetOutsideBox},
      {"x 1e8", [](auto& a) { a.pose.x = 1e8; }, R::kPositionOutOfRange},
      {"yaw 1e3", [](auto& a) { a.pose.yaw = 1e3; }, R::kYawOutOfRange},
      {"asymmetric covariance", [](auto& a) { a.pose_covariance(0, 1) = 0.02; }, R::kCovarianceInvalid},
      {"zero variance", [](auto& a) { a.pose_covariance(2, 2) = 0.0; }, R::kCovarianceInvalid},
      {"indefinite covariance",
       [](auto& a) {
         a.pose_covariance(0, 1) = a.pose_covariance(1, 0) = 0.3;  // |corr| > 1
       },
       R::kCovarianceInvalid},
      {"sigma 100 m", [](auto& a) { a.pose_covariance(0, 0) = 1e4; }, R::kCovarianceTooLarge},
      {"speed 100 m/s", [](auto& a) { a.speed_mps = 100.0; }, R::kSpeedOutOfRange},
      {"reverse 30 m/s", [](auto& a) { a.speed_mps = -30.0; }, R::kSpeedOutOfRange},
      {"yaw rate 5", [](auto& a) { a.yaw_rate_rps = -5.0; }, R::kYawRateOutOfRange},
      {"2 s old", [](auto& a) { a.generation_time = kNow - 2 * kNsPerSecond; }, R::kTooOld},
      {"time 0", [](auto& a) { a.generation_time = 0; }, R::kTooOld},
      {"time min", [](auto& a) { a.generation_time = std::numeric_limits<TimeNs>::min(); }, R::kTooOld},
      {"1 s ahead", [](auto& a) { a.generation_time = kNow + kNsPerSecond; }, R::kFromFuture},
      {"time max", [](auto& a) { a.generation_time = std::numeric_limits<TimeNs>::max(); }, R::kFromFuture},
      {"host name", [](auto& a) { a.reply_to.address = "car.example"; }, R::kReplyAddressInvalid},
      {"empty address", [](auto& a) { a.reply_to.address.clear(); }, R::kReplyAddressInvalid},
      {"broadcast", [](auto& a) { a.reply_to.address = "255.255.255.255"; }, R::kReplyAddressInvalid},
      {"multicast v4", [](auto& a) { a.reply_to.address = "239.1.2.3"; }, R::kReplyAddressInvalid},
      {"unspecified v6", [](auto& a) { a.reply_to.address = "::"; }, R::kReplyAddressInvalid},
      {"multicast v6", [](auto& a) { a.reply_to.address = "ff02::1"; }, R::kReplyAddressInvalid},
      {"multicast v4, mapped", [](auto& a) { a.reply_to.address = "::ffff:239.1.2.3"; },
       R::kReplyAddressInvalid},
      {"broadcast, mapped", [](auto& a) { a.reply_to.address = "::ffff:255.255.255.255"; },
       R::kReplyAddressInvalid},
      {"embedded NUL", [](auto& a) { a.reply_to.address = std::string("192.0.2.1\0x", 11); },
       R::kReplyAddressInvalid},
      {"port 0", [](auto& a) { a.reply_to.port = 0; }, R::kReplyPortInvalid},
      {"port 70000", [](auto& a) { a.reply_to.port = 70000; }, R::kReplyPortInvalid},
  };
  for (const Case& c : cases) {
    VehicleAnnouncement a = testing::make_announcement(7, 1, kNow - 50 * kNsPerMs);
    c.mutate(a);
    EXPECT_EQ(validate_announcement(a, kNow), c.expected)
        << c.name << ": got " << to_string(validate_announcement(a, kNow)) << ", expected "
        << to_string(c.expected);
  }
}

TEST(AnnouncementValidation, LimitsAreInclusiveAtTheirEdges) {
  VehicleAnnouncement a = testing::make_announcement(7, 1, kNow);
  a.size = {25.0, 5.0, 6.0};
  EXPECT_EQ(validate_announcement(a, kNow), AnnouncementReason::kValid);
  a.size = {1.0, 0.5, 0.5};
  a.reference_offset = {0.0, 0.0};
  EXPECT_EQ(validate_announcement(a, kNow), AnnouncementReason::kValid);
  a.generation_time = kNow - kNsPerSecond;
  EXPECT_EQ(validate_announcement(a, kNow), AnnouncementReason::kValid);
  a.generation_time = kNow - kNsPerSecond - 1;
  EXPECT_EQ(validate_announcement(a, kNow), AnnouncementReason::kTooOld);
}

// fault_rsud_clock_offset under load: rsud read a vehicle's announcements 600 ms ahead of its clock
// after they had waited 0.4-1.4 s in the socket behind a stalled loop, and took them for 200 ms ahead
// or less. How far ahead is judged at their arrival; how old, when they are used.
TEST(AnnouncementValidation, FutureJudgedAtArrivalAgeWhenUsed) {
  const TimeNs received = kNow;
  const TimeNs read_late = kNow + 500 * kNsPerMs;  // waited 0.5 s for the receiver
  VehicleAnnouncement ahead = testing::make_announcement(7, 1, received + 600 * kNsPerMs);
  EXPECT_EQ(validate_announcement(ahead, read_late), AnnouncementReason::kValid);  // judged when read
  EXPECT_EQ(validate_announcement(ahead, read_late, {}, received), AnnouncementReason::kFromFuture);
  ahead.generation_time = received + 200 * kNsPerMs;  // the limit itself: accepted
  EXPECT_EQ(validate_announcement(ahead, read_late, {}, received), AnnouncementReason::kValid);
  // 800 ms behind, read 0.5 s late: 1.3 s old when used, too old though it came in at 0.8 s.
  const VehicleAnnouncement behind = testing::make_announcement(7, 1, received - 800 * kNsPerMs);
  EXPECT_EQ(validate_announcement(behind, read_late, {}, received), AnnouncementReason::kTooOld);
  EXPECT_EQ(validate_announcement(behind, received, {}, received), AnnouncementReason::kValid);
  // An arrival after the judging time (the clock stepped back between the two): judged at `now`.
  const VehicleAnnouncement early = testing::make_announcement(7, 1, kNow + 300 * kNsPerMs);
  EXPECT_EQ(validate_announcement(early, kNow, {}, kNow + kNsPerSecond), AnnouncementReason::kFromFuture);
  AnnouncementValidator validator;
  ahead.generation_time = received + 600 * kNsPerMs;
  EXPECT_EQ(validator.check(ahead, read_late, received), AnnouncementReason::kFromFuture);
  EXPECT_EQ(validator.counts().count(AnnouncementReason::kFromFuture), 1U);
}

TEST(AnnouncementValidation, ValidatorCountsByReason) {
  AnnouncementValidator validator;
  VehicleAnnouncement good = testing::make_announcement(7, 1, kNow);
  VehicleAnnouncement bad = good;
  bad.size.length_m = 100.0;
  for (int i = 0; i < 3; ++i) {
    validator.check(good, kNow);
  }
  validator.check(bad, kNow);
  EXPECT_EQ(validator.counts().count(AnnouncementReason::kValid), 3U);
  EXPECT_EQ(validator.counts().count(AnnouncementReason::kLengthOutOfRange), 1U);
  EXPECT_EQ(validator.counts().total(), 4U);
}

}  // namespace
}  // namespace rsu::v2i
