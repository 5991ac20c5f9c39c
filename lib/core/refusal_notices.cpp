// SPDX-License-Identifier: Apache-2.0
#include "core/refusal_notices.h"

namespace rsu::core {

std::optional<v2i::AnnouncementRefusal> refusal_for(const DatagramOutcome& outcome, std::uint64_t rsu_id) {
  v2i::AnnouncementRefusal r;
  r.rsu_id = rsu_id;
  r.vehicle_id = outcome.vehicle_id;
  r.announcement_sequence = outcome.announcement_sequence;
  switch (outcome.stage) {
    case DatagramStage::kValidation:
      r.reason = v2i::RefusalReason::kValidation;
      r.detail = v2i::to_string(outcome.validation);
      return r;
    case DatagramStage::kReplyToMismatch:
      r.reason = v2i::RefusalReason::kReplyToMismatch;
      r.detail = to_string(outcome.reply_to);
      return r;
    case DatagramStage::kRegistry:
      // A repeated sequence is the vehicle's own retransmission (or a replay of it): nothing to say.
      if (outcome.upsert == v2i::UpsertOutcome::kDuplicateSequence)
        return std::nullopt;
      r.reason = v2i::RefusalReason::kRegistry;
      r.detail = v2i::to_string(outcome.upsert);
      return r;
    default:
      return std::nullopt;
  }
}

std::optional<v2i::AnnouncementRefusal> RefusalNotices::consider(const DatagramOutcome& outcome,
                                                                 std::uint64_t rsu_id, TimeNs now) {
  if (!limits_.enabled())
    return std::nullopt;
  std::optional<v2i::AnnouncementRefusal> notice = refusal_for(outcome, rsu_id);
  if (!notice)
    return std::nullopt;
  if (!limits_.admit(outcome.vehicle_id, now)) {
    ++rate_limited_;
    return std::nullopt;
  }
  ++notices_;
  return notice;
}

RefusalNotices RefusalNotices::reloaded(const NoticeConfig& next) const {
  RefusalNotices fresh(next);
  fresh.notices_ = notices_;
  fresh.rate_limited_ = rate_limited_;
  return fresh;
}

void RefusalNotices::report(CounterList& out) const {
  out.add("refusal", "notices", notices_);
  out.add("refusal", "rate_limited", rate_limited_);
}

}  // namespace rsu::core
