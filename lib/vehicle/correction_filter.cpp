// SPDX-License-Identifier: Apache-2.0
#include "vehicle/correction_filter.h"

#include <algorithm>
#include <variant>

#include "fusion/measurement_model.h"
#include "v2i/wire_codec.h"

namespace rsu::vehicle {

const char* to_string(CorrectionVerdict verdict) {
  switch (verdict) {
    case CorrectionVerdict::kAccepted:
      return "accepted";
    case CorrectionVerdict::kGarbage:
      return "garbage";
    case CorrectionVerdict::kNotACorrection:
      return "not_a_correction";
    case CorrectionVerdict::kNotAuthentic:
      return "not_authentic";
    case CorrectionVerdict::kUnknownVersion:
      return "unknown_version";
    case CorrectionVerdict::kWrongVehicleId:
      return "wrong_vehicle_id";
    case CorrectionVerdict::kInvalidContent:
      return "invalid_content";
    case CorrectionVerdict::kDuplicate:
      return "duplicate";
    case CorrectionVerdict::kStale:
      return "stale";
    case CorrectionVerdict::kRefusal:
      return "refusal";
    case CorrectionVerdict::kAdvertisement:
      return "advertisement";
    case CorrectionVerdict::kFixWithheld:
      return "fix_withheld";
    case CorrectionVerdict::kCount:
      break;
  }
  return "unknown";
}

CorrectionVerdict CorrectionFilter::check(std::span<const std::uint8_t> datagram, TimeNs now,
                                          v2i::Correction& out) {
  ++checks_;
  const CorrectionVerdict verdict = classify(datagram, now, out);
  counts_.add(verdict);
  if (verdict == CorrectionVerdict::kAccepted) {
    remember(out);
  }
  return verdict;
}

CorrectionVerdict CorrectionFilter::classify(std::span<const std::uint8_t> datagram, TimeNs now,
                                             v2i::Correction& out) {
  v2i::AuthenticatedMessage authenticated = authenticator_.authenticate(datagram, now);
  if (authenticated.verdict == v2i::AuthVerdict::kMalformed) {
    return authenticated.message.status == v2i::DecodeStatus::kUnsupportedVersion
               ? CorrectionVerdict::kUnknownVersion
               : CorrectionVerdict::kGarbage;
  }
  if (!authenticated.accepted()) {
    return CorrectionVerdict::kNotAuthentic;
  }
  if (auto* refusal = std::get_if<v2i::AnnouncementRefusal>(&authenticated.message.body)) {
    if (refusal->vehicle_id != config_.vehicle_id)
      return CorrectionVerdict::kWrongVehicleId;
    last_refusal_ = std::move(*refusal);
    return CorrectionVerdict::kRefusal;
  }
  if (auto* withheld = std::get_if<v2i::FixWithheld>(&authenticated.message.body)) {
    if (withheld->vehicle_id != config_.vehicle_id)
      return CorrectionVerdict::kWrongVehicleId;
    last_fix_withheld_ = *withheld;
    return CorrectionVerdict::kFixWithheld;
  }
  if (auto* advertisement = std::get_if<v2i::RsuAdvertisement>(&authenticated.message.body)) {
    last_advertisement_ = *advertisement;
    return CorrectionVerdict::kAdvertisement;
  }
  auto* correction = std::get_if<v2i::Correction>(&authenticated.message.body);
  if (correction == nullptr) {
    return CorrectionVerdict::kNotACorrection;
  }
  if (correction->vehicle_id != config_.vehicle_id) {
    return CorrectionVerdict::kWrongVehicleId;
  }
  // The fuser's own well-formedness test, so that whatever passes here can be fused.
  const fusion::PoseMeasurement as_measurement{correction->sweep_time, fusion::MeasurementSource::kRsu,
                                               correction->pose, correction->pose_covariance};
  if (!fusion::is_well_formed(as_measurement)) {
    return CorrectionVerdict::kInvalidContent;
  }
  const auto known = order_by_rsu_.find(correction->rsu_id);
  if (known != order_by_rsu_.end()) {
    const RsuOrder& last = known->second;
    if (correction->sequence == last.last_sequence && correction->sweep_time == last.last_sweep_time) {
      return CorrectionVerdict::kDuplicate;
    }
    // The sweep time, not the sequence, decides what is news: a restarted RSU counts from the start
    // again, and its corrections must still be taken (issue 4: corrections resume after a restart).
    if (correction->sweep_time <= last.last_sweep_time) {
      return CorrectionVerdict::kStale;
    }
  }
  out = std::move(*correction);
  return CorrectionVerdict::kAccepted;
}

void CorrectionFilter::remember(const v2i::Correction& correction) {
  auto known = order_by_rsu_.find(correction.rsu_id);
  if (known == order_by_rsu_.end()) {
    if (order_by_rsu_.size() >= std::max<std::size_t>(config_.max_tracked_rsus, 1)) {
      const auto oldest = std::min_element(
          order_by_rsu_.begin(), order_by_rsu_.end(),
          [](const auto& a, const auto& b) { return a.second.last_heard < b.second.last_heard; });
      order_by_rsu_.erase(oldest);
    }
    known = order_by_rsu_.emplace(correction.rsu_id, RsuOrder{}).first;
  } else {
    // Serial-number arithmetic (RFC 1982): "newer" is a positive signed difference modulo 2^32.
    const auto step = static_cast<std::int32_t>(correction.sequence - known->second.last_sequence);
    if (step <= 0) {
      ++sequence_restarts_;
    }
  }
  known->second = {correction.sequence, correction.sweep_time, checks_};
}

}  // namespace rsu::vehicle
