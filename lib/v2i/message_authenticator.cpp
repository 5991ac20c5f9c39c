// SPDX-License-Identifier: Apache-2.0
#include "v2i/message_authenticator.h"

#include <cmath>
#include <cstring>
#include <variant>

namespace rsu::v2i {
namespace {

AuthVerdict from_replay(security::ReplayVerdict v) {
  switch (v) {
    case security::ReplayVerdict::kFresh:
      return AuthVerdict::kAccepted;
    case security::ReplayVerdict::kStale:
      return AuthVerdict::kStale;
    case security::ReplayVerdict::kFuture:
      return AuthVerdict::kFuture;
    case security::ReplayVerdict::kDuplicate:
      return AuthVerdict::kDuplicate;
    case security::ReplayVerdict::kTooOld:
    case security::ReplayVerdict::kCount:
      break;
  }
  return AuthVerdict::kTooOld;
}

// Whether the trust entry may sign this body: role first, then the id it speaks for.
AuthVerdict check_rights(const security::TrustEntry& entry, const MessageBody& body) {
  if (const auto* a = std::get_if<VehicleAnnouncement>(&body)) {
    if (entry.role != security::SignerRole::kVehicle)
      return AuthVerdict::kWrongRole;
    return entry.may_sign_for(a->vehicle_id) ? AuthVerdict::kAccepted : AuthVerdict::kWrongSubject;
  }
  std::uint64_t rsu_id = 0;
  if (const auto* c = std::get_if<Correction>(&body)) {
    rsu_id = c->rsu_id;
  } else if (const auto* r = std::get_if<RsuAdvertisement>(&body)) {
    rsu_id = r->rsu_id;
  } else if (const auto* f = std::get_if<AnnouncementRefusal>(&body)) {
    rsu_id = f->rsu_id;
  } else if (const auto* w = std::get_if<FixWithheld>(&body)) {
    rsu_id = w->rsu_id;
  }
  if (entry.role != security::SignerRole::kRsu)
    return AuthVerdict::kWrongRole;
  return entry.may_sign_for(rsu_id) ? AuthVerdict::kAccepted : AuthVerdict::kWrongSubject;
}

// The signature fields of a signed envelope and the trust entry of its signer, or the verdict that
// refuses it before any signature is checked.
AuthVerdict find_signer(const Envelope& envelope, const security::TrustList& trust, security::KeyId& signer,
                        const security::TrustEntry*& entry) {
  if (envelope.signer_key_id.empty() && envelope.signature.empty())
    return AuthVerdict::kUnsigned;
  if (envelope.signer_key_id.size() != security::kKeyIdBytes ||
      envelope.signature.size() != security::kSignatureBytes) {
    return AuthVerdict::kMalformedSignature;
  }
  std::memcpy(signer.data(), envelope.signer_key_id.data(), signer.size());
  entry = trust.find(signer);
  return entry == nullptr ? AuthVerdict::kUnknownSigner : AuthVerdict::kAccepted;
}

bool signature_verifies(const Envelope& envelope, const security::PublicKey& key) {
  const std::span<const std::uint8_t> signature(
      reinterpret_cast<const std::uint8_t*>(envelope.signature.data()), envelope.signature.size());
  return security::verify_signature(key, signing_input(envelope.payload), signature);
}

}  // namespace

namespace {

std::optional<SignatureCheck> check_ahead(std::span<const std::uint8_t> bytes,
                                          const security::TrustList& trust, const TimeWindow* window,
                                          const std::optional<VerificationRadius>& verify_within) {
  const DecodedEnvelope decoded = decode_envelope(bytes);
  if (decoded.status != DecodeStatus::kOk)
    return std::nullopt;
  security::KeyId signer{};
  const security::TrustEntry* entry = nullptr;
  if (find_signer(decoded.envelope, trust, signer, entry) != AuthVerdict::kAccepted)
    return std::nullopt;
  if (window != nullptr) {
    const DecodedMessage payload = decode_payload(decoded.envelope);
    const TimeNs t = payload.header.generation_time;
    if (payload.status == DecodeStatus::kOk &&
        (t < window->now - window->max_age || t > window->now + window->max_future ||
         (verify_within && !verify_within->needs(payload.body))))
      return std::nullopt;
  }
  return SignatureCheck{entry->public_key, signature_verifies(decoded.envelope, entry->public_key)};
}

}  // namespace

std::optional<SignatureCheck> check_signature_ahead(std::span<const std::uint8_t> bytes,
                                                    const security::TrustList& trust) {
  return check_ahead(bytes, trust, nullptr, std::nullopt);
}

std::optional<SignatureCheck> check_signature_ahead(std::span<const std::uint8_t> bytes,
                                                    const security::TrustList& trust,
                                                    const TimeWindow& window,
                                                    const std::optional<VerificationRadius>& verify_within) {
  return check_ahead(bytes, trust, &window, verify_within);
}

bool VerificationRadius::needs(const MessageBody& body) const {
  const auto* a = std::get_if<VehicleAnnouncement>(&body);
  if (a == nullptr)
    return true;
  // A NaN or infinite pose (so distance) is verified: validation then refuses it, counted by its reason.
  const double distance = std::hypot(a->pose.x - x, a->pose.y - y);
  return !(distance > radius_m && std::isfinite(distance));
}

const char* to_string(SecurityMode mode) {
  return mode == SecurityMode::kSigned ? "signed" : "insecure";
}

const char* to_string(AuthVerdict verdict) {
  switch (verdict) {
    case AuthVerdict::kAccepted:
      return "accepted";
    case AuthVerdict::kAcceptedUnverified:
      return "accepted_unverified";
    case AuthVerdict::kMalformed:
      return "malformed";
    case AuthVerdict::kUnsigned:
      return "unsigned";
    case AuthVerdict::kMalformedSignature:
      return "malformed_signature";
    case AuthVerdict::kUnknownSigner:
      return "unknown_signer";
    case AuthVerdict::kBadSignature:
      return "bad_signature";
    case AuthVerdict::kWrongRole:
      return "wrong_role";
    case AuthVerdict::kWrongSubject:
      return "wrong_subject";
    case AuthVerdict::kStale:
      return "stale";
    case AuthVerdict::kFuture:
      return "future";
    case AuthVerdict::kDuplicate:
      return "duplicate";
    case AuthVerdict::kTooOld:
      return "too_old";
    case AuthVerdict::kNotNeeded:
      return "not_needed";
    case AuthVerdict::kCount:
      break;
  }
  return "unknown";
}

MessageAuthenticator::MessageAuthenticator(const SecurityConfig& config, security::TrustList trust)
    : config_(config), trust_(std::move(trust)), replay_(config.replay) {
  security::ensure_sodium_initialized();
}

void MessageAuthenticator::reconfigure(const SecurityConfig& config, security::TrustList trust) {
  config_ = config;
  trust_ = std::move(trust);
  replay_.set_config(config.replay);
}

AuthenticatedMessage MessageAuthenticator::authenticate(std::span<const std::uint8_t> bytes, TimeNs now,
                                                        const SignatureCheck* checked) {
  AuthenticatedMessage out;
  out.verdict = check(bytes, now, checked, out);
  counts_.add(out.verdict);
  return out;
}

AuthVerdict MessageAuthenticator::check(std::span<const std::uint8_t> bytes, TimeNs now,
                                        const SignatureCheck* checked, AuthenticatedMessage& out) {
  DecodedEnvelope decoded = decode_envelope(bytes);
  if (decoded.status != DecodeStatus::kOk) {
    out.message.status = decoded.status;
    return AuthVerdict::kMalformed;
  }
  const Envelope& envelope = decoded.envelope;
  if (config_.mode == SecurityMode::kInsecure) {
    out.message = decode_payload(envelope);
    return out.message.status == DecodeStatus::kOk ? AuthVerdict::kAcceptedUnverified
                                                   : AuthVerdict::kMalformed;
  }
  const security::TrustEntry* entry = nullptr;
  if (const AuthVerdict found = find_signer(envelope, trust_, out.signer, entry);
      found != AuthVerdict::kAccepted)
    return found;
  // The cheap refusals before the signature (~40 us): a message outside the time window, or whose sequence
  // the signer's window already holds, is refused whatever its signature. A receiver reading a backlog (its
  // CPU share below the load's need) had spent most of its time verifying what it then refused as stale
  // (README, "Robustness"). So the payload is parsed before the signature (the parser is fuzzed); nothing
  // is recorded and nothing in it is used until the signature verified.
  DecodedMessage payload = decode_payload(envelope);
  if (payload.status == DecodeStatus::kOk) {
    const security::ReplayVerdict early =
        replay_.check(out.signer, payload.header.sequence, payload.header.generation_time, now);
    if (early != security::ReplayVerdict::kFresh) {
      ++refused_before_signature_;
      return from_replay(early);
    }
    if (config_.verify_within && !config_.verify_within->needs(payload.body))
      return AuthVerdict::kNotNeeded;  // not verified, nothing recorded (VerificationRadius)
  }
  bool valid = false;
  if (checked != nullptr && checked->public_key == entry->public_key) {
    valid = checked->valid;
    ++signatures_checked_ahead_;
  } else {
    valid = signature_verifies(envelope, entry->public_key);
    ++signatures_verified_;
  }
  if (!valid)
    return AuthVerdict::kBadSignature;
  out.message = std::move(payload);
  if (out.message.status != DecodeStatus::kOk) {
    return AuthVerdict::kMalformed;  // signed garbage: a broken signer, not an attacker
  }
  const AuthVerdict rights = check_rights(*entry, out.message.body);
  if (rights != AuthVerdict::kAccepted) {
    return rights;
  }
  return from_replay(
      replay_.admit(out.signer, out.message.header.sequence, out.message.header.generation_time, now));
}

}  // namespace rsu::v2i
