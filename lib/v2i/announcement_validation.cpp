// SPDX-License-Identifier: Apache-2.0
#include "v2i/announcement_validation.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>

#include "v2i/ip_literal.h"

namespace rsu::v2i {
namespace {

bool all_finite(const VehicleAnnouncement& a) {
  const std::array<double, 8> values = {
      a.size.length_m,        a.size.width_m, a.size.height_m, a.reference_offset.x(),
      a.reference_offset.y(), a.pose.x,       a.pose.y,        a.pose.yaw};
  for (const double v : values) {
    if (!std::isfinite(v)) {
      return false;
    }
  }
  return a.pose_covariance.allFinite() && (!a.speed_mps || std::isfinite(*a.speed_mps)) &&
         (!a.yaw_rate_rps || std::isfinite(*a.yaw_rate_rps));
}

bool in_range(double v, double lo, double hi) {
  return v >= lo && v <= hi;
}

// now - t, saturated instead of overflowing for garbage times.
TimeNs saturating_age(TimeNs t, TimeNs now) {
  TimeNs age = 0;
  if (__builtin_sub_overflow(now, t, &age)) {
    return now > t ? std::numeric_limits<TimeNs>::max() : std::numeric_limits<TimeNs>::min();
  }
  return age;
}

AnnouncementReason check_covariance(const Eigen::Matrix3d& c, const AnnouncementLimits& limits) {
  const double scale = c.cwiseAbs().maxCoeff();
  if (!((c - c.transpose()).cwiseAbs().maxCoeff() <= 1e-9 * scale)) {
    return AnnouncementReason::kCovarianceInvalid;
  }
  if (!(c(0, 0) > 0.0 && c(1, 1) > 0.0 && c(2, 2) > 0.0)) {
    return AnnouncementReason::kCovarianceInvalid;
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen;
  eigen.computeDirect(c, Eigen::EigenvaluesOnly);
  if (!(eigen.eigenvalues().minCoeff() > 0.0)) {
    return AnnouncementReason::kCovarianceInvalid;
  }
  const double max_position_var = limits.max_position_sigma_m * limits.max_position_sigma_m;
  if (c(0, 0) > max_position_var || c(1, 1) > max_position_var ||
      c(2, 2) > limits.max_yaw_sigma_rad * limits.max_yaw_sigma_rad) {
    return AnnouncementReason::kCovarianceTooLarge;
  }
  return AnnouncementReason::kValid;
}

}  // namespace

const char* to_string(AnnouncementReason reason) {
  switch (reason) {
    case AnnouncementReason::kValid:
      return "valid";
    case AnnouncementReason::kUnsupportedVersion:
      return "unsupported_version";
    case AnnouncementReason::kMissingVehicleId:
      return "missing_vehicle_id";
    case AnnouncementReason::kNonFinite:
      return "non_finite";
    case AnnouncementReason::kLengthOutOfRange:
      return "length_out_of_range";
    case AnnouncementReason::kWidthOutOfRange:
      return "width_out_of_range";
    case AnnouncementReason::kHeightOutOfRange:
      return "height_out_of_range";
    case AnnouncementReason::kWiderThanLong:
      return "wider_than_long";
    case AnnouncementReason::kReferenceOffsetOutsideBox:
      return "reference_offset_outside_box";
    case AnnouncementReason::kPositionOutOfRange:
      return "position_out_of_range";
    case AnnouncementReason::kYawOutOfRange:
      return "yaw_out_of_range";
    case AnnouncementReason::kCovarianceInvalid:
      return "covariance_invalid";
    case AnnouncementReason::kCovarianceTooLarge:
      return "covariance_too_large";
    case AnnouncementReason::kSpeedOutOfRange:
      return "speed_out_of_range";
    case AnnouncementReason::kYawRateOutOfRange:
      return "yaw_rate_out_of_range";
    case AnnouncementReason::kTooOld:
      return "too_old";
    case AnnouncementReason::kFromFuture:
      return "from_future";
    case AnnouncementReason::kReplyAddressInvalid:
      return "reply_address_invalid";
    case AnnouncementReason::kReplyPortInvalid:
      return "reply_port_invalid";
    case AnnouncementReason::kCount:
      break;
  }
  return "unknown";
}

bool is_unicast_ip_literal(const std::string& address) {
  const std::optional<IpLiteral> literal = parse_ip_literal(address);
  return literal && is_unicast(*literal);
}

AnnouncementReason validate_announcement(const VehicleAnnouncement& a, TimeNs now,
                                         const AnnouncementLimits& limits, std::optional<TimeNs> received) {
  if (a.protocol_version != kProtocolVersion) {
    return AnnouncementReason::kUnsupportedVersion;
  }
  if (a.vehicle_id == 0) {
    return AnnouncementReason::kMissingVehicleId;
  }
  if (!all_finite(a)) {
    return AnnouncementReason::kNonFinite;
  }
  if (!in_range(a.size.length_m, limits.min_length_m, limits.max_length_m)) {
    return AnnouncementReason::kLengthOutOfRange;
  }
  if (!in_range(a.size.width_m, limits.min_width_m, limits.max_width_m)) {
    return AnnouncementReason::kWidthOutOfRange;
  }
  if (!in_range(a.size.height_m, limits.min_height_m, limits.max_height_m)) {
    return AnnouncementReason::kHeightOutOfRange;
  }
  if (a.size.width_m > a.size.length_m) {
    return AnnouncementReason::kWiderThanLong;
  }
  if (std::abs(a.reference_offset.x()) > 0.5 * a.size.length_m + limits.reference_offset_margin_m ||
      std::abs(a.reference_offset.y()) > 0.5 * a.size.width_m + limits.reference_offset_margin_m) {
    return AnnouncementReason::kReferenceOffsetOutsideBox;
  }
  if (std::abs(a.pose.x) > limits.max_abs_coordinate_m || std::abs(a.pose.y) > limits.max_abs_coordinate_m) {
    return AnnouncementReason::kPositionOutOfRange;
  }
  if (std::abs(a.pose.yaw) > limits.max_abs_yaw_rad) {
    return AnnouncementReason::kYawOutOfRange;
  }
  if (const AnnouncementReason r = check_covariance(a.pose_covariance, limits);
      r != AnnouncementReason::kValid) {
    return r;
  }
  if (a.speed_mps && !in_range(*a.speed_mps, -limits.max_reverse_speed_mps, limits.max_speed_mps)) {
    return AnnouncementReason::kSpeedOutOfRange;
  }
  if (a.yaw_rate_rps && std::abs(*a.yaw_rate_rps) > limits.max_abs_yaw_rate_rps) {
    return AnnouncementReason::kYawRateOutOfRange;
  }
  if (saturating_age(a.generation_time, now) > limits.max_age) {
    return AnnouncementReason::kTooOld;
  }
  // Received later than judged cannot be: a clock stepped back between the two is judged at `now`.
  const TimeNs arrival = received ? std::min(*received, now) : now;
  if (saturating_age(a.generation_time, arrival) < -limits.max_future) {
    return AnnouncementReason::kFromFuture;
  }
  if (!is_unicast_ip_literal(a.reply_to.address)) {
    return AnnouncementReason::kReplyAddressInvalid;
  }
  if (a.reply_to.port == 0 || a.reply_to.port > 65535) {
    return AnnouncementReason::kReplyPortInvalid;
  }
  return AnnouncementReason::kValid;
}

}  // namespace rsu::v2i
