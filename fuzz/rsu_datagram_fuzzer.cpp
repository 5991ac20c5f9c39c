// Fuzzes the RSU core's announcement path (RsuCore::on_datagram, lib/rsu/rsu_core.h): flood limit ->
// decode -> validate -> reply-to check -> registry, with a fixed configuration and hand-stepped time,
// over a sequence of datagrams so that the registry's state (updates, capacity, rate limits,
// expiry) is reached too.
//
// Input: repeated { u8 source selector, u16 LE milliseconds since the previous datagram,
//                   u16 LE length, that many datagram bytes }.
#include <array>
#include <cstddef>
#include <cstdint>

#include "common/time.h"
#include "fuzz_input.h"
#include "rsu/rsu_core.h"

namespace {

rsu::core::RsuCoreConfig fuzz_config() {
  rsu::core::RsuCoreConfig c;
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
  rsu::core::RsuCore core(fuzz_config());
  rsu::fuzz::FuzzInput in(data, size);
  rsu::TimeNs now = 1'718'000'000LL * rsu::kNsPerSecond;
  while (!in.empty()) {
    const auto& source = kSources[in.u8() % kSources.size()];
    now += static_cast<rsu::TimeNs>(in.u16()) * rsu::kNsPerMs;
    (void)core.on_datagram(in.record(), source, now);
    (void)core.expire(now);
  }
  (void)core.counters();
  return 0;
}
