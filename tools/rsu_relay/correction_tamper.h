// SPDX-License-Identifier: Apache-2.0
// A faulty RSU made on purpose (rsu-relay, issue 18's fault injection): corrections on their way to the
// vehicle are decoded, altered (a position bias, a scaled covariance, bursts of another vehicle's pose)
// and signed again with the RSU's key, which the test owns. Once any alteration is configured every
// correction is re-signed (altered or not), so that the vehicle sees one signer sequence for that key.
// Pure: time is the corrections' own sweep time.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <vector>

#include "common/time.h"
#include "v2i/message_signer.h"
#include "v2i/messages.h"
#include "v2i/security/ed25519.h"

namespace rsu::tools {

struct TamperConfig {
  Eigen::Vector2d bias_m = Eigen::Vector2d::Zero();  // added to the position (map frame)
  double covariance_scale = 1.0;                     // the stated covariance times this
  // Wrong-vehicle bursts: for `burst_length` of every `burst_period` the pose is moved by
  // `burst_offset_m` (another vehicle's place, e.g. the next lane).
  Eigen::Vector2d burst_offset_m = Eigen::Vector2d::Zero();
  TimeNs burst_period = 0;
  TimeNs burst_length = 0;
  // Corrections swept before this are forwarded unaltered (still re-signed); bursts count from it.
  TimeNs from = std::numeric_limits<TimeNs>::min();

  bool any() const {
    return !bias_m.isZero() || covariance_scale != 1.0 || (burst_period > 0 && burst_length > 0);
  }
  bool in_burst(TimeNs sweep_time) const;
};

struct TamperedDatagram {
  std::vector<std::uint8_t> bytes;            // what to forward
  std::optional<v2i::Correction> correction;  // as forwarded, when the datagram was a correction
  bool altered = false;
  bool burst = false;  // another vehicle's pose
};

class CorrectionTamper {
 public:
  // rsu_key: signs the re-encoded corrections (empty: unsigned, for an RSU in insecure mode).
  CorrectionTamper(const TamperConfig& config, std::optional<v2i::security::SigningKey> rsu_key)
      : config_(config), signer_(std::move(rsu_key)) {}

  // Without any alteration configured, or for a datagram that is not a decodable correction, the
  // bytes are forwarded as they came.
  TamperedDatagram process(std::span<const std::uint8_t> datagram);

 private:
  TamperConfig config_;
  v2i::MessageSigner signer_;
};

}  // namespace rsu::tools
