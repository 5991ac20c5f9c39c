// SPDX-License-Identifier: Apache-2.0
// What the vehicle sends to the RSUs, and when: its announcement (box size, reference offset, its own
// best pose with covariance and motion, where to reply), one signed datagram per RSU with the vehicle's
// own announcement sequence, and the keep-alive that repeats the latest pose when nothing new was sent
// for a while (so one lost datagram does not expire the vehicle at the RSU) until that pose is too old
// for the RSU to accept. Pure: the caller passes the times in and sends the bytes.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "common/pose.h"
#include "common/time.h"
#include "v2i/announcement_validation.h"
#include "v2i/message_signer.h"
#include "v2i/messages.h"
#include "v2i/security/ed25519.h"

namespace rsu::vehicle {

// The vehicle's own estimate of its reference point, as announced (map frame ENU, m, rad CCW from east).
struct VehicleState {
  TimeNs time = 0;  // when the pose was valid (e.g. the NDT scan time): the generation time
  Pose2 pose;
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Identity();  // (x, y, yaw)
  std::optional<double> speed_mps;
  std::optional<double> yaw_rate_rps;
};

struct AnnouncerConfig {
  std::uint64_t vehicle_id = 0;
  v2i::BoxSize size;
  // The reference point of the announced pose minus the box centre, vehicle frame (x forward, y left).
  Eigen::Vector2d reference_offset = Eigen::Vector2d::Zero();
  // Keep-alive: repeat the latest pose after this long without a send (0: never) ...
  TimeNs announce_period = 100 * kNsPerMs;
  // ... while it is at most this old (the RSU refuses older ones; lib/v2i/announcement_validation.h).
  TimeNs max_resend_age = 1 * kNsPerSecond;
};

class Announcer {
 public:
  // Without a key the datagrams go unsigned (insecure mode, local development only).
  Announcer(const AnnouncerConfig& config, std::optional<v2i::security::SigningKey> key)
      : config_(config), signer_(std::move(key)) {}

  // Encodes `state` once per reply address (one per RSU: each RSU is told the local address it is
  // reached from), every datagram signed at `now` with the signer's next sequence, all carrying the
  // same announcement sequence. Returns kValid with out[i] the datagram for reply_to[i] (empty if it
  // could not be encoded), or the reason an RSU would refuse the state (NaN, bad covariance, absurd
  // size, ...) with `out` untouched. The generation time is not judged against `now`: the RSU judges
  // age.
  v2i::AnnouncementReason announce(const VehicleState& state, TimeNs now,
                                   std::span<const v2i::UdpEndpoint> reply_to,
                                   std::vector<std::vector<std::uint8_t>>& out);

  // The pose to repeat now, if a keep-alive is due: nothing was sent for `quiet_for` (measured by the
  // caller on a monotonic clock) of at least the announce period, and the latest pose is at most
  // max_resend_age old at `now` (the common clock).
  std::optional<VehicleState> keepalive_due(TimeNs quiet_for, TimeNs now) const;

  // Announcement sequence the next announcement will carry (wraps modulo 2^32, as the wire says).
  std::uint32_t next_sequence() const { return next_sequence_; }
  const AnnouncerConfig& config() const { return config_; }

 private:
  AnnouncerConfig config_;
  v2i::MessageSigner signer_;
  std::uint32_t next_sequence_ = 0;
  std::optional<VehicleState> latest_;
};

}  // namespace rsu::vehicle
