// SPDX-License-Identifier: Apache-2.0
// V2I messages as plain C++ data (decoded from / encoded to proto/v2i.proto by wire_codec.h).
// Map frame ENU, metres, radians CCW from east; vehicle frame x forward, y left; time in ns of the
// common clock (docs/design.md §3).
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

#include "common/pose.h"
#include "common/time.h"

namespace rsu::v2i {

// The wire format version this code speaks (SignedV2iMessage.protocol_version, proto/v2i.proto).
inline constexpr std::uint32_t kProtocolVersion = 2;

struct BoxSize {
  double length_m = 0.0;  // along vehicle x
  double width_m = 0.0;   // along vehicle y
  double height_m = 0.0;
};

struct UdpEndpoint {
  std::string address;     // numeric IPv4 or IPv6 literal
  std::uint32_t port = 0;  // as on the wire; validation checks 1..65535
};

struct VehicleAnnouncement {
  std::uint32_t protocol_version = kProtocolVersion;
  std::uint64_t vehicle_id = 0;
  std::uint32_t sequence = 0;
  TimeNs generation_time = 0;
  BoxSize size;
  // Reference point minus footprint box centre, vehicle frame (zero: the pose is the box centre).
  Eigen::Vector2d reference_offset = Eigen::Vector2d::Zero();
  Pose2 pose;                                                     // of the reference point
  Eigen::Matrix3d pose_covariance = Eigen::Matrix3d::Identity();  // (x, y, yaw)
  std::optional<double> speed_mps;
  std::optional<double> yaw_rate_rps;
  UdpEndpoint reply_to;
};

enum class YawResolution : std::uint8_t {
  kUnresolved = 0,  // yaw only meaningful modulo pi
  kPrior = 1,       // branch nearest the vehicle's announced yaw
  kGeometry = 2,    // branch fixed by what the RSU saw
};

struct CorrectionQuality {
  std::uint32_t points_used = 0;
  std::uint32_t faces_seen = 0;
  double range_m = 0.0;
  YawResolution yaw_resolution = YawResolution::kUnresolved;
  double confidence = 0.0;  // 0..1
};

struct Correction {
  std::uint32_t protocol_version = kProtocolVersion;
  std::uint64_t rsu_id = 0;
  std::uint64_t vehicle_id = 0;
  std::uint32_t sequence = 0;
  TimeNs sweep_time = 0;  // when the LiDAR swept the vehicle
  Pose2 pose;             // footprint box centre
  Eigen::Matrix3d pose_covariance = Eigen::Matrix3d::Identity();
  CorrectionQuality quality;
  std::uint32_t announcement_sequence = 0;
};

// Why an RSU withholds its corrections (proto/v2i.proto FixesWithheld).
enum class FixesWithheld : std::uint8_t {
  kNone = 0,
  kMountMoved = 1,      // the LiDAR moved beyond the tolerance (confirmed)
  kMountSuspected = 2,  // its estimate is beyond the tolerance; the scene cannot confirm it
  kMountMismatch = 3,   // its view no longer matches its reference scene
  kUnknown = 4,         // a value this receiver does not know
  kCount,
};

inline const char* to_string(FixesWithheld w) {
  switch (w) {
    case FixesWithheld::kNone:
      return "none";
    case FixesWithheld::kMountMoved:
      return "mount_moved";
    case FixesWithheld::kMountSuspected:
      return "mount_suspected";
    case FixesWithheld::kMountMismatch:
      return "mount_mismatch";
    case FixesWithheld::kUnknown:
    case FixesWithheld::kCount:
      break;
  }
  return "unknown";
}

struct RsuAdvertisement {
  std::uint32_t protocol_version = kProtocolVersion;
  std::uint64_t rsu_id = 0;
  Pose3 lidar_pose;
  double coverage_radius_m = 0.0;
  std::uint32_t correction_port = 0;
  std::uint32_t announcement_port = 0;
  FixesWithheld fixes_withheld = FixesWithheld::kNone;
  double mount_error_at_radius_m = 0.0;  // with a mount cause: the RSU's estimate at coverage_radius_m
};

// Why an RSU refused an announcement (proto/v2i.proto RefusalReason).
enum class RefusalReason : std::uint8_t {
  kUnspecified = 0,
  kValidation = 1,       // detail: the validation reason (announcement_validation.h)
  kReplyToMismatch = 2,  // detail: "address" or "port"
  kRegistry = 3,         // detail: the registry's outcome (vehicle_registry.h)
  kCount,
};

inline const char* to_string(RefusalReason r) {
  switch (r) {
    case RefusalReason::kValidation:
      return "validation";
    case RefusalReason::kReplyToMismatch:
      return "reply_to_mismatch";
    case RefusalReason::kRegistry:
      return "registry";
    case RefusalReason::kUnspecified:
    case RefusalReason::kCount:
      break;
  }
  return "unspecified";
}

// At most this many bytes of printable ASCII in AnnouncementRefusal::detail.
inline constexpr std::size_t kMaxRefusalDetailBytes = 32;

// RSU -> vehicle: an announcement the RSU refused, and why.
struct AnnouncementRefusal {
  std::uint32_t protocol_version = kProtocolVersion;
  std::uint64_t rsu_id = 0;
  std::uint64_t vehicle_id = 0;
  std::uint32_t announcement_sequence = 0;
  RefusalReason reason = RefusalReason::kUnspecified;
  std::string detail;
};

// Why an RSU sends a vehicle it swept no correction (proto/v2i.proto FixWithheldReason).
enum class FixWithheldReason : std::uint8_t {
  kUnspecified = 0,        // a value this receiver does not know; never sent
  kPositionUnbounded = 1,  // its position open over more than a fix may claim (position_sigma_m says)
  kYawUnobserved = 2,      // no seen face tells its heading, and none usable was announced
  kInconsistent = 3,       // a box of the announced size contradicts the points or the announced heading
  kNoOwnCluster = 4,       // no cluster near it known to be its own rather than a neighbour's
  kNoFit = 5,              // too few or scattered points on it to fit a box
  kOutOfCoverage = 6,      // its box lies beyond the RSU's coverage radius
  kMount = 7,              // fixed, but the RSU withholds every fix: its LiDAR moved (mount_cause)
  kCount,
};

inline const char* to_string(FixWithheldReason r) {
  switch (r) {
    case FixWithheldReason::kPositionUnbounded:
      return "position_unbounded";
    case FixWithheldReason::kYawUnobserved:
      return "yaw_unobserved";
    case FixWithheldReason::kInconsistent:
      return "inconsistent";
    case FixWithheldReason::kNoOwnCluster:
      return "no_own_cluster";
    case FixWithheldReason::kNoFit:
      return "no_fit";
    case FixWithheldReason::kOutOfCoverage:
      return "out_of_coverage";
    case FixWithheldReason::kMount:
      return "mount";
    case FixWithheldReason::kUnspecified:
    case FixWithheldReason::kCount:
      break;
  }
  return "unspecified";
}

// RSU -> vehicle: it was swept, and gets no correction for that rotation, and why.
struct FixWithheld {
  std::uint32_t protocol_version = kProtocolVersion;
  std::uint64_t rsu_id = 0;
  std::uint64_t vehicle_id = 0;
  std::uint32_t announcement_sequence = 0;
  TimeNs sweep_time = 0;
  FixWithheldReason reason = FixWithheldReason::kUnspecified;
  // kPositionUnbounded: the sigma the fix would have stated (larger axis, m) and the largest sent (m).
  std::optional<double> position_sigma_m;
  std::optional<double> max_position_sigma_m;
  bool packets_lost_nearby = false;  // the RSU judged it by its stricter rules for an incomplete sweep
  FixesWithheld mount_cause = FixesWithheld::kNone;  // kMount: why the RSU withholds its fixes
};

}  // namespace rsu::v2i
