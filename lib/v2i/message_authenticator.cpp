#include "v2i/message_authenticator.h"

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
  }
  if (entry.role != security::SignerRole::kRsu)
    return AuthVerdict::kWrongRole;
  return entry.may_sign_for(rsu_id) ? AuthVerdict::kAccepted : AuthVerdict::kWrongSubject;
}

}  // namespace

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

AuthenticatedMessage MessageAuthenticator::authenticate(std::span<const std::uint8_t> bytes, TimeNs now) {
  AuthenticatedMessage out;
  out.verdict = check(bytes, now, out);
  counts_.add(out.verdict);
  return out;
}

AuthVerdict MessageAuthenticator::check(std::span<const std::uint8_t> bytes, TimeNs now,
                                        AuthenticatedMessage& out) {
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
  if (envelope.signer_key_id.empty() && envelope.signature.empty()) {
    return AuthVerdict::kUnsigned;
  }
  if (envelope.signer_key_id.size() != security::kKeyIdBytes ||
      envelope.signature.size() != security::kSignatureBytes) {
    return AuthVerdict::kMalformedSignature;
  }
  std::memcpy(out.signer.data(), envelope.signer_key_id.data(), out.signer.size());
  const security::TrustEntry* entry = trust_.find(out.signer);
  if (entry == nullptr) {
    return AuthVerdict::kUnknownSigner;
  }
  const std::span<const std::uint8_t> signature(
      reinterpret_cast<const std::uint8_t*>(envelope.signature.data()), envelope.signature.size());
  if (!security::verify_signature(entry->public_key, signing_input(envelope.payload), signature)) {
    return AuthVerdict::kBadSignature;
  }
  out.message = decode_payload(envelope);
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
