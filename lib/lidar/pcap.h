// SPDX-License-Identifier: Apache-2.0
// Classic pcap files (the libpcap format, as `tcpdump -w` and VeloView write them) as pure byte
// formatting and parsing: rsud and rsu-decode replay recorded LiDAR traffic and tests write captures,
// with no file or socket here.
//
// Written: magic 0xa1b2c3d4 (microsecond timestamps) in little-endian order, version 2.4, snaplen
// 65535, link type 1 (Ethernet), each datagram as Ethernet II + IPv4 (header checksum) + UDP
// (checksum). Read: both byte orders, microsecond or nanosecond magic, link types 1 (Ethernet,
// optionally 802.1Q tagged) and 113 (Linux cooked capture, `tcpdump -i any`); IPv4 fragments are
// reassembled (ipv4_reassembly.h).
#pragma once

#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include "common/time.h"
#include "lidar/ipv4_reassembly.h"

namespace rsu::lidar {

struct UdpEndpoint {
  std::uint32_t ip = 0;  // host order: 192.168.1.201 is 0xC0A801C9
  std::uint16_t port = 0;
};

constexpr std::uint32_t ipv4_address(std::uint8_t a, std::uint8_t b, std::uint8_t c, std::uint8_t d) {
  return (std::uint32_t{a} << 24) | (std::uint32_t{b} << 16) | (std::uint32_t{c} << 8) | std::uint32_t{d};
}

// The 24-byte file header.
std::vector<std::uint8_t> pcap_global_header();

// Appends one record holding a UDP datagram. The record time is `time_ns` floored to the microsecond.
// Throws std::invalid_argument if time_ns is negative or past 2^32 s, or the payload exceeds the
// IPv4 UDP maximum of 65507 bytes.
void append_udp_record(std::vector<std::uint8_t>& out, TimeNs time_ns, UdpEndpoint src, UdpEndpoint dst,
                       std::span<const std::uint8_t> payload);

struct UdpDatagram {
  TimeNs time_ns = 0;  // capture time
  UdpEndpoint src;
  UdpEndpoint dst;
  std::vector<std::uint8_t> payload;
};

// Errors that stop parsing (the file is not a usable pcap from that point on).
enum class PcapError {
  none,
  truncated_file_header,    // fewer than 24 bytes
  bad_magic,                // not a pcap file
  pcapng_not_supported,     // a pcapng file (convert with `editcap -F pcap`)
  unsupported_link_type,    // not Ethernet or Linux cooked capture
  truncated_record_header,  // bytes left over that do not make a 16-byte record header
  truncated_record,         // a record's captured length runs past the end of the data
  bad_record_length,        // captured length larger than any snapshot length (262144)
};
std::string_view to_string(PcapError error);

// Records that are valid pcap but not an intact IPv4 UDP datagram; skipped and counted.
struct PcapSkipped {
  std::uint64_t not_ipv4 = 0;
  std::uint64_t not_udp = 0;
  std::uint64_t fragmented = 0;  // fragmented IPv4 datagrams that could not be put together
                                 // (incomplete, inconsistent or oversized: ipv4_reassembly.h)
  std::uint64_t malformed = 0;   // bad IPv4/UDP header or lengths, cut by the snapshot length, bad time
};

struct PcapParseResult {
  PcapError error = PcapError::none;
  // Every datagram before the error, if any: a capture cut off mid-record (a killed tcpdump) still
  // yields its complete records, while error says that the file did not end cleanly.
  std::vector<UdpDatagram> datagrams;
  PcapSkipped skipped;
  // UDP datagrams that arrived as IPv4 fragments and were put back together (every Ouster lidar
  // packet on a 1500-byte link), included in `datagrams` at the capture time of their last fragment.
  std::uint64_t reassembled = 0;

  bool ok() const { return error == PcapError::none; }
};

// Reads a capture record by record from its bytes handed in piece by piece (a file read in chunks, so
// that a long recording never has to fit in memory). IPv4 fragments are put back together
// (ipv4_reassembly.h). Checksums are not verified: captures of locally sent traffic carry unfilled
// checksums when the NIC offloads them.
class PcapReader {
 public:
  enum class Next {
    datagram,   // `out` holds the next UDP datagram
    skipped,    // a record that is not an intact IPv4 UDP datagram (counted in skipped())
    need_more,  // feed() more bytes (or finish() at the end of the file)
    error,      // the file is not usable from here on (error())
  };

  // The next part of the file.
  void feed(std::span<const std::uint8_t> bytes);
  Next next(UdpDatagram& out);
  // The end of the file: gives up fragments still incomplete (counted) and sets and returns the error
  // if bytes are left that make no whole record.
  PcapError finish();

  PcapError error() const { return error_; }
  PcapSkipped skipped() const;
  std::uint64_t reassembled() const { return reassembler_.stats().reassembled; }
  std::uint64_t records() const { return records_; }  // records read, whatever they held
  // Whole frames shorter than their IPv4 length, read at their own length (early VLP-16 firmware's
  // position packets: pcap.cpp).
  std::uint64_t ip_lengths_repaired() const { return ip_lengths_repaired_; }

 private:
  bool read_header();

  std::vector<std::uint8_t> buffer_;
  std::size_t at_ = 0;  // first unread byte of buffer_
  bool header_read_ = false;
  bool big_endian_ = false;
  TimeNs ns_per_fraction_ = kNsPerUs;
  std::uint32_t link_type_ = 0;
  PcapError error_ = PcapError::none;
  PcapSkipped skipped_;  // without the reassembler's
  Ipv4Reassembler reassembler_;
  std::uint64_t records_ = 0;
  std::uint64_t ip_lengths_repaired_ = 0;
};

// A whole capture in memory (tests, small files): PcapReader over all of `bytes`.
PcapParseResult parse_pcap(std::span<const std::uint8_t> bytes);

}  // namespace rsu::lidar
