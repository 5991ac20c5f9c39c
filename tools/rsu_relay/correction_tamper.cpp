// SPDX-License-Identifier: Apache-2.0
#include "tools/rsu_relay/correction_tamper.h"

#include <variant>

#include "v2i/wire_codec.h"

namespace rsu::tools {

bool TamperConfig::in_burst(TimeNs sweep_time) const {
  if (burst_period <= 0 || burst_length <= 0 || sweep_time < from) {
    return false;
  }
  // Unsigned: `from` may be the minimum, and the difference must not overflow.
  const auto since = static_cast<std::uint64_t>(sweep_time) - static_cast<std::uint64_t>(from);
  return since % static_cast<std::uint64_t>(burst_period) < static_cast<std::uint64_t>(burst_length);
}

TamperedDatagram CorrectionTamper::process(std::span<const std::uint8_t> datagram) {
  TamperedDatagram out;
  out.bytes.assign(datagram.begin(), datagram.end());
  const v2i::DecodedMessage decoded = v2i::decode_v2i_message(datagram);
  const auto* correction = std::get_if<v2i::Correction>(&decoded.body);
  if (decoded.status != v2i::DecodeStatus::kOk || correction == nullptr) {
    return out;
  }
  out.correction = *correction;
  if (!config_.any()) {
    return out;
  }
  v2i::Correction& c = *out.correction;
  if (c.sweep_time >= config_.from) {
    c.pose.x += config_.bias_m.x();
    c.pose.y += config_.bias_m.y();
    c.pose_covariance *= config_.covariance_scale;
    out.burst = config_.in_burst(c.sweep_time);
    if (out.burst) {
      c.pose.x += config_.burst_offset_m.x();
      c.pose.y += config_.burst_offset_m.y();
    }
    out.altered = !config_.bias_m.isZero() || config_.covariance_scale != 1.0 || out.burst;
  }
  // Signed again at the RSU's own generation time, so that the vehicle's freshness test sees the RSU's.
  std::vector<std::uint8_t> bytes = signer_.encode(c, decoded.header.generation_time);
  if (!bytes.empty()) {
    out.bytes = std::move(bytes);
  }
  return out;
}

}  // namespace rsu::tools
