// SPDX-License-Identifier: Apache-2.0
#include "core/correction_builder.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <utility>

#include "common/angles.h"

namespace rsu::core {

v2i::YawResolution to_wire(perception::AmbiguityResolution resolution) {
  switch (resolution) {
    case perception::AmbiguityResolution::prior:
      return v2i::YawResolution::kPrior;
    case perception::AmbiguityResolution::geometry:
      return v2i::YawResolution::kGeometry;
    case perception::AmbiguityResolution::edge_lengths:
    case perception::AmbiguityResolution::unresolved:
      break;
  }
  return v2i::YawResolution::kUnresolved;
}

std::uint32_t faces_seen(const perception::RectangleFit& fit) {
  const auto n = std::count_if(fit.edges.begin(), fit.edges.end(), [](const auto& e) { return e.seen; });
  return static_cast<std::uint32_t>(std::min<std::ptrdiff_t>(n, 2));
}

v2i::Correction make_correction(const CorrectionInputs& in, const perception::CorrectedPose& fix,
                                const perception::RectangleFit& fit, const Eigen::Vector2d& lidar_xy) {
  v2i::Correction c;
  c.rsu_id = in.rsu_id;
  c.vehicle_id = in.vehicle_id;
  c.sequence = in.sequence;
  c.announcement_sequence = in.announcement_sequence;
  c.sweep_time = in.sweep_time;
  c.pose = {fix.pose.x, fix.pose.y, wrap_angle(fix.pose.yaw)};
  c.pose_covariance = fix.covariance;
  c.quality.points_used = static_cast<std::uint32_t>(in.points_used);
  c.quality.faces_seen = faces_seen(fit);
  c.quality.range_m = (fix.alignment_point - lidar_xy).norm();
  c.quality.yaw_resolution = to_wire(fix.resolution);
  c.quality.confidence = std::clamp(fix.confidence, 0.0, 1.0);
  return c;
}

namespace {

std::optional<v2i::security::SigningKey> signing_key(const RsuCoreConfig& config) {
  return config.security.mode == v2i::SecurityMode::kSigned ? config.signing_key : std::nullopt;
}

}  // namespace

CorrectionBuilder::CorrectionBuilder(const RsuCoreConfig& config, std::uint32_t first_signer_sequence)
    : lidar_xy_(config.mount.x, config.mount.y), signer_(signing_key(config), first_signer_sequence) {
  advertised_.rsu_id = config.rsu_id;
  advertised_.lidar_pose = config.mount;
  advertised_.coverage_radius_m = config.coverage_radius_m;
  advertised_.correction_port = config.correction_port;
  advertised_.announcement_port = config.announcement_port;
}

std::optional<OutgoingCorrection> CorrectionBuilder::build(const v2i::VehicleAnnouncement& a,
                                                           const perception::VehicleFix& fix,
                                                           TimeNs sweep_time, TimeNs now) {
  VehicleChannel& channel = channels_[a.vehicle_id];
  CorrectionInputs inputs;
  inputs.rsu_id = advertised_.rsu_id;
  inputs.vehicle_id = a.vehicle_id;
  inputs.sequence = channel.next_sequence;
  inputs.announcement_sequence = a.sequence;
  inputs.sweep_time = sweep_time;
  inputs.points_used = fix.points_used;
  OutgoingCorrection out;
  out.correction = make_correction(inputs, fix.corrected, fix.fit, lidar_xy_);
  out.bytes = signer_.encode(out.correction, now);
  if (out.bytes.empty())
    return std::nullopt;
  out.destination = a.reply_to;
  ++channel.next_sequence;  // wraps modulo 2^32, as the wire says
  channel.matched = true;
  channel.last_matched_sweep = sweep_time;
  return out;
}

bool CorrectionBuilder::corrected_this_rotation(std::uint64_t vehicle_id, TimeNs batch_time,
                                                TimeNs rotation_period_ns) const {
  const auto it = channels_.find(vehicle_id);
  return it != channels_.end() && it->second.matched &&
         std::abs(batch_time - it->second.last_matched_sweep) < rotation_period_ns / 2;
}

std::vector<std::uint8_t> CorrectionBuilder::advertisement(TimeNs now, v2i::FixesWithheld withheld,
                                                           double mount_error_at_radius_m) {
  advertised_.fixes_withheld = withheld;
  advertised_.mount_error_at_radius_m = withheld == v2i::FixesWithheld::kNone ? 0.0 : mount_error_at_radius_m;
  return signer_.encode(advertised_, now);
}

void CorrectionBuilder::forget_unregistered(const v2i::VehicleRegistry& registry, TimeNs now) {
  for (auto it = channels_.begin(); it != channels_.end();)
    it = registry.find(it->first, now) == nullptr ? channels_.erase(it) : std::next(it);
}

CorrectionBuilder CorrectionBuilder::reloaded(const RsuCoreConfig& next) && {
  CorrectionBuilder fresh(next, signer_.next_sequence());
  fresh.channels_ = std::move(channels_);
  return fresh;
}

}  // namespace rsu::core
