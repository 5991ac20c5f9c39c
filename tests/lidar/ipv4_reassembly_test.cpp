// SPDX-License-Identifier: Apache-2.0
// IPv4 fragment reassembly: the reassembler alone, then a real Ouster capture written as a 1500-byte
// Ethernet would carry it (each lidar packet in IP fragments, as tcpdump records them) and read back.
#include "lidar/ipv4_reassembly.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <stdexcept>

#include "lidar/pcap.h"
#include "tests/lidar/real_data.h"

namespace rsu::lidar {
namespace {

std::vector<std::uint8_t> bytes_of(std::size_t n, std::uint8_t seed) {
  std::vector<std::uint8_t> b(n);
  for (std::size_t i = 0; i < n; ++i) {
    b[i] = static_cast<std::uint8_t>(seed + 31 * i);
  }
  return b;
}

Ipv4Fragment piece(const std::vector<std::uint8_t>& whole, std::size_t from, std::size_t n, bool more,
                   std::uint16_t id = 9, TimeNs t = 0) {
  Ipv4Fragment f;
  f.src = 1;
  f.dst = 2;
  f.protocol = 17;
  f.identification = id;
  f.offset_bytes = from;
  f.more_fragments = more;
  f.data = std::span(whole).subspan(from, n);
  f.time_ns = t;
  return f;
}

TEST(Ipv4Reassembly, InAnyOrder) {
  const std::vector<std::uint8_t> whole = bytes_of(4000, 3);
  for (const std::vector<int>& order : std::vector<std::vector<int>>{{0, 1, 2}, {2, 1, 0}, {1, 2, 0}}) {
    Ipv4Reassembler r;
    std::optional<Ipv4Datagram> done;
    for (std::size_t k = 0; k < order.size(); ++k) {
      const auto from = static_cast<std::size_t>(order[k]) * 1480;
      done = r.add(piece(whole, from, std::min<std::size_t>(1480, whole.size() - from), order[k] != 2, 9,
                         static_cast<TimeNs>(k)));
      EXPECT_EQ(done.has_value(), k == 2);
    }
    ASSERT_TRUE(done);
    EXPECT_EQ(done->payload, whole);
    EXPECT_EQ(done->time_ns, 2);  // the fragment that completed it
    EXPECT_EQ(done->protocol, 17);
    EXPECT_EQ(r.stats().reassembled, 1U);
    EXPECT_EQ(r.pending(), 0U);
  }
}

TEST(Ipv4Reassembly, InterleavedDatagramsAndRepeatedFragments) {
  const std::vector<std::uint8_t> a = bytes_of(3000, 1);
  const std::vector<std::uint8_t> b = bytes_of(3000, 2);
  Ipv4Reassembler r;
  EXPECT_FALSE(r.add(piece(a, 0, 1480, true, 1)));
  EXPECT_FALSE(r.add(piece(b, 0, 1480, true, 2)));
  EXPECT_FALSE(r.add(piece(a, 0, 1480, true, 1)));  // a repeated copy, identical: harmless
  EXPECT_FALSE(r.add(piece(b, 1480, 1480, true, 2)));
  const auto done_b = r.add(piece(b, 2960, 40, false, 2));
  const auto done_a = r.add(piece(a, 1480, 1520, false, 1));
  ASSERT_TRUE(done_a && done_b);
  EXPECT_EQ(done_a->payload, a);
  EXPECT_EQ(done_b->payload, b);
}

TEST(Ipv4Reassembly, RefusalsCounted) {
  const std::vector<std::uint8_t> whole = bytes_of(3000, 5);
  std::vector<std::uint8_t> other = whole;
  other[100] ^= 0xFF;
  Ipv4Reassembler r(/*timeout_ns=*/1000, /*max_pending=*/2);
  // Overlapping fragments that disagree: the datagram is dropped.
  EXPECT_FALSE(r.add(piece(whole, 0, 1480, true, 1)));
  EXPECT_FALSE(r.add(piece(other, 0, 200, true, 1)));
  EXPECT_EQ(r.stats().overlapping, 1U);
  EXPECT_EQ(r.pending(), 0U);
  // Two different ends, and bytes past the end.
  EXPECT_FALSE(r.add(piece(whole, 1480, 1520, false, 2)));
  EXPECT_FALSE(r.add(piece(whole, 1480, 100, false, 2)));
  EXPECT_FALSE(r.add(piece(whole, 2000, 100, false, 3)));
  EXPECT_FALSE(r.add(piece(whole, 2000, 1000, true, 3)));
  EXPECT_EQ(r.stats().overlapping, 3U);
  // Past 65,535 bytes.
  Ipv4Fragment huge = piece(whole, 0, 1000, true, 4);
  huge.offset_bytes = 65000;
  EXPECT_FALSE(r.add(huge));
  EXPECT_EQ(r.stats().too_large, 1U);
  // Eviction beyond two pending, then the timeout, then the end of the input.
  EXPECT_FALSE(r.add(piece(whole, 0, 100, true, 5, 10)));
  EXPECT_FALSE(r.add(piece(whole, 0, 100, true, 6, 20)));
  EXPECT_FALSE(r.add(piece(whole, 0, 100, true, 7, 30)));  // evicts 5
  EXPECT_EQ(r.stats().timed_out, 1U);
  EXPECT_FALSE(r.add(piece(whole, 100, 100, true, 8, 1025)));  // 6 expired (1005 ns old)
  EXPECT_EQ(r.stats().timed_out, 2U);
  r.finish();
  EXPECT_EQ(r.stats().timed_out, 4U);
  EXPECT_EQ(r.stats().reassembled, 0U);
  EXPECT_THROW(Ipv4Reassembler(0, 1), std::invalid_argument);
}

// A real OS-1-32 capture (6,464-byte lidar packets) as a 1500-byte Ethernet carries it: each datagram
// in 1480-byte IP fragments, written here from RFC 791 directly, the fragments of neighbouring
// datagrams interleaved. Reading it back gives the original datagrams, none lost.
TEST(Ipv4Reassembly, FragmentedRealOusterCaptureReadsBack) {
  const std::vector<UdpDatagram> original = test::read_capture("ouster/OS-1-32-G_v2.1.1_1024x10.pcap");
  ASSERT_EQ(original.size(), 64U);
  std::vector<std::uint8_t> file = pcap_global_header();
  std::vector<std::vector<std::uint8_t>> frames;
  for (std::size_t i = 0; i < original.size(); ++i) {
    const UdpDatagram& d = original[i];
    std::vector<std::uint8_t> udp = {static_cast<std::uint8_t>(d.src.port >> 8),
                                     static_cast<std::uint8_t>(d.src.port),
                                     static_cast<std::uint8_t>(d.dst.port >> 8),
                                     static_cast<std::uint8_t>(d.dst.port),
                                     static_cast<std::uint8_t>((d.payload.size() + 8) >> 8),
                                     static_cast<std::uint8_t>(d.payload.size() + 8),
                                     0,
                                     0};
    udp.insert(udp.end(), d.payload.begin(), d.payload.end());
    for (std::size_t from = 0; from < udp.size(); from += 1480) {
      const std::size_t n = std::min<std::size_t>(1480, udp.size() - from);
      const bool more = from + n < udp.size();
      // Ethernet II (IPv4), IPv4 header (RFC 791: identification = datagram index, flags and offset),
      // then this fragment's part of the UDP datagram.
      std::vector<std::uint8_t> f(14 + 20 + n, 0);
      f[12] = 0x08;
      const std::size_t total = 20 + n;
      const std::size_t flags = (more ? 0x2000U : 0U) | (from / 8);
      const std::size_t header[20] = {
          0x45, 0, total >> 8, total & 0xFF, i >> 8, i & 0xFF, flags >> 8, flags & 0xFF, 64, 17,
          0,    0, 192,        168,          1,      201,      192,        168,          1,  100};
      for (std::size_t k = 0; k < 20; ++k) {
        f[14 + k] = static_cast<std::uint8_t>(header[k]);
      }
      for (std::size_t k = 0; k < n; ++k) {
        f[34 + k] = udp[from + k];
      }
      frames.push_back(std::move(f));
    }
  }
  // Interleave: swap neighbouring frames (fragments of one datagram, and across datagrams).
  for (std::size_t k = 1; k + 1 < frames.size(); k += 3) {
    std::swap(frames[k], frames[k + 1]);
  }
  for (std::size_t k = 0; k < frames.size(); ++k) {
    const auto t = static_cast<std::uint32_t>(k);
    const std::uint32_t len = static_cast<std::uint32_t>(frames[k].size());
    for (const std::uint32_t v : {1'650'000'000U, t, len, len}) {
      for (int b = 0; b < 4; ++b) {
        file.push_back(static_cast<std::uint8_t>(v >> (8 * b)));
      }
    }
    file.insert(file.end(), frames[k].begin(), frames[k].end());
  }
  const PcapParseResult back = parse_pcap(file);
  ASSERT_TRUE(back.ok());
  EXPECT_EQ(frames.size(), 64U * 5U);  // 6,472 bytes of UDP in five fragments each
  EXPECT_EQ(back.reassembled, 64U);
  EXPECT_EQ(back.skipped.fragmented, 0U);
  EXPECT_EQ(back.skipped.malformed, 0U);
  ASSERT_EQ(back.datagrams.size(), original.size());
  for (std::size_t i = 0; i < original.size(); ++i) {
    EXPECT_EQ(back.datagrams[i].payload, original[i].payload) << i;
    EXPECT_EQ(back.datagrams[i].dst.port, 7502);
    EXPECT_EQ(back.datagrams[i].src.ip, ipv4_address(192, 168, 1, 201));
  }
}

}  // namespace
}  // namespace rsu::lidar
