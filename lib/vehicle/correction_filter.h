// SPDX-License-Identifier: Apache-2.0
// Decides whether a datagram received on the vehicle's correction port is a correction this vehicle
// should use, and counts every refusal by reason. Pure computation (no socket, time passed in): the
// VehicleClient feeds it the bytes, the tests feed it crafted ones. In signed mode the RSU's signature
// is verified against the trust list (an RSU key listed for that rsu_id), and its generation time and
// the RSU's sequence number are checked against the replay windows, BEFORE anything is fused
// (v2i/message_authenticator.h; the details of a refusal are in authentication_counts()).
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <span>

#include "common/enum_counter.h"
#include "common/time.h"
#include "v2i/message_authenticator.h"
#include "v2i/messages.h"
#include "v2i/security/trust_list.h"

namespace rsu::vehicle {

enum class CorrectionVerdict : std::uint8_t {
  kAccepted,
  kGarbage,         // not a decodable datagram (empty, too large, not protobuf, no body, bad covariance)
  kUnknownVersion,  // protocol_version this client does not speak
  kNotAuthentic,    // signed mode: unsigned, unknown or unentitled signer, bad signature, stale, replayed
  kNotACorrection,  // a valid message of another kind (an announcement or advertisement)
  kWrongVehicleId,  // meant for another vehicle
  kInvalidContent,  // NaN/inf pose, or a covariance that is not symmetric positive definite
  kDuplicate,       // the same RSU sequence and sweep time as the last one accepted from that RSU
  kStale,           // a sweep no newer than the last one accepted from that RSU (reordered or replayed)
  kRefusal,         // not a correction: an RSU's notice that it refused this vehicle's announcement
                    // (authenticated like a correction; last_refusal() says why)
  kAdvertisement,   // not a correction: an RSU's advertisement (authenticated like a correction;
                    // last_advertisement() holds it: whether that RSU withholds its fixes, and why)
  kFixWithheld,     // not a correction: an RSU swept this vehicle and says why it sends no fix
                    // (authenticated like a correction; last_fix_withheld() says why)
  kCount,
};

const char* to_string(CorrectionVerdict verdict);

struct CorrectionFilterConfig {
  std::uint64_t vehicle_id = 0;
  // Per-RSU ordering state is kept for at most this many RSU ids, so that a flood of forged ids cannot
  // grow memory; the least recently heard one is forgotten first.
  std::size_t max_tracked_rsus = 64;
  // Signed (the default): only corrections signed by an RSU key of the trust list, fresh, not replayed.
  v2i::SecurityConfig security;
  v2i::security::TrustList trust_list;  // the RSU keys, each bound to its rsu_ids
};

class CorrectionFilter {
 public:
  explicit CorrectionFilter(const CorrectionFilterConfig& config)
      : config_(config), authenticator_(config.security, config.trust_list) {}

  // Authenticates, decodes and checks one datagram received at `now` (the vehicle's clock, which the
  // RSU's generation time is compared with); on kAccepted `out` holds the correction.
  CorrectionVerdict check(std::span<const std::uint8_t> datagram, TimeNs now, v2i::Correction& out);

  const EnumCounter<CorrectionVerdict>& counts() const { return counts_; }
  // The refusal notice of the last check() that returned kRefusal.
  const v2i::AnnouncementRefusal& last_refusal() const { return last_refusal_; }
  // The notice of the last check() that returned kFixWithheld.
  const v2i::FixWithheld& last_fix_withheld() const { return last_fix_withheld_; }
  // The advertisement of the last check() that returned kAdvertisement.
  const v2i::RsuAdvertisement& last_advertisement() const { return last_advertisement_; }
  // Every datagram's authentication verdict (accepted, or refused by reason).
  const EnumCounter<v2i::AuthVerdict>& authentication_counts() const { return authenticator_.counts(); }
  // Forgets silent RSUs' replay state (call now and then).
  void expire(TimeNs now) { authenticator_.expire(now); }
  // Accepted corrections whose sequence went backwards while the sweep time moved on: the RSU daemon
  // restarted (its per-vehicle counter starts again), which must not lock the vehicle out.
  std::uint64_t sequence_restarts() const { return sequence_restarts_; }

 private:
  struct RsuOrder {
    std::uint32_t last_sequence = 0;
    TimeNs last_sweep_time = 0;
    std::uint64_t last_heard = 0;  // check() call count, for least-recently-heard eviction
  };

  CorrectionVerdict classify(std::span<const std::uint8_t> datagram, TimeNs now, v2i::Correction& out);
  void remember(const v2i::Correction& correction);

  CorrectionFilterConfig config_;
  v2i::MessageAuthenticator authenticator_;
  EnumCounter<CorrectionVerdict> counts_;
  v2i::AnnouncementRefusal last_refusal_;
  v2i::RsuAdvertisement last_advertisement_;
  v2i::FixWithheld last_fix_withheld_;
  std::map<std::uint64_t, RsuOrder> order_by_rsu_;
  std::uint64_t checks_ = 0;
  std::uint64_t sequence_restarts_ = 0;
};

}  // namespace rsu::vehicle
