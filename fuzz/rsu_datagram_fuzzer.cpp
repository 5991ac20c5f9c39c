// SPDX-License-Identifier: Apache-2.0
// Fuzzes the RSU core's announcement path (RsuCore::on_datagram, lib/core/rsu_core.h): flood limit ->
// authenticate (decode, signature, time and sequence windows) -> validate -> reply-to check ->
// registry, with a fixed configuration and hand-stepped time, over a sequence of datagrams so that the
// registry's and the replay window's state (updates, capacity, rate limits, expiry) is reached too.
// Every datagram goes to two cores: one in signed mode (the seeds are signed with fuzz_keys.h's vehicle
// key, which it trusts) and one in insecure mode, which reaches the registry with any well-formed bytes.
// Records whose selector byte has its top bit set also go to the signed core's peer path
// (RsuCore::on_peer_announcement: the same datagram shared by another RSU over the data bus).
//
// Input: repeated { u8 source selector, u16 LE milliseconds since the previous datagram,
//                   u16 LE length, that many datagram bytes }.
#include <array>
#include <cstddef>
#include <cstdint>

#include "common/time.h"
#include "core/rsu_core.h"
#include "fuzz_input.h"
#include "fuzz_keys.h"

namespace {

rsu::core::RsuCoreConfig fuzz_config(rsu::v2i::SecurityMode mode) {
  rsu::core::RsuCoreConfig c;
  c.security.mode = mode;
  c.signing_key = rsu::fuzz::fuzz_rsu_key();
  c.trust_list = rsu::fuzz::fuzz_trust_list();
  c.sensor_model = "vlp16";
  c.mount = {0.0, 0.0, 2.5, 0.0, 0.0, 0.0};
  c.registry.capacity = 8;  // small, so that the capacity limit is reached
  c.announcement_port = 4500;
  c.correction_port = 4500;
  return c;
}

// Senders: the seeds' announcements give reply_to 192.0.2.17, so source 0 matches them.
const std::array<rsu::core::SourceEndpoint, 4> kSources = {{
    {"192.0.2.17", 47001},
    {"192.0.2.18", 47002},
    {"2001:db8::17", 47003},
    {"192.0.2.17", 50000},
}};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  rsu::core::RsuCore signed_core(fuzz_config(rsu::v2i::SecurityMode::kSigned));
  rsu::core::RsuCore insecure_core(fuzz_config(rsu::v2i::SecurityMode::kInsecure));
  rsu::fuzz::FuzzInput in(data, size);
  rsu::TimeNs now = 1'718'000'000LL * rsu::kNsPerSecond;
  while (!in.empty()) {
    const std::uint8_t selector = in.u8();
    const auto& source = kSources[selector % kSources.size()];
    now += static_cast<rsu::TimeNs>(in.u16()) * rsu::kNsPerMs;
    const auto record = in.record();
    (void)signed_core.on_datagram(record, source, now);
    if (selector & 0x80U) {
      (void)signed_core.on_peer_announcement(record, {.origin_rsu_id = 2, .sender = source}, now);
    }
    (void)insecure_core.on_datagram(record, source, now);
    (void)signed_core.expire(now);
    (void)insecure_core.expire(now);
  }
  (void)signed_core.counters();
  (void)insecure_core.counters();
  return 0;
}
