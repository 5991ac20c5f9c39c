// SPDX-License-Identifier: Apache-2.0
// Sanity checks of a decoded VehicleAnnouncement before it may touch the registry. Every rejection has
// a reason, so the daemon can count what arrives (and from whom) instead of crashing or guessing.
#pragma once

#include <cstdint>
#include <optional>

#include "common/angles.h"
#include "common/enum_counter.h"
#include "common/time.h"
#include "v2i/messages.h"

namespace rsu::v2i {

// Plausibility limits. Wide enough for any road vehicle, narrow enough that a garbage number is not
// silently turned into an association gate or a rectangle to fit.
struct AnnouncementLimits {
  // Motorcycles are about 2 m long and 0.7 m wide; EU modular truck combinations reach 25.25 m and
  // escorted wide loads about 5 m. The RSU's size correction (paper Algorithm 1) treats length as the
  // longer edge, so a vehicle wider than long is refused too.
  double min_length_m = 1.0;
  double max_length_m = 25.0;
  double min_width_m = 0.5;
  double max_width_m = 5.0;
  // Low sports cars are about 1.1 m high; legal limits are 4 to 4.3 m, high loads a little more.
  double min_height_m = 0.5;
  double max_height_m = 6.0;
  // The reference point (rear axle, GNSS antenna) lies on the vehicle; a tow hitch sits a little
  // behind the body, hence the margin around the footprint box.
  double reference_offset_margin_m = 0.5;
  // Map coordinates: a local ENU/MGRS frame spans kilometres, but UTM northings reach 1e7 m, so only
  // values beyond the Earth's size are refused.
  double max_abs_coordinate_m = 1.0e7;
  // The wire says (-pi, pi]; a little wrap slop is tolerated, nonsense like 1e9 rad is not.
  double max_abs_yaw_rad = 2.0 * kPi;
  // A pose claiming more uncertainty than this is not an estimate; gating on it would match anything.
  double max_position_sigma_m = 50.0;
  double max_yaw_sigma_rad = kPi;
  // 70 m/s = 252 km/h, above any road speed limit; reversing is slower.
  double max_speed_mps = 70.0;
  double max_reverse_speed_mps = 20.0;
  // A car at its 5 m minimum turning radius and 10 m/s turns at 2 rad/s.
  double max_abs_yaw_rate_rps = 3.0;
  // Announcements come at about 10 Hz; one older than this says little about where the vehicle is
  // now. "Future" allows for clock synchronisation error between vehicle and RSU.
  TimeNs max_age = 1 * kNsPerSecond;
  TimeNs max_future = 200 * kNsPerMs;
};

enum class AnnouncementReason : std::uint8_t {
  kValid,
  kUnsupportedVersion,
  kMissingVehicleId,  // vehicle_id 0 (proto3 default: the field was absent)
  kNonFinite,         // NaN or inf in any number
  kLengthOutOfRange,
  kWidthOutOfRange,
  kHeightOutOfRange,
  kWiderThanLong,
  kReferenceOffsetOutsideBox,
  kPositionOutOfRange,
  kYawOutOfRange,
  kCovarianceInvalid,  // not symmetric, not positive definite, or a variance <= 0
  kCovarianceTooLarge,
  kSpeedOutOfRange,
  kYawRateOutOfRange,
  kTooOld,
  kFromFuture,
  kReplyAddressInvalid,  // not a numeric unicast IPv4/IPv6 address
  kReplyPortInvalid,
  kCount,
};

const char* to_string(AnnouncementReason reason);

// Checks one announcement judged at `now` (common clock) that came off the wire at `received` (none:
// `now`). Its age (max_age) is judged at `now`, what it is worth when used; how far ahead of our clock
// it was generated (max_future: the sender's clock) at `received`, so that a receiver that falls behind
// does not let an announcement from a clock too far ahead pass once it has waited long enough.
AnnouncementReason validate_announcement(const VehicleAnnouncement& announcement, TimeNs now,
                                         const AnnouncementLimits& limits = {},
                                         std::optional<TimeNs> received = std::nullopt);

// True when `address` is a numeric IPv4 or IPv6 literal of a unicast host (not unspecified,
// multicast or broadcast), so corrections cannot be aimed at a whole network.
bool is_unicast_ip_literal(const std::string& address);

// Validates and counts by reason: the daemon keeps one of these.
class AnnouncementValidator {
 public:
  explicit AnnouncementValidator(const AnnouncementLimits& limits = {}) : limits_(limits) {}

  AnnouncementReason check(const VehicleAnnouncement& announcement, TimeNs now,
                           std::optional<TimeNs> received = std::nullopt) {
    const AnnouncementReason reason = validate_announcement(announcement, now, limits_, received);
    counts_.add(reason);
    return reason;
  }
  const EnumCounter<AnnouncementReason>& counts() const { return counts_; }
  const AnnouncementLimits& limits() const { return limits_; }

 private:
  AnnouncementLimits limits_;
  EnumCounter<AnnouncementReason> counts_;
};

}  // namespace rsu::v2i
