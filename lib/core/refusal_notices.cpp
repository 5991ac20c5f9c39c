// SPDX-License-Identifier: Apache-2.0
#include "core/refusal_notices.h"

#include <stdexcept>
#include <string>

namespace rsu::core {
namespace {

v2i::RateLimitConfig per_vehicle_limit(const RefusalNoticeConfig& c) {
  if (!(c.per_vehicle_interval_s > 0.0) || !(c.rate_per_s > 0.0))
    throw std::invalid_argument("refusal notices: the interval and the rate must be > 0");
  // One token, refilled once per interval.
  return {.bucket = {.rate_per_s = 1.0 / c.per_vehicle_interval_s, .burst = 1.0}, .max_sources = 4096};
}

}  // namespace

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

RefusalNotices::RefusalNotices(const RefusalNoticeConfig& config)
    : config_(config),
      per_vehicle_(per_vehicle_limit(config)),
      overall_({.rate_per_s = config.rate_per_s, .burst = config.rate_per_s}, 0) {}

std::optional<v2i::AnnouncementRefusal> RefusalNotices::consider(const DatagramOutcome& outcome,
                                                                 std::uint64_t rsu_id, TimeNs now) {
  if (!config_.enabled)
    return std::nullopt;
  std::optional<v2i::AnnouncementRefusal> notice = refusal_for(outcome, rsu_id);
  if (!notice)
    return std::nullopt;
  if (per_vehicle_.admit("vehicle:" + std::to_string(outcome.vehicle_id), now) !=
          v2i::RateDecision::kAllowed ||
      !overall_.try_take(now)) {
    ++rate_limited_;
    return std::nullopt;
  }
  ++notices_;
  return notice;
}

RefusalNotices RefusalNotices::reloaded(const RefusalNoticeConfig& next) const {
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
