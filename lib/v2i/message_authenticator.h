// SPDX-License-Identifier: Apache-2.0
// The receiving side of V2I message security (proto/v2i.proto, version 2): decides whether a datagram
// comes from a trusted signer that may say what it says, and is neither stale nor replayed. Pure: the
// trust list is parsed elsewhere from text, time is passed in. Every verdict is counted by reason.
//
// Order of checks (signed mode), cheapest refusal first: envelope (size, protobuf, version) -> signature
// present and well-formed -> signer in the trust list -> the payload parsed (fuzzed: fuzz/v2i_datagram_
// fuzzer.cpp) and its generation time and sequence checked against the windows, recording nothing (what
// they refuse is refused whatever its signature; an RSU behind with a backlog had spent most of its time
// verifying what it then refused as stale) -> Ed25519 over kSigningContext || 0 || the payload bytes as
// received -> payload parses -> signer's role and ids allow this body -> generation-time window ->
// per-signer sequence window (only now is the signer's replay state updated, so a forger cannot move it).
// Nothing in an unverified payload is returned or acted on. With a verification radius (verify on demand,
// below), a vehicle announcement claiming a place beyond it is dropped after the windows, unverified.
//
// Insecure mode (local development only; the daemon and client warn loudly): any well-formed message
// is taken without checking signature, time or sequence, and counted as accepted_unverified.
//
// The Ed25519 check, the one costly step (~40 us), needs only the bytes and the trust list: a receiver may
// run it ahead on another thread (check_signature_ahead, rsud's V2I receiver thread) and hand its result
// in; the checks that need the receiver's state (rights, time, replay) stay here, in arrival order.
//
// Forwarded datagrams (a peer RSU relaying a vehicle's original bytes) verify the same way: the
// signature is the vehicle's, over the bytes as the vehicle sent them; a copy that arrives both
// directly and forwarded is accepted once and then refused as a duplicate.
#pragma once

#include <cstdint>
#include <optional>
#include <span>

#include "common/enum_counter.h"
#include "common/time.h"
#include "v2i/security/ed25519.h"
#include "v2i/security/replay_guard.h"
#include "v2i/security/trust_list.h"
#include "v2i/wire_codec.h"

namespace rsu::v2i {

enum class SecurityMode : std::uint8_t {
  kSigned,    // sign everything sent, accept only verified messages (the default)
  kInsecure,  // send unsigned, accept anything well-formed: local development only
};

const char* to_string(SecurityMode mode);

// Verify on demand: a receiver verifies what it may act on. V2X security (IEEE 1609.2, ETSI TS 103 097)
// leaves to the receiver which messages it verifies, and stacks verify those that feed a decision; an RSU
// acts on a vehicle's announcement only where its LiDAR may see the vehicle, while its radio hears
// vehicles hundreds of metres away. A vehicle announcement whose pose lies farther than `radius_m` from
// (x, y) is therefore not verified (AuthVerdict::kNotNeeded): nothing in it is used or recorded, so a
// forged one changes nothing, and a genuine one is verified as soon as its vehicle claims a place within
// the radius. Every other message, and an announcement whose pose is not finite, is verified.
struct VerificationRadius {
  double x = 0.0;
  double y = 0.0;
  double radius_m = 0.0;

  // Whether `body` must be verified before it is refused or used.
  bool needs(const MessageBody& body) const;
};

struct SecurityConfig {
  SecurityMode mode = SecurityMode::kSigned;
  security::ReplayConfig replay;
  std::optional<VerificationRadius> verify_within;  // none: verify every message (the library's default)
};

enum class AuthVerdict : std::uint8_t {
  kAccepted,            // verified signer, allowed body, fresh
  kAcceptedUnverified,  // insecure mode: taken without checks
  kMalformed,           // not a decodable version-2 datagram (the DecodeStatus says why)
  kUnsigned,            // no signature, in signed mode
  kMalformedSignature,  // key id not 8 bytes or signature not 64 bytes
  kUnknownSigner,       // key id not in the trust list
  kBadSignature,        // the signature does not verify over the payload bytes
  kWrongRole,           // e.g. a vehicle key signing a correction, an RSU key an announcement
  kWrongSubject,        // the key is not listed for this vehicle_id / rsu_id
  kStale,               // generated more than max_age before now
  kFuture,              // generated more than max_future after now
  kDuplicate,           // the signer's sequence number was already accepted
  kTooOld,              // the sequence number fell behind the window, or predates a restart
  kNotNeeded,           // an announcement beyond the verification radius: dropped unverified (not a refusal)
  kCount,
};

const char* to_string(AuthVerdict verdict);

struct AuthenticatedMessage {
  AuthVerdict verdict = AuthVerdict::kMalformed;
  DecodedMessage message;    // status kOk once decoded and verified (also when a later check refused it)
  security::KeyId signer{};  // when signed

