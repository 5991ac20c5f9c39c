// SPDX-License-Identifier: Apache-2.0
// Configuration of the vehicle's V2I client (issue 4, item 3). Defaults: the paper's test vehicle and
// 10 Hz announcements.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "common/time.h"
#include "v2i/message_authenticator.h"
#include "v2i/messages.h"
#include "v2i/security/ed25519.h"
#include "v2i/security/trust_list.h"

namespace rsu::vehicle_client {

struct VehicleClientConfig {
  std::uint64_t vehicle_id = 0;  // non-zero, stable for the trip
  // Footprint box; the default is the Lexus RX450h of the paper's experiments (docs/design.md §2).
  v2i::BoxSize size{4.89, 1.92, 1.70};
  // The reference point of the announced pose minus the box centre, vehicle frame (x forward, y left).
  Eigen::Vector2d reference_offset = Eigen::Vector2d::Zero();

  // Where RSUs listen for announcements, "HOST:PORT" (IPv6 as "[ADDR]:PORT"). Each announcement goes
  // to every one of them. All must be of one address family.
  std::vector<std::string> rsu_endpoints;

  // Local address and port receiving corrections. Empty address: any address of the RSUs' family.
  // Port 0: an ephemeral port; the announcement carries the one actually bound.
  std::string bind_address;
  std::uint16_t bind_port = 0;
  // The address announced as reply_to. Empty: the bound address when it is specific, else the local
  // address the kernel routes each RSU's traffic from (so 127.0.0.1 for an RSU on loopback).
  std::string reply_address;

  // Keep-alive: when no announcement went out for this long, the latest pose is announced again (new
  // sequence, same generation time), so that one lost datagram does not expire the vehicle at the RSU.
  // 0 turns it off.
  TimeNs announce_period = 100 * kNsPerMs;
  // ... but not once the latest pose is older than this on the client's clock: the RSU would refuse
  // it anyway (its default max_age is 1 s, lib/v2i/announcement_validation.h).
  TimeNs max_resend_age = 1 * kNsPerSecond;

  // Corrections kept for poll(); beyond this the oldest are dropped (and counted), so a client that
  // never polls does not grow without bound.
  std::size_t max_pending_corrections = 1024;
  // Per-RSU ordering state (see CorrectionFilterConfig).
  std::size_t max_tracked_rsus = 64;

  // Message security (proto/v2i.proto). Signed (the default): announcements are signed with
  // signing_key (a vehicle key the RSUs' trust lists bind to vehicle_id), and only corrections signed
  // by an RSU key of trust_list, fresh and not replayed, are used. Insecure: local development only.
  v2i::SecurityConfig security;
  std::optional<v2i::security::SigningKey> signing_key;  // required in signed mode
  v2i::security::TrustList trust_list;                   // the RSU keys
};

}  // namespace rsu::vehicle_client
