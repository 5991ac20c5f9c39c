// SPDX-License-Identifier: Apache-2.0
// Replay protection for signed V2I messages (proto/v2i.proto): a generation-time window around the
// receiver's clock, and per signer a sliding anti-replay window over its sequence numbers (RFC 4303
// §3.4.3, IPsec ESP: a 64-bit bitmap below the highest number accepted), so that mild reordering is
// accepted and duplicates are not. Pure: time is passed in. Call it only for messages whose signature
// verified, so that a forger cannot move a signer's window.
//
// The time window is what bounds replay when the sequence state is gone (receiver restart, signer
// evicted or expired here): a captured message is useless after max_age. Sequence numbers use RFC 1982
// serial arithmetic over 2^32. A signer may restart its counter (reboot): a number the window refuses
// is taken as a restart when the message's generation time is newer than everything accepted from that
// signer (a replay cannot be newer: its signature fixes its time); messages generated before the
// restart are refused afterwards.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>

#include "common/time.h"
#include "v2i/security/ed25519.h"

namespace rsu::v2i::security {

struct ReplayConfig {
  // A message generated more than this before the receiver's clock is stale ...
  TimeNs max_age = 1 * kNsPerSecond;
  // ... and more than this after it is from the future (a clock offset, or a pre-made message).
  TimeNs max_future = 1 * kNsPerSecond;
  // Signers tracked at once; when full, the one heard least recently is forgotten (the time window
  // still protects it). The trust list bounds the legitimate count; this bounds memory regardless.
  std::size_t max_signers = 4096;
  // A signer silent this long is forgotten (its old messages are then stale anyway if >= max_age).
  TimeNs signer_expiry = 60 * kNsPerSecond;
};

enum class ReplayVerdict : std::uint8_t {
  kFresh,      // accepted; the signer's window now holds it
  kStale,      // generation time older than now - max_age
  kFuture,     // generation time newer than now + max_future
  kDuplicate,  // this sequence number was already accepted from this signer (inside the window)
  kTooOld,     // the sequence number is behind the window (more than 63 below the highest), or the
               // message was generated before the signer's last restart
  kCount,
};

const char* to_string(ReplayVerdict verdict);

// The 64-wide anti-replay window of one signer.
class SequenceWindow {
 public:
  static constexpr std::uint32_t kWidth = 64;
  enum class Check : std::uint8_t { kNew, kDuplicate, kTooOld };

  Check check(std::uint32_t sequence) const;
  void accept(std::uint32_t sequence);  // precondition: check(sequence) == kNew
  void restart(std::uint32_t sequence);

 private:
  bool started_ = false;
  std::uint32_t highest_ = 0;
  std::uint64_t seen_ = 0;  // bit i: highest_ - i was accepted
};

struct ReplayStats {
  std::uint64_t restarts = 0;   // signers that restarted their sequence
  std::uint64_t evictions = 0;  // signers forgotten because max_signers was reached
  std::uint64_t expired = 0;    // signers forgotten after signer_expiry of silence
};

class ReplayGuard {
 public:
  explicit ReplayGuard(const ReplayConfig& config) : config_(config) {}

  // Checks one verified message and, when fresh, records it.
  ReplayVerdict admit(const KeyId& signer, std::uint32_t sequence, TimeNs generation_time, TimeNs now);
  // What admit() would say now, recording nothing: lets a receiver refuse a message that admit() would
  // refuse before paying for its signature (MessageAuthenticator). kFresh means "verify, then admit".
  ReplayVerdict check(const KeyId& signer, std::uint32_t sequence, TimeNs generation_time, TimeNs now) const;
  // Forgets signers silent for signer_expiry (call about once a second).
  void expire(TimeNs now);

  std::size_t tracked() const { return signers_.size(); }
  const ReplayStats& stats() const { return stats_; }
  const ReplayConfig& config() const { return config_; }
  // New limits; the signers' windows are kept (a smaller max_signers takes effect as new ones arrive).
  void set_config(const ReplayConfig& config) { config_ = config; }

 private:
  struct SignerState {
    SequenceWindow window;
    TimeNs newest_generation = 0;  // of everything accepted
    TimeNs restarted_at = 0;       // generation time of the message that restarted the counter
    TimeNs last_heard = 0;         // receiver clock
  };

  SignerState& state_for(const KeyId& signer, TimeNs now, bool& fresh);

  ReplayConfig config_;
  std::map<KeyId, SignerState> signers_;
  ReplayStats stats_;
};

}  // namespace rsu::v2i::security