  bool accepted() const {
    return verdict == AuthVerdict::kAccepted || verdict == AuthVerdict::kAcceptedUnverified;
  }
};

// A datagram's signature checked ahead of authenticate(), and the key it was checked against: it is
// used only when that is still the signer's key in the authenticator's trust list (a list reloaded in
// between makes authenticate() verify again).
struct SignatureCheck {
  security::PublicKey public_key{};
  bool valid = false;
};

// The Ed25519 check of `bytes` against its signer's key in `trust`, or nothing when there is no
// signature to check (not a version-2 envelope, unsigned, malformed signature fields, signer not
// listed): authenticate() refuses those cheaply itself.
std::optional<SignatureCheck> check_signature_ahead(std::span<const std::uint8_t> bytes,
                                                    const security::TrustList& trust);

// The receiver's clock and time window (security.max_age_s, max_future_s), for checking ahead only what
// authenticate() would not refuse by its generation time before verifying it.
struct TimeWindow {
  TimeNs now = 0;
  TimeNs max_age = 0;
  TimeNs max_future = 0;
};

// The same, but nothing for a message generated outside `window` (authenticate() refuses it before its
// signature): a receiver thread behind with a backlog does not verify what is refused as stale anyway.
// Nor for an announcement beyond `verify_within`, when given (authenticate() drops it unverified).
std::optional<SignatureCheck> check_signature_ahead(
    std::span<const std::uint8_t> bytes, const security::TrustList& trust, const TimeWindow& window,
    const std::optional<VerificationRadius>& verify_within = {});

class MessageAuthenticator {
 public:
  MessageAuthenticator(const SecurityConfig& config, security::TrustList trust);

  // `checked`: the result of check_signature_ahead() on these same bytes, if it was run.
  AuthenticatedMessage authenticate(std::span<const std::uint8_t> bytes, TimeNs now,
                                    const SignatureCheck* checked = nullptr);

  // A new configuration and trust list (SIGHUP): the signers' replay state and the counts are kept, so
  // nothing accepted before can be replayed after a reload.
  void reconfigure(const SecurityConfig& config, security::TrustList trust);
  // Forgets silent signers' replay state (call about once a second).
  void expire(TimeNs now) { replay_.expire(now); }

  SecurityMode mode() const { return config_.mode; }
  const SecurityConfig& config() const { return config_; }
  const security::TrustList& trust_list() const { return trust_; }
  const security::ReplayGuard& replay() const { return replay_; }
  const EnumCounter<AuthVerdict>& counts() const { return counts_; }
  // Ed25519 checks done here, and results of check_signature_ahead() taken instead.
  std::uint64_t signatures_verified() const { return signatures_verified_; }
  std::uint64_t signatures_checked_ahead() const { return signatures_checked_ahead_; }
  // Refused by the time window or the signer's sequence window before their signature was checked.
  std::uint64_t refused_before_signature() const { return refused_before_signature_; }

 private:
  AuthVerdict check(std::span<const std::uint8_t> bytes, TimeNs now, const SignatureCheck* checked,
                    AuthenticatedMessage& out);

  SecurityConfig config_;
  security::TrustList trust_;
  security::ReplayGuard replay_;
  EnumCounter<AuthVerdict> counts_;
  std::uint64_t signatures_verified_ = 0;
  std::uint64_t signatures_checked_ahead_ = 0;
  std::uint64_t refused_before_signature_ = 0;
};

}  // namespace rsu::v2i
