// SPDX-License-Identifier: Apache-2.0
// What became of one datagram received on the announcement port (or shared by another RSU over the data
// bus, RsuCore::on_peer_announcement): accepted into the registry, or the
// stage that refused it and why. Every refusal has a reason, so the daemon counts and logs instead of
// crashing or guessing (issue #4: garbage, truncated, oversized, unknown version, absurd sizes, floods).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "v2i/announcement_validation.h"
#include "v2i/message_authenticator.h"
#include "v2i/vehicle_registry.h"
#include "v2i/wire_codec.h"

namespace rsu::core {

enum class DatagramStage : std::uint8_t {
  kAccepted,         // the registry took it (upsert says added / updated)
  kFloodLimited,     // the source host exceeded the pre-decode datagram rate
  kDecode,           // not a well-formed version-2 datagram (see `decode`)
  kAuthentication,   // unsigned, unknown signer, bad signature, not its to sign, stale, replayed (`auth`)
  kNotAnnouncement,  // a well-formed correction or advertisement sent to the announcement port
  kValidation,       // an announcement with implausible content (see `validation`)
  kReplyToMismatch,  // reply_to is not the sender's address and port (RsuCoreConfig::reply_to, `reply_to`)
  kRegistry,         // refused by the registry: rate limit, stale sequence, full (see `upsert`)
  // Not a refusal: an announcement claiming a place beyond the verification radius (coverage radius +
  // security.verify_beyond_coverage_m), dropped unverified (v2i::VerificationRadius: verify on demand).
  kBeyondVerification,
  // Only for announcements shared by other RSUs (RsuCore::on_peer_announcement):
  kFromSelf,    // carries this RSU's own id: its own share echoed back, or another RSU with the same id
  kNotFresher,  // the registry already holds this announcement (same or newer sequence)
  kCount,
};

const char* to_string(DatagramStage stage);

// reply_to against the datagram's source (RsuCoreConfig::reply_to), counted as reply_to.<detail>.
enum class ReplyToCheck : std::uint8_t {
  kMatches,   // the source's address and port, or not checked that far (a refusal before it)
  kAddress,   // refused: another address than the source's
  kPort,      // refused: the source's address, another port
  kReplaced,  // ReplyToPolicy::kUseSource: it differed, the source's endpoint is used instead
  kCount,
};

const char* to_string(ReplyToCheck check);

struct DatagramOutcome {
  DatagramStage stage = DatagramStage::kDecode;
  v2i::DecodeStatus decode = v2i::DecodeStatus::kOk;
  v2i::AuthVerdict auth = v2i::AuthVerdict::kAccepted;
  v2i::AnnouncementReason validation = v2i::AnnouncementReason::kValid;
  v2i::UpsertOutcome upsert = v2i::UpsertOutcome::kCount;  // kCount: the registry was not reached
  std::uint64_t vehicle_id = 0;                            // when decoded as an announcement
  std::uint32_t announcement_sequence = 0;                 // when decoded as an announcement
  ReplyToCheck reply_to = ReplyToCheck::kMatches;
  // RsuCore::on_datagram: the encoded AnnouncementRefusal to send to the datagram's source (signed in
  // signed mode), when the refusal deserves one and the limits allow it (core/refusal_notices.h).
  std::vector<std::uint8_t> refusal_notice;

  bool accepted() const { return stage == DatagramStage::kAccepted; }
  // "stage" or "stage:detail", e.g. "decode:parse_error", "auth:bad_signature",
  // "validation:length_out_of_range", "reply_to_mismatch:port": a stable key for counting and
  // rate-limited logging.
  std::string reason() const;
};

}  // namespace rsu::core
