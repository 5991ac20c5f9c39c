// SPDX-License-Identifier: Apache-2.0
#include "vehicle/announcer.h"

namespace rsu::vehicle {

v2i::AnnouncementReason Announcer::announce(const VehicleState& state, TimeNs now,
                                            std::span<const v2i::UdpEndpoint> reply_to,
                                            std::vector<std::vector<std::uint8_t>>& out) {
  v2i::VehicleAnnouncement a;
  a.vehicle_id = config_.vehicle_id;
  a.sequence = next_sequence_;
  a.generation_time = state.time;
  a.size = config_.size;
  a.reference_offset = config_.reference_offset;
  a.pose = state.pose;
  a.pose_covariance = state.covariance;
  a.speed_mps = state.speed_mps;
  a.yaw_rate_rps = state.yaw_rate_rps;
  if (!reply_to.empty()) {
    a.reply_to = reply_to.front();
  }
  // The RSU's own plausibility test, with "now" = the pose's time: content only, the RSU judges age.
  const v2i::AnnouncementReason reason = v2i::validate_announcement(a, state.time);
  if (reason != v2i::AnnouncementReason::kValid) {
    return reason;
  }
  out.clear();
  for (const v2i::UdpEndpoint& reply : reply_to) {
    a.reply_to = reply;
    // One signed datagram per RSU (its own reply_to), each with the next signer sequence number.
    out.push_back(signer_.encode(a, now));
  }
  ++next_sequence_;
  latest_ = state;
  return v2i::AnnouncementReason::kValid;
}

std::optional<VehicleState> Announcer::keepalive_due(TimeNs quiet_for, TimeNs now) const {
  if (config_.announce_period <= 0 || !latest_ || quiet_for < config_.announce_period ||
      now - latest_->time > config_.max_resend_age) {
    return std::nullopt;
  }
  return latest_;
}

}  // namespace rsu::vehicle
