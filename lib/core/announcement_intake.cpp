// SPDX-License-Identifier: Apache-2.0
#include "core/announcement_intake.h"

#include <algorithm>
#include <utility>
#include <variant>

#include "v2i/ip_literal.h"
#include "v2i/wire_codec.h"

namespace rsu::core {

v2i::SecurityConfig announcement_security(const RsuCoreConfig& config) {
  v2i::SecurityConfig security = config.security;
  if (config.verify_beyond_coverage_m) {
    security.verify_within =
        v2i::VerificationRadius{.x = config.mount.x,
                                .y = config.mount.y,
                                .radius_m = config.coverage_radius_m + *config.verify_beyond_coverage_m};
  }
  return security;
}

AnnouncementIntake::AnnouncementIntake(const RsuCoreConfig& config)
    : rsu_id_(config.rsu_id),
      reply_to_policy_(config.reply_to),
      flood_limiter_(config.datagram_flood),
      peer_flood_limiter_(config.peers.flood),
      authenticator_(announcement_security(config), config.trust_list),
      validator_(config.announcement_limits),
      registry_(config.registry) {}

ReplyToCheck AnnouncementIntake::check_reply_to(v2i::VehicleAnnouncement& a,
                                                const SourceEndpoint& sender) const {
  const bool same_address = v2i::same_host(a.reply_to.address, sender.address);
  const bool same_port = a.reply_to.port == sender.port;
  if (same_address && same_port)
    return ReplyToCheck::kMatches;
  switch (reply_to_policy_) {
    case ReplyToPolicy::kMatchAddressAndPort:
      return same_address ? ReplyToCheck::kPort : ReplyToCheck::kAddress;
    case ReplyToPolicy::kMatchAddress:
      return same_address ? ReplyToCheck::kMatches : ReplyToCheck::kAddress;
    case ReplyToPolicy::kUseSource:
      break;
  }
  // Behind NAT the vehicle cannot know the address and port the RSU sees; replies to those reach it.
  a.reply_to = {sender.address, sender.port};
  return ReplyToCheck::kReplaced;
}

std::optional<v2i::VehicleAnnouncement> AnnouncementIntake::screen(std::span<const std::uint8_t> bytes,
                                                                   const SourceEndpoint& sender, TimeNs now,
                                                                   const v2i::SignatureCheck* checked,
                                                                   DatagramOutcome& out,
                                                                   std::optional<TimeNs> received) {
  v2i::AuthenticatedMessage authenticated = authenticator_.authenticate(bytes, now, checked);
  out.auth = authenticated.verdict;
  if (authenticated.verdict == v2i::AuthVerdict::kNotNeeded) {
    out.stage = DatagramStage::kBeyondVerification;
    return std::nullopt;
  }
  if (authenticated.verdict == v2i::AuthVerdict::kMalformed) {
    decode_counts_.add(authenticated.message.status);
    out.stage = DatagramStage::kDecode;
    out.decode = authenticated.message.status;
    return std::nullopt;
  }
  if (!authenticated.accepted()) {
    out.stage = DatagramStage::kAuthentication;
    return std::nullopt;
  }
  auto* announcement = std::get_if<v2i::VehicleAnnouncement>(&authenticated.message.body);
  if (announcement == nullptr) {
    out.stage = DatagramStage::kNotAnnouncement;
    return std::nullopt;
  }
  out.vehicle_id = announcement->vehicle_id;
  out.announcement_sequence = announcement->sequence;
  out.validation = validator_.check(*announcement, now, received);
  if (out.validation != v2i::AnnouncementReason::kValid) {
    out.stage = DatagramStage::kValidation;
    return std::nullopt;
  }
  out.reply_to = check_reply_to(*announcement, sender);
  if (out.reply_to != ReplyToCheck::kMatches)
    reply_to_counts_.add(out.reply_to);
  if (out.reply_to == ReplyToCheck::kAddress || out.reply_to == ReplyToCheck::kPort) {
    out.stage = DatagramStage::kReplyToMismatch;
    return std::nullopt;
  }
  return std::move(*announcement);
}

DatagramOutcome AnnouncementIntake::register_announcement(const v2i::VehicleAnnouncement& a,
                                                          const std::string& source, TimeNs now,
                                                          DatagramOutcome out) {
  out.upsert = registry_.upsert(a, source, now);
  out.stage = v2i::is_accepted(out.upsert) ? DatagramStage::kAccepted : DatagramStage::kRegistry;
  return out;
}

DatagramOutcome AnnouncementIntake::on_datagram(std::span<const std::uint8_t> bytes,
                                                const SourceEndpoint& source, TimeNs now,
                                                const v2i::SignatureCheck* checked,
                                                std::optional<TimeNs> received) {
  DatagramOutcome out;
  if (flood_limiter_.admit(source.address, now) != v2i::RateDecision::kAllowed) {
    out.stage = DatagramStage::kFloodLimited;
  } else if (const auto announcement = screen(bytes, source, now, checked, out, received)) {
    out = register_announcement(*announcement, source.address, now, out);
  }
  datagram_stages_.add(out.stage);
  return out;
}

DatagramOutcome AnnouncementIntake::on_peer_announcement(std::span<const std::uint8_t> datagram,
                                                         const PeerProvenance& from, TimeNs now) {
  DatagramOutcome out;
  const auto finish = [&](DatagramStage stage) {
    out.stage = stage;
    peer_stages_.add(stage);
    return out;
  };
  if (from.origin_rsu_id == rsu_id_)
    return finish(DatagramStage::kFromSelf);  // the bus delivers an RSU's own samples back to it
  if (peer_flood_limiter_.admit("rsu:" + std::to_string(from.origin_rsu_id), now) !=
      v2i::RateDecision::kAllowed) {
    return finish(DatagramStage::kFloodLimited);
  }
  const auto announcement = screen(datagram, from.sender, now, nullptr, out);
  if (out.stage == DatagramStage::kAuthentication && out.auth == v2i::AuthVerdict::kDuplicate) {
    // A signed datagram this RSU verified already: the vehicle announced here too, or another peer
    // shared it first. Not news, not an attack (the bytes are the vehicle's own, signature and all).
    return finish(DatagramStage::kNotFresher);
  }
  if (!announcement)
    return finish(out.stage);
  // Checked before the registry so that a vehicle announcing to several RSUs, each sharing it, is not
  // charged twice by the registry's per-source rate limit for one announcement.
  const v2i::RegisteredVehicle* known = registry_.find(announcement->vehicle_id, now);
  if (known != nullptr && !v2i::sequence_newer(announcement->sequence, known->announcement.sequence))
    return finish(DatagramStage::kNotFresher);
  // The registry's source is the vehicle's address, as for its own datagrams: its rate limit and
  // source-change count follow the vehicle, whichever RSU heard it.
  out = register_announcement(*announcement, from.sender.address, now, out);
  return finish(out.stage);
}

std::size_t AnnouncementIntake::expire(TimeNs now) {
  const std::size_t n = registry_.expire(now);
  flood_limiter_.prune(now);
  peer_flood_limiter_.prune(now);
  authenticator_.expire(now);
  return n;
}

AnnouncementIntake AnnouncementIntake::reloaded(const RsuCoreConfig& next, TimeNs now) && {
  AnnouncementIntake fresh(next);
  if (registry_.config() == next.registry) {
    fresh.registry_ = std::move(registry_);
  } else {
    // Re-enter the vehicles in the order they were last heard, at those times (a fresh rate limiter
    // starts full, so only a source with more vehicles than its burst loses some).
    auto active = registry_.active(now);
    std::sort(active.begin(), active.end(),
              [](const auto* a, const auto* b) { return a->last_heard < b->last_heard; });
    for (const v2i::RegisteredVehicle* v : active)
      fresh.registry_.upsert(v->announcement, v->source, v->last_heard);
  }
  fresh.authenticator_ = std::move(authenticator_);
  fresh.authenticator_.reconfigure(announcement_security(next), next.trust_list);
  fresh.datagram_stages_ = datagram_stages_;
  fresh.peer_stages_ = peer_stages_;
  fresh.decode_counts_ = decode_counts_;
  fresh.reply_to_counts_ = reply_to_counts_;
  return fresh;
}

void AnnouncementIntake::report(CounterList& out) const {
  out.add_all("datagram", datagram_stages_);
  out.add_all("peer", peer_stages_);
  out.add_all("decode", decode_counts_, v2i::DecodeStatus::kEmpty);  // kOk is no refusal
  // auth.* counts the datagrams that reached authentication: an undecodable one (AuthVerdict::kMalformed)
  // is counted once, by its decode.* reason, so that every refused datagram has exactly one reason.
  const EnumCounter<v2i::AuthVerdict>& auth = authenticator_.counts();
  for (const auto verdict : {v2i::AuthVerdict::kAccepted, v2i::AuthVerdict::kAcceptedUnverified})
    out.add("auth", to_string(verdict), auth.count(verdict));
  out.add_all("auth", auth, v2i::AuthVerdict::kUnsigned);
  out.add_level("auth", "signers_tracked", authenticator_.replay().tracked());
  out.add("auth", "sequence_restarts", authenticator_.replay().stats().restarts);
  out.add("auth", "signers_evicted", authenticator_.replay().stats().evictions);
  out.add_level("auth", "trusted_keys", authenticator_.trust_list().size());
  // Where the Ed25519 checks ran: here, or ahead on the receiver's thread (rsud's v2i.verifier_thread).
  out.add("auth", "signatures_verified", authenticator_.signatures_verified());
  out.add("auth", "signatures_checked_ahead", authenticator_.signatures_checked_ahead());
  // Of the auth.* refusals, those made before any signature check (time or sequence window).
  out.add("auth", "refused_before_signature", authenticator_.refused_before_signature());
  // 1 while running without signatures: local development only (the daemon also warns).
  out.add_level("security", "insecure_mode", authenticator_.mode() == v2i::SecurityMode::kInsecure ? 1 : 0);
  out.add_all("validation", validator_.counts(),
              v2i::AnnouncementReason::kUnsupportedVersion);          // after kValid
  out.add_all("reply_to", reply_to_counts_, ReplyToCheck::kAddress);  // kMatches is no event
  out.add_all("registry", registry_.stats().outcomes);
  out.add("registry", "expired", registry_.stats().expired);
  out.add_level("registry", "vehicles", registry_.size());
}

}  // namespace rsu::core
