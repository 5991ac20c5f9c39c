// SPDX-License-Identifier: Apache-2.0
// Telling a vehicle the LiDAR swept why it gets no correction for that rotation (proto/v2i.proto
// FixWithheld; issue 12: where the RSU cannot bound its error it sends no fix, and the vehicle should
// know why none comes). What became of a released vehicle's fix (GatheredFixOutcome, the size
// correction's CorrectionStatus, the mount monitor's stop) is put in the wire's terms here, in one place.
//
// Who gets one: a registered vehicle the LiDAR swept (points were gathered for it) and released without
// a correction, unless it got one in the same rotation (a later release of it holds what lay beside or
// ahead of its own: nothing the vehicle needs to hear). A vehicle the LiDAR did not see at all gets
// none: the RSU cannot tell it from one elsewhere. Each goes to the vehicle's announced reply_to, as its
// corrections do, at most one per vehicle per per_vehicle_interval_s and rate_per_s in all
// (notice_limits.h): a vehicle the RSU keeps withholding learns why within a second.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "calibration/mount_monitor.h"
#include "common/counter_list.h"
#include "common/enum_counter.h"
#include "common/time.h"
#include "core/gathered_fix.h"
#include "core/notice_limits.h"
#include "core/rsu_core_config.h"
#include "perception/size_correction.h"
#include "v2i/messages.h"

namespace rsu::core {

struct OutgoingNotice {
  v2i::UdpEndpoint destination;     // the vehicle's announced reply_to
  std::vector<std::uint8_t> bytes;  // the encoded FixWithheld, signed in signed mode
  v2i::FixWithheld notice;          // what the bytes say
};

// Why the RSU withholds every fix, in the wire's terms (RsuAdvertisement.fixes_withheld), from the
// mount monitor's cause of a stop.
v2i::FixesWithheld mount_withheld(calibration::StopCause cause);

// The notice for a released vehicle's fix that will not be sent, or nothing when it goes out. `mount`:
// why the RSU withholds every fix now (kNone while it serves); lost_nearby: packets were lost while the
// sweep passed the vehicle (GatheredVehicleFixer::fix); `correction`: the fix's rules (its sigma bound).
std::optional<v2i::FixWithheld> withheld_notice(const GatheredFix& fix, const v2i::VehicleAnnouncement& a,
                                                std::uint64_t rsu_id, bool lost_nearby,
                                                v2i::FixesWithheld mount,
                                                const perception::CorrectionConfig& correction);

class WithheldNotices {
 public:
  explicit WithheldNotices(const NoticeConfig& config) : limits_(config) {}

  bool enabled() const { return limits_.enabled(); }
  // `notice` when the limits let it go at `now`, else nothing; counted by reason either way.
  std::optional<v2i::FixWithheld> consider(v2i::FixWithheld notice, TimeNs now);
  void prune(TimeNs now) { limits_.prune(now); }
  // This one under `next` (SIGHUP): the counts go on, the limits start afresh.
  WithheldNotices reloaded(const NoticeConfig& next) const;

  // withheld_notice.<reason>: notices made (to be sent); withheld_notice.rate_limited.<reason>: owed
  // one, the limits held it back.
  void report(CounterList& out) const;

 private:
  NoticeLimits limits_;
  EnumCounter<v2i::FixWithheldReason> notices_;
  EnumCounter<v2i::FixWithheldReason> rate_limited_;
};

}  // namespace rsu::core
