// SPDX-License-Identifier: Apache-2.0
// Fuzzes the pcap reader (lib/lidar/pcap.h) that rsud and rsu-decode replay captures with: any file must
// give its complete UDP datagrams, counted skips and at most one error, never a crash; and read in
// pieces (as a file is, chunk by chunk) it must give exactly what the whole file gives.
//
// Input: the capture's bytes; their first byte also picks the piece size (1 to 256 bytes).
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <span>
#include <vector>

#include "lidar/pcap.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::span<const std::uint8_t> bytes(data, size);
  const rsu::lidar::PcapParseResult result = rsu::lidar::parse_pcap(bytes);
  (void)rsu::lidar::to_string(result.error);
  std::size_t payload_bytes = 0;
  for (const rsu::lidar::UdpDatagram& d : result.datagrams)
    payload_bytes += d.payload.size();
  // Payloads are copied out of the input: they cannot exceed it (fragments put together excepted:
  // each fragment's bytes are in the input too).
  if (payload_bytes > size) {
    std::abort();
  }

  const std::size_t piece = size > 0 ? std::size_t{data[0]} + 1 : 1;
  rsu::lidar::PcapReader reader;
  std::vector<rsu::lidar::UdpDatagram> pieces;
  rsu::lidar::UdpDatagram d;
  for (std::size_t at = 0; at < size; at += piece) {
    reader.feed(bytes.subspan(at, std::min(piece, size - at)));
    for (;;) {
      const rsu::lidar::PcapReader::Next next = reader.next(d);
      if (next == rsu::lidar::PcapReader::Next::datagram)
        pieces.push_back(d);
      else if (next != rsu::lidar::PcapReader::Next::skipped)
        break;
    }
  }
  if (reader.finish() != result.error || pieces.size() != result.datagrams.size()) {
    std::abort();  // read in pieces, the capture reads the same
  }
  for (std::size_t i = 0; i < pieces.size(); ++i) {
    if (pieces[i].payload != result.datagrams[i].payload || pieces[i].time_ns != result.datagrams[i].time_ns)
      std::abort();
  }
  return 0;
}
