// SPDX-License-Identifier: Apache-2.0
// Telling a vehicle why its announcement was refused (proto/v2i.proto AnnouncementRefusal): which
// refusals deserve a notice, and how many may go out. Only an announcement that passed authentication
// gets one (in signed mode the vehicle's own signature, so a forged source address cannot aim notices at
// a third party), never one the registry took as a retransmission, and each goes to the datagram's
// source, smaller than what it answers. At most one per vehicle per `per_vehicle_interval_s`, and
// `rate_per_s` in all (notice_limits.h): a vehicle that keeps announcing wrongly learns why within a
// second, and a flood of refusable announcements cannot turn the RSU into a sender.
#pragma once

#include <cstdint>
#include <optional>

#include "common/counter_list.h"
#include "common/time.h"
#include "core/datagram_outcome.h"
#include "core/notice_limits.h"
#include "core/rsu_core_config.h"
#include "v2i/messages.h"

namespace rsu::core {

// The wire's reason and detail for a refused outcome, or nothing when the outcome gets no notice
// (accepted, refused before authentication, a retransmission, not an announcement).
std::optional<v2i::AnnouncementRefusal> refusal_for(const DatagramOutcome& outcome, std::uint64_t rsu_id);

class RefusalNotices {
 public:
  explicit RefusalNotices(const NoticeConfig& config) : limits_(config) {}

  // The notice to send for `outcome` (received at `now`), if it deserves one and the limits allow it.
  std::optional<v2i::AnnouncementRefusal> consider(const DatagramOutcome& outcome, std::uint64_t rsu_id,
                                                   TimeNs now);
  void prune(TimeNs now) { limits_.prune(now); }
  // This one under `next` (SIGHUP): the counts go on, the limits start afresh.
  RefusalNotices reloaded(const NoticeConfig& next) const;

  // refusal.notices (to be sent), refusal.rate_limited (deserved one, the limits held it back)
  void report(CounterList& out) const;

 private:
  NoticeLimits limits_;
  std::uint64_t notices_ = 0;
  std::uint64_t rate_limited_ = 0;
};

}  // namespace rsu::core
