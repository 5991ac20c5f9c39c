// Fuzzes the pcap parser (lib/lidar/pcap.h) that replays recorded Velodyne traffic: any file must give
// its complete UDP datagrams, counted skips and at most one error, never a crash.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <span>

#include "lidar/pcap.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const rsu::PcapParseResult result = rsu::parse_pcap(std::span<const std::uint8_t>(data, size));
  (void)rsu::to_string(result.error);
  std::size_t payload_bytes = 0;
  for (const rsu::UdpDatagram& d : result.datagrams)
    payload_bytes += d.payload.size();
  if (payload_bytes > size) {
    std::abort();  // payloads are copied out of the input: they cannot exceed it
  }
  return 0;
}
