// SPDX-License-Identifier: Apache-2.0
#include "lidar/pcap.h"

#include <gtest/gtest.h>

#include <random>
#include <stdexcept>

namespace rsu::lidar {
namespace {

constexpr UdpEndpoint kSensor{ipv4_address(192, 168, 1, 201), 2368};
constexpr UdpEndpoint kHost{ipv4_address(255, 255, 255, 255), 2368};

std::uint32_t le32(const std::vector<std::uint8_t>& b, std::size_t at) {
  return b[at] | (b[at + 1] << 8) | (b[at + 2] << 16) | (static_cast<std::uint32_t>(b[at + 3]) << 24);
}

// RFC 1071: the ones'-complement sum of a correct header (checksum included) is 0xFFFF.
std::uint32_t ones_sum(const std::vector<std::uint8_t>& b, std::size_t from, std::size_t n,
                       std::uint32_t sum = 0) {
  for (std::size_t i = 0; i < n; i += 2) {
    sum += (b[from + i] << 8) + (i + 1 < n ? b[from + i + 1] : 0);
  }
  while (sum > 0xFFFF) {
    sum = (sum & 0xFFFF) + (sum >> 16);
  }
  return sum;
}

std::vector<std::uint8_t> payload_of(std::size_t n, std::uint8_t seed) {
  std::vector<std::uint8_t> p(n);
  for (std::size_t i = 0; i < n; ++i) {
    p[i] = static_cast<std::uint8_t>(seed + 7 * i);
  }
  return p;
}

TEST(LidarPcap, GlobalHeaderBytes) {
  const std::vector<std::uint8_t> h = pcap_global_header();
  ASSERT_EQ(h.size(), 24U);
  EXPECT_EQ((std::vector<std::uint8_t>(h.begin(), h.begin() + 4)),
            (std::vector<std::uint8_t>{0xd4, 0xc3, 0xb2, 0xa1}));
  EXPECT_EQ(h[4] | (h[5] << 8), 2);  // version 2.4
  EXPECT_EQ(h[6] | (h[7] << 8), 4);
  EXPECT_EQ(le32(h, 16), 65535U);  // snaplen
  EXPECT_EQ(le32(h, 20), 1U);      // Ethernet
}

TEST(LidarPcap, RecordHeadersAndChecksums) {
  std::vector<std::uint8_t> file = pcap_global_header();
  const std::vector<std::uint8_t> payload = payload_of(1206, 3);
  append_udp_record(file, 1'700'000'123 * kNsPerSecond + 456'789'999, kSensor, kHost, payload);
  ASSERT_EQ(file.size(), 24U + 16U + 42U + 1206U);
  EXPECT_EQ(le32(file, 24), 1'700'000'123U);
  EXPECT_EQ(le32(file, 28), 456'789U);  // microseconds, floored
  EXPECT_EQ(le32(file, 32), 1248U);     // the 1248-byte frame the Velodyne manuals quote
  EXPECT_EQ(le32(file, 36), 1248U);
  const std::size_t eth = 40;
  EXPECT_EQ((file[eth + 12] << 8) | file[eth + 13], 0x0800);
  const std::size_t ip = eth + 14;
  EXPECT_EQ(file[ip], 0x45);
  EXPECT_EQ((file[ip + 2] << 8) | file[ip + 3], 20 + 8 + 1206);
  EXPECT_EQ(file[ip + 9], 17);
  EXPECT_EQ(ones_sum(file, ip, 20), 0xFFFFU);
  const std::size_t udp = ip + 20;
  EXPECT_EQ((file[udp] << 8) | file[udp + 1], 2368);
  EXPECT_EQ((file[udp + 4] << 8) | file[udp + 5], 8 + 1206);
  // UDP checksum over the pseudo-header (addresses, zero + protocol, UDP length) and the datagram.
  std::uint32_t pseudo = ones_sum(file, ip + 12, 8) + 17 + 8 + 1206;
  EXPECT_EQ(ones_sum(file, udp, 8 + 1206, pseudo), 0xFFFFU);
  EXPECT_EQ(std::equal(payload.begin(), payload.end(), file.begin() + static_cast<std::ptrdiff_t>(udp + 8)),
            true);
}

TEST(LidarPcap, RoundTrip) {
  std::vector<std::uint8_t> file = pcap_global_header();
  const std::vector<std::size_t> sizes = {0, 1, 7, 1206, 1206, 554, 1472, 9000, 65507};
  std::vector<TimeNs> times;
  for (std::size_t i = 0; i < sizes.size(); ++i) {
    times.push_back(3 * kNsPerSecond + static_cast<TimeNs>(i) * 1'327'104 + 999);
    const UdpEndpoint src{kSensor.ip + static_cast<std::uint32_t>(i), static_cast<std::uint16_t>(1000 + i)};
    append_udp_record(file, times.back(), src, kHost, payload_of(sizes[i], static_cast<std::uint8_t>(i)));
  }
  const PcapParseResult parsed = parse_pcap(file);
  ASSERT_TRUE(parsed.ok()) << to_string(parsed.error);
  ASSERT_EQ(parsed.datagrams.size(), sizes.size());
  for (std::size_t i = 0; i < sizes.size(); ++i) {
    const UdpDatagram& d = parsed.datagrams[i];
    EXPECT_EQ(d.time_ns, times[i] / 1000 * 1000);
    EXPECT_EQ(d.src.ip, kSensor.ip + i);
    EXPECT_EQ(d.src.port, 1000 + i);
    EXPECT_EQ(d.dst.ip, kHost.ip);
    EXPECT_EQ(d.dst.port, 2368);
    EXPECT_EQ(d.payload, payload_of(sizes[i], static_cast<std::uint8_t>(i)));
  }
}

// Fed in pieces of any size (a file read in chunks), the reader yields exactly what the whole-file
// parse does.
TEST(LidarPcap, ReaderFedInPiecesEqualsTheWholeFile) {
  std::vector<std::uint8_t> file = pcap_global_header();
  for (int i = 0; i < 40; ++i) {
    append_udp_record(file, kNsPerSecond + i * 1000, kSensor, kHost,
                      payload_of(static_cast<std::size_t>(17 * i % 1300), static_cast<std::uint8_t>(i)));
  }
  const PcapParseResult whole = parse_pcap(file);
  ASSERT_TRUE(whole.ok());
  for (const std::size_t piece : {1UL, 7UL, 24UL, 1000UL, 4096UL}) {
    PcapReader reader;
    std::vector<UdpDatagram> got;
    UdpDatagram d;
    for (std::size_t at = 0; at < file.size(); at += piece) {
      reader.feed(std::span(file).subspan(at, std::min(piece, file.size() - at)));
      for (PcapReader::Next n = reader.next(d); n != PcapReader::Next::need_more; n = reader.next(d)) {
        ASSERT_EQ(n, PcapReader::Next::datagram);
        got.push_back(d);
      }
    }
    EXPECT_EQ(reader.finish(), PcapError::none);
    EXPECT_EQ(reader.records(), 40U);
    ASSERT_EQ(got.size(), whole.datagrams.size()) << piece;
    for (std::size_t i = 0; i < got.size(); ++i) {
      EXPECT_EQ(got[i].time_ns, whole.datagrams[i].time_ns);
      EXPECT_EQ(got[i].payload, whole.datagrams[i].payload);
    }
  }
}

TEST(LidarPcap, TruncatedFilesAreRejectedKeepingCompleteRecords) {
  std::vector<std::uint8_t> file = pcap_global_header();
  std::vector<std::size_t> record_ends;
  for (int i = 0; i < 3; ++i) {
    append_udp_record(file, kNsPerSecond * (i + 1), kSensor, kHost,
                      payload_of(30 + 10 * static_cast<std::size_t>(i), 1));
    record_ends.push_back(file.size());
  }
  for (std::size_t n = 0; n < file.size(); ++n) {
    const PcapParseResult r = parse_pcap(std::span(file).first(n));
    std::size_t complete = 0;
    std::size_t record_start = 24;
    for (const std::size_t end : record_ends) {
      if (n >= end) {
        ++complete;
        record_start = end;
      }
    }
    PcapError expected = PcapError::none;
    if (n < 24) {
      expected = PcapError::truncated_file_header;
    } else if (n == record_start) {
      expected = PcapError::none;  // ends cleanly between records
    } else if (n < record_start + 16) {
      expected = PcapError::truncated_record_header;
    } else {
      expected = PcapError::truncated_record;
    }
    ASSERT_EQ(r.error, expected) << "length " << n << ": " << to_string(r.error);
    ASSERT_EQ(r.datagrams.size(), complete) << "length " << n;
  }
}

TEST(LidarPcap, RejectsForeignFiles) {
  std::vector<std::uint8_t> file = pcap_global_header();
  append_udp_record(file, 0, kSensor, kHost, payload_of(10, 0));
  auto bad = file;
  bad[0] = 0x00;
  EXPECT_EQ(parse_pcap(bad).error, PcapError::bad_magic);
  bad = file;
  bad[0] = 0x0a, bad[1] = 0x0d, bad[2] = 0x0d, bad[3] = 0x0a;
  EXPECT_EQ(parse_pcap(bad).error, PcapError::pcapng_not_supported);
  bad = file;
  bad[20] = 101;  // raw IP
  EXPECT_EQ(parse_pcap(bad).error, PcapError::unsupported_link_type);
  bad = file;
  bad[24 + 8 + 2] = 0x10;  // captured length 0x100000 + ...
  EXPECT_EQ(parse_pcap(bad).error, PcapError::bad_record_length);
}

// A big-endian, nanosecond pcap written by hand: Linux cooked capture of one UDP datagram with
// checksums left at zero.
TEST(LidarPcap, ReadsBigEndianNanosecondLinuxCooked) {
  std::vector<std::uint8_t> f = {0xa1, 0xb2, 0x3c, 0x4d, 0, 2, 0,    4,    0, 0, 0, 0,
                                 0,    0,    0,    0,    0, 0, 0xff, 0xff, 0, 0, 0, 113};
  const std::vector<std::uint8_t> frame = {
      0,    0,    0,    1,    0, 6,  1,    2, 3,  4,  5, 6, 0,  0, 0x08, 0x00,               // SLL
      0x45, 0,    0,    31,   0, 0,  0x40, 0, 64, 17, 0, 0, 10, 0, 0,    1,    10, 0, 0, 2,  // IPv4
      0x09, 0x40, 0x09, 0x41, 0, 11, 0,    0,                                                // UDP
      'a',  'b',  'c'};
  const std::vector<std::uint8_t> record_header = {0,    0,    0,    5,
                                                   0x07, 0x5b, 0xcd, 0x15,
                                                   0,    0,    0,    static_cast<std::uint8_t>(frame.size()),
                                                   0,    0,    0,    static_cast<std::uint8_t>(frame.size())};
  f.insert(f.end(), record_header.begin(), record_header.end());
  f.insert(f.end(), frame.begin(), frame.end());
  const PcapParseResult r = parse_pcap(f);
  ASSERT_TRUE(r.ok()) << to_string(r.error);
  ASSERT_EQ(r.datagrams.size(), 1U);
  EXPECT_EQ(r.datagrams[0].time_ns, 5 * kNsPerSecond + 123'456'789);
  EXPECT_EQ(r.datagrams[0].src.ip, ipv4_address(10, 0, 0, 1));
  EXPECT_EQ(r.datagrams[0].src.port, 2368);
  EXPECT_EQ(r.datagrams[0].dst.port, 2369);
  EXPECT_EQ(r.datagrams[0].payload, (std::vector<std::uint8_t>{'a', 'b', 'c'}));
}

TEST(LidarPcap, SkipsFramesThatAreNotIntactUdp) {
  std::vector<std::uint8_t> good = pcap_global_header();
  append_udp_record(good, 0, kSensor, kHost, payload_of(20, 0));
  const std::size_t eth = 40;
  const std::size_t ip = eth + 14;
  auto with = [&](std::size_t at, std::uint8_t v) {
    auto f = good;
    f[at] = v;
    return parse_pcap(f);
  };
  EXPECT_EQ(with(eth + 12, 0x86).skipped.not_ipv4, 1U);  // 0x86DD: IPv6
  EXPECT_EQ(with(ip + 9, 6).skipped.not_udp, 1U);        // TCP
  EXPECT_EQ(with(ip + 6, 0x20).skipped.fragmented, 1U);  // more fragments
  EXPECT_EQ(with(ip, 0x65).skipped.malformed, 1U);       // IPv6 version nibble
  // The IPv4 total length past the frame: a frame cut by the snapshot length (original length larger
  // than the captured one) is unusable; a frame captured whole is read at its own length (early VLP-16
  // firmware sends position packets whose IPv4 length is its data packets'), its UDP length checked.
  auto cut = good;
  cut[ip + 2] = 0xFF;
  cut[37] += 1;  // original length 256 bytes more than captured
  EXPECT_EQ(parse_pcap(cut).skipped.malformed, 1U);
  const PcapParseResult long_ip = with(ip + 2, 0xFF);
  ASSERT_EQ(long_ip.datagrams.size(), 1U);
  EXPECT_EQ(long_ip.datagrams[0].payload, payload_of(20, 0));
  PcapReader reader;
  auto lying = good;
  lying[ip + 2] = 0xFF;
  reader.feed(lying);
  UdpDatagram d;
  EXPECT_EQ(reader.next(d), PcapReader::Next::datagram);
  EXPECT_EQ(reader.ip_lengths_repaired(), 1U);
  EXPECT_EQ(with(ip + 20 + 4, 0xFF).skipped.malformed, 1U);  // UDP length past the datagram
  EXPECT_EQ(with(28 + 3, 0x10).skipped.malformed, 1U);       // microseconds >= 1e6
  for (const auto& r : {with(eth + 12, 0x86), with(ip + 9, 6)}) {
    EXPECT_TRUE(r.ok());
    EXPECT_TRUE(r.datagrams.empty());
  }
  // An 802.1Q tag before the IPv4 ether type is looked through.
  auto tagged = good;
  const std::vector<std::uint8_t> tag = {0x81, 0x00, 0x00, 0x05};
  tagged.insert(tagged.begin() + static_cast<std::ptrdiff_t>(eth + 12), tag.begin(), tag.end());
  tagged[32] += 4;  // captured and original lengths
  tagged[36] += 4;
  const PcapParseResult r = parse_pcap(tagged);
  ASSERT_TRUE(r.ok());
  ASSERT_EQ(r.datagrams.size(), 1U);
  EXPECT_EQ(r.datagrams[0].payload, payload_of(20, 0));
}

TEST(LidarPcap, RandomBytesNeverCrash) {
  std::mt19937_64 rng(8);
  std::uniform_int_distribution<int> byte(0, 255);
  std::uniform_int_distribution<std::size_t> length(0, 600);
  std::size_t parsed_ok = 0;
  for (int i = 0; i < 3000; ++i) {
    // Half start with a valid header so that record parsing is exercised.
    std::vector<std::uint8_t> f = i % 2 == 0 ? pcap_global_header() : std::vector<std::uint8_t>{};
    for (std::size_t n = length(rng); n > 0; --n) {
      f.push_back(static_cast<std::uint8_t>(byte(rng)));
    }
    if (i % 4 == 0 && f.size() > 40) {
      f[32] = static_cast<std::uint8_t>(f.size() - 40);  // a plausible captured length
      f[33] = f[34] = f[35] = 0;
    }
    const PcapParseResult r = parse_pcap(f);
    parsed_ok += r.ok() ? 1 : 0;
    for (const UdpDatagram& d : r.datagrams) {
      ASSERT_LE(d.payload.size(), f.size());
    }
  }
  EXPECT_GT(parsed_ok, 0U);
}

TEST(LidarPcap, WriterRefusesUnrepresentableInput) {
  std::vector<std::uint8_t> f;
  EXPECT_THROW(append_udp_record(f, -1, kSensor, kHost, {}), std::invalid_argument);
  EXPECT_THROW(append_udp_record(f, (TimeNs{1} << 32) * kNsPerSecond, kSensor, kHost, {}),
               std::invalid_argument);
  const std::vector<std::uint8_t> huge(65508);
  EXPECT_THROW(append_udp_record(f, 0, kSensor, kHost, huge), std::invalid_argument);
  EXPECT_TRUE(f.empty());
}

}  // namespace
}  // namespace rsu::lidar
