// SPDX-License-Identifier: Apache-2.0
#include "v2i/vehicle_registry.h"

#include <algorithm>
#include <cmath>

namespace rsu::v2i {
namespace {

bool size_changed(const BoxSize& a, const BoxSize& b, double tolerance) {
  return std::abs(a.length_m - b.length_m) > tolerance || std::abs(a.width_m - b.width_m) > tolerance ||
         std::abs(a.height_m - b.height_m) > tolerance;
}

}  // namespace

const char* to_string(UpsertOutcome outcome) {
  switch (outcome) {
    case UpsertOutcome::kAdded:
      return "added";
    case UpsertOutcome::kUpdated:
      return "updated";
    case UpsertOutcome::kUpdatedSizeChanged:
      return "updated_size_changed";
    case UpsertOutcome::kRateLimited:
      return "rate_limited";
    case UpsertOutcome::kTooManySources:
      return "too_many_sources";
    case UpsertOutcome::kDuplicateSequence:
      return "duplicate_sequence";
    case UpsertOutcome::kStaleSequence:
      return "stale_sequence";
    case UpsertOutcome::kRegistryFull:
      return "registry_full";
    case UpsertOutcome::kCount:
      break;
  }
  return "unknown";
}

bool sequence_newer(std::uint32_t a, std::uint32_t b) {
  // a - b modulo 2^32 in (0, 2^31): a is ahead. Exactly 2^31 apart is undefined by RFC 1982; treat
  // it as not newer.
  const std::uint32_t ahead = a - b;
  return ahead != 0 && ahead < 0x80000000U;
}

VehicleRegistry::VehicleRegistry(const VehicleRegistryConfig& config)
    : config_(config), rate_limiter_(config.rate_limit) {}

bool VehicleRegistry::is_silent(const RegisteredVehicle& v, TimeNs now) const {
  TimeNs silence = 0;
  if (__builtin_sub_overflow(now, v.last_heard, &silence)) {
    return now > v.last_heard;  // a difference beyond int64: silent if now is the later one
  }
  return silence > config_.silence_timeout;
}

UpsertOutcome VehicleRegistry::record(UpsertOutcome outcome) {
  stats_.outcomes.add(outcome);
  return outcome;
}

UpsertOutcome VehicleRegistry::upsert(const VehicleAnnouncement& announcement, std::string_view source,
                                      TimeNs now) {
  // Rate limiting first: it is the cheap defence and must count every datagram of a flooding source.
  switch (rate_limiter_.admit(source, now)) {
    case RateDecision::kAllowed:
      break;
    case RateDecision::kLimited:
      return record(UpsertOutcome::kRateLimited);
    case RateDecision::kTooManySources:
      return record(UpsertOutcome::kTooManySources);
  }

  auto it = vehicles_.find(announcement.vehicle_id);
  if (it != vehicles_.end() && is_silent(it->second, now)) {
    // Silent too long: forget it, so a restarted vehicle (sequence reset) is accepted afresh.
    vehicles_.erase(it);
    ++stats_.expired;
    it = vehicles_.end();
  }
  if (it == vehicles_.end()) {
    if (vehicles_.size() >= config_.capacity) {
      expire(now);
      if (vehicles_.size() >= config_.capacity) {
        return record(UpsertOutcome::kRegistryFull);
      }
    }
    RegisteredVehicle v;
    v.announcement = announcement;
    v.source = std::string(source);
    v.first_heard = now;
    v.last_heard = now;
    v.announcements = 1;
    vehicles_.emplace(announcement.vehicle_id, std::move(v));
    return record(UpsertOutcome::kAdded);
  }

  RegisteredVehicle& v = it->second;
  if (announcement.sequence == v.announcement.sequence) {
    return record(UpsertOutcome::kDuplicateSequence);
  }
  if (!sequence_newer(announcement.sequence, v.announcement.sequence)) {
    return record(UpsertOutcome::kStaleSequence);
  }
  const bool resized = size_changed(announcement.size, v.announcement.size, config_.size_change_tolerance_m);
  if (v.source != source) {
    // Accepted (a vehicle's address can change on a handover), but counted: until announcements are
    // signed this is also what an impostor using the same id looks like.
    ++stats_.source_changes;
    v.source = std::string(source);
  }
  v.announcement = announcement;
  v.last_heard = std::max(v.last_heard, now);
  ++v.announcements;
  return record(resized ? UpsertOutcome::kUpdatedSizeChanged : UpsertOutcome::kUpdated);
}

std::size_t VehicleRegistry::expire(TimeNs now) {
  const std::size_t removed =
      std::erase_if(vehicles_, [this, now](const auto& entry) { return is_silent(entry.second, now); });
  stats_.expired += removed;
  return removed;
}

const RegisteredVehicle* VehicleRegistry::find(std::uint64_t vehicle_id, TimeNs now) const {
  const auto it = vehicles_.find(vehicle_id);
  if (it == vehicles_.end() || is_silent(it->second, now)) {
    return nullptr;
  }
  return &it->second;
}

std::vector<const RegisteredVehicle*> VehicleRegistry::active(TimeNs now) const {
  std::vector<const RegisteredVehicle*> out;
  out.reserve(vehicles_.size());
  for (const auto& [id, v] : vehicles_) {
    if (!is_silent(v, now)) {
      out.push_back(&v);
    }
  }
  std::sort(out.begin(), out.end(), [](const RegisteredVehicle* a, const RegisteredVehicle* b) {
    return a->announcement.vehicle_id < b->announcement.vehicle_id;
  });
  return out;
}

}  // namespace rsu::v2i
