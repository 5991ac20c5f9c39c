// SPDX-License-Identifier: Apache-2.0
// The correction a vehicle receives (proto/v2i.proto Correction, messages.h): its fix (pose of the
// footprint centre, covariance, how the yaw was settled) with the sweep time and the quality block,
// encoded with the RSU's per-vehicle sequence and signed in signed mode. Also the RSU's advertisement and
// its notices, which its signer seals too.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <unordered_map>
#include <vector>

#include <Eigen/Core>

#include "common/time.h"
#include "core/rsu_core_config.h"
#include "perception/rectangle_fit.h"
#include "perception/size_correction.h"
#include "perception/vehicle_fix.h"
#include "v2i/message_signer.h"
#include "v2i/messages.h"
#include "v2i/vehicle_registry.h"

namespace rsu::core {

// How the fix settled the yaw, in the wire's terms. The wire's PRIOR / GEOMETRY say which way the
// length axis lies (the off-by-90 deg question, docs/design.md §1); Algorithm 1's "longest edge is
// the length" and an unresolved fix are reported as UNRESOLVED.
v2i::YawResolution to_wire(perception::AmbiguityResolution resolution);

// Faces of the fitted rectangle the LiDAR saw (0..2; 1 = one edge, 2 = an L).
std::uint32_t faces_seen(const perception::RectangleFit& fit);

struct CorrectionInputs {
  std::uint64_t rsu_id = 0;
  std::uint64_t vehicle_id = 0;
  std::uint32_t sequence = 0;               // the RSU's per-vehicle counter
  std::uint32_t announcement_sequence = 0;  // of the announcement whose size and yaw prior were used
  TimeNs sweep_time = 0;                    // mean firing time of the vehicle's points
  std::size_t points_used = 0;
};

// `fix` must be ok(). range_m is the horizontal distance from the LiDAR to the alignment corner.
v2i::Correction make_correction(const CorrectionInputs& inputs, const perception::CorrectedPose& fix,
                                const perception::RectangleFit& fit, const Eigen::Vector2d& lidar_xy);

struct OutgoingCorrection {
  v2i::UdpEndpoint destination;     // the vehicle's announced reply_to
  std::vector<std::uint8_t> bytes;  // the encoded datagram, signed in signed mode
  v2i::Correction correction;       // what the bytes say (vehicle id, sweep time, pose, quality)
};

class CorrectionBuilder {
 public:
  // `first_signer_sequence`: where the signer's counter starts (carried over a reload).
  CorrectionBuilder(const RsuCoreConfig& config, std::uint32_t first_signer_sequence = 0);

  // The correction for the vehicle that announced `a`, from its fix swept at `sweep_time`, encoded at
  // `now`; its per-vehicle sequence advances. Empty if encoding failed.
  std::optional<OutgoingCorrection> build(const v2i::VehicleAnnouncement& a,
                                          const perception::VehicleFix& fix, TimeNs sweep_time, TimeNs now);
  // Whether the vehicle was corrected from a sweep within half a rotation of `batch_time`: a vehicle is
  // fixed once per rotation (a later cluster near it is something else).
  bool corrected_this_rotation(std::uint64_t vehicle_id, TimeNs batch_time, TimeNs rotation_period_ns) const;
  // The encoded RsuAdvertisement, signed in signed mode (empty if encoding failed), saying whether the
  // fixes are withheld now and why (with a mount cause, the estimated error at the coverage radius).
  std::vector<std::uint8_t> advertisement(TimeNs now, v2i::FixesWithheld withheld = v2i::FixesWithheld::kNone,
                                          double mount_error_at_radius_m = 0.0);
  // An encoded notice (refusal_notices.h, withheld_notices.h), signed in signed mode (empty if encoding
  // failed): the one signer seals everything the RSU sends, so a vehicle's replay window sees one counter.
  std::vector<std::uint8_t> notice(const v2i::AnnouncementRefusal& notice, TimeNs now) {
    return signer_.encode(notice, now);
  }
  std::vector<std::uint8_t> notice(const v2i::FixWithheld& notice, TimeNs now) {
    return signer_.encode(notice, now);
  }

  // Forgets the channels of vehicles the registry no longer holds.
  void forget_unregistered(const v2i::VehicleRegistry& registry, TimeNs now);
  // This builder under `next` (SIGHUP): the per-vehicle sequences and the signer's sequence go on, the
  // new key signs.
  CorrectionBuilder reloaded(const RsuCoreConfig& next) &&;

 private:
  struct VehicleChannel {
    std::uint32_t next_sequence = 0;
    TimeNs last_matched_sweep = 0;
    bool matched = false;
  };

  v2i::RsuAdvertisement advertised_;
  Eigen::Vector2d lidar_xy_;
  v2i::MessageSigner signer_;
  std::unordered_map<std::uint64_t, VehicleChannel> channels_;
};

}  // namespace rsu::core
