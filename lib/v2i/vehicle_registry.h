// SPDX-License-Identifier: Apache-2.0
// The RSU's table of connected vehicles that announced themselves (paper Section 3.2: the vehicle tells
// the RSU its box size over V2I). Keyed by vehicle id; entries expire after a silence. Pure: time is
// passed in by the caller, which also validates announcements first (announcement_validation.h).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "common/enum_counter.h"
#include "common/time.h"
#include "v2i/messages.h"
#include "v2i/source_rate_limiter.h"

namespace rsu::v2i {

struct VehicleRegistryConfig {
  // Announcements come at about 10 Hz: 2 s is 20 missed in a row, a vehicle that has left or lost
  // its link. Until then its last announcement (predicted forward) still serves association.
  TimeNs silence_timeout = 2 * kNsPerSecond;
  // Vehicles tracked at once. One LiDAR sees well under a hundred vehicles; the bound caps memory and
  // association cost against a flood of invented ids.
  std::size_t capacity = 256;
  RateLimitConfig rate_limit;
  // Announced dimensions differing by more than this count as a size change.
  double size_change_tolerance_m = 0.01;

  bool operator==(const VehicleRegistryConfig&) const = default;
};

enum class UpsertOutcome : std::uint8_t {
  kAdded,
  kUpdated,
  kUpdatedSizeChanged,  // accepted, and the box size differs from the previous announcement
  kRateLimited,         // the source exceeded its token bucket
  kTooManySources,      // the rate limiter's table of sources is full
  kDuplicateSequence,   // same sequence as the last accepted one
  kStaleSequence,       // older sequence (serial-number order, RFC 1982) than the last accepted one
  kRegistryFull,        // a new vehicle while `capacity` vehicles are active
  kCount,
};

const char* to_string(UpsertOutcome outcome);
inline bool is_accepted(UpsertOutcome o) {
  return o == UpsertOutcome::kAdded || o == UpsertOutcome::kUpdated ||
         o == UpsertOutcome::kUpdatedSizeChanged;
}

// True when sequence a comes after b modulo 2^32 (RFC 1982 serial-number arithmetic), so the counter
// may wrap. A vehicle that restarts its counter is refused as stale until its entry expires.
bool sequence_newer(std::uint32_t a, std::uint32_t b);

struct RegisteredVehicle {
  VehicleAnnouncement announcement;  // the latest accepted
  std::string source;                // the sender of that announcement, as passed to upsert
  TimeNs first_heard = 0;
  TimeNs last_heard = 0;            // receive time (RSU clock), not the vehicle's generation time
  std::uint64_t announcements = 0;  // accepted so far
};

struct RegistryStats {
  EnumCounter<UpsertOutcome> outcomes;
  std::uint64_t source_changes = 0;  // accepted announcements from a different source than before
  std::uint64_t expired = 0;
};

class VehicleRegistry {
 public:
  explicit VehicleRegistry(const VehicleRegistryConfig& config = {});

  // Adds or refreshes a vehicle from a validated announcement received from `source` at `now`.
  UpsertOutcome upsert(const VehicleAnnouncement& announcement, std::string_view source, TimeNs now);

  // Removes vehicles silent for longer than the timeout; returns how many.
  std::size_t expire(TimeNs now);

  // The vehicle, if registered and not silent for longer than the timeout at `now`.
  const RegisteredVehicle* find(std::uint64_t vehicle_id, TimeNs now) const;

  // Vehicles not silent at `now`, ordered by id (deterministic for association and tests).
  std::vector<const RegisteredVehicle*> active(TimeNs now) const;

  std::size_t size() const { return vehicles_.size(); }
  const RegistryStats& stats() const { return stats_; }
  const VehicleRegistryConfig& config() const { return config_; }

 private:
  bool is_silent(const RegisteredVehicle& v, TimeNs now) const;
  UpsertOutcome record(UpsertOutcome outcome);

  VehicleRegistryConfig config_;
  SourceRateLimiter rate_limiter_;
  std::unordered_map<std::uint64_t, RegisteredVehicle> vehicles_;
  RegistryStats stats_;
};

}  // namespace rsu::v2i
