// SPDX-License-Identifier: Apache-2.0
// What the vehicles tell the RSU, into its registry: every datagram from the announcement port, and
// every announcement another RSU shared on the data bus, takes one path - a cheap per-source rate
// limit, authentication (signature, signer's rights, time and sequence windows), decoding, validation,
// the reply_to check, the registry (expiry, capacity, per-source rate) - and each refusal is counted by
// stage and reason (datagram_outcome.h). README, "Signed V2I messages" and "Several RSUs on one bus".
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>

#include "common/counter_list.h"
#include "common/enum_counter.h"
#include "common/time.h"
#include "core/datagram_outcome.h"
#include "core/rsu_core_config.h"
#include "v2i/announcement_validation.h"
#include "v2i/message_authenticator.h"
#include "v2i/messages.h"
#include "v2i/source_rate_limiter.h"
#include "v2i/vehicle_registry.h"

namespace rsu::core {

// Who sent a datagram. `address` is the numeric IP literal; the rate limits are per address (host),
// so a sender cannot earn fresh tokens by changing ports.
struct SourceEndpoint {
  std::string address;
  std::uint16_t port = 0;
};

// Where an announcement shared by another RSU came from (README, "Several RSUs on one bus"). The
// announcement itself travels as the vehicle's original datagram, so that every RSU decodes and checks
// it itself (and verifies the vehicle's own signature).
struct PeerProvenance {
  std::uint64_t origin_rsu_id = 0;  // the RSU that received it from the vehicle
  SourceEndpoint sender;            // the vehicle, as that RSU saw it (reply_to is checked against it)
};

// The security configuration the intake authenticates with: RsuCoreConfig::security with the
// verification radius around the LiDAR (RsuCoreConfig::verify_beyond_coverage_m).
v2i::SecurityConfig announcement_security(const RsuCoreConfig& config);

class AnnouncementIntake {
 public:
  explicit AnnouncementIntake(const RsuCoreConfig& config);

  // RsuCore::on_datagram and RsuCore::on_peer_announcement (rsu_core.h).
  DatagramOutcome on_datagram(std::span<const std::uint8_t> bytes, const SourceEndpoint& source, TimeNs now,
                              const v2i::SignatureCheck* checked = nullptr,
                              std::optional<TimeNs> received = std::nullopt);
  DatagramOutcome on_peer_announcement(std::span<const std::uint8_t> datagram, const PeerProvenance& from,
                                       TimeNs now);

  // Forgets silent vehicles, idle sources and silent signers; returns how many vehicles.
  std::size_t expire(TimeNs now);

  // This intake under `next` (SIGHUP): the registered vehicles (re-entered in the order they were
  // last heard if the registry's setup changed), the signers' replay state and the stage counts are
  // kept; the new trust list takes effect. The rate limiters and validation counts start afresh.
  AnnouncementIntake reloaded(const RsuCoreConfig& next, TimeNs now) &&;

  const v2i::VehicleRegistry& registry() const { return registry_; }
  const EnumCounter<DatagramStage>& datagram_stages() const { return datagram_stages_; }
  const EnumCounter<DatagramStage>& peer_stages() const { return peer_stages_; }
  const EnumCounter<v2i::DecodeStatus>& decode_counts() const { return decode_counts_; }
  const v2i::AnnouncementValidator& validator() const { return validator_; }
  const v2i::MessageAuthenticator& authenticator() const { return authenticator_; }

  // datagram.*, peer.*, decode.*, auth.*, security.insecure_mode, validation.*, reply_to.*, registry.*
  void report(CounterList& out) const;

 private:
  // Authentication, decoding, validation and the reply_to check, whatever carried the datagram: the
  // announcement, or empty with `out` saying which stage refused it.
  std::optional<v2i::VehicleAnnouncement> screen(std::span<const std::uint8_t> bytes,
                                                 const SourceEndpoint& sender, TimeNs now,
                                                 const v2i::SignatureCheck* checked, DatagramOutcome& out,
                                                 std::optional<TimeNs> received = std::nullopt);
  // reply_to against the sender under the policy (RsuCoreConfig::reply_to); kReplaced rewrites it.
  ReplyToCheck check_reply_to(v2i::VehicleAnnouncement& announcement, const SourceEndpoint& sender) const;
  DatagramOutcome register_announcement(const v2i::VehicleAnnouncement& a, const std::string& source,
                                        TimeNs now, DatagramOutcome out);

  std::uint64_t rsu_id_;
  ReplyToPolicy reply_to_policy_;
  v2i::SourceRateLimiter flood_limiter_;
  v2i::SourceRateLimiter peer_flood_limiter_;  // keyed by origin RSU
  v2i::MessageAuthenticator authenticator_;
  v2i::AnnouncementValidator validator_;
  v2i::VehicleRegistry registry_;
  EnumCounter<DatagramStage> datagram_stages_;
  EnumCounter<DatagramStage> peer_stages_;
  EnumCounter<v2i::DecodeStatus> decode_counts_;
  EnumCounter<ReplyToCheck> reply_to_counts_;
};

}  // namespace rsu::core
