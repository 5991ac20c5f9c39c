// SPDX-License-Identifier: Apache-2.0
// pcap formatting and parsing (see pcap.h). Layouts: libpcap file format (tcpdump.org "pcap-savefile"),
// Ethernet II, IPv4 (RFC 791, checksum RFC 1071), UDP (RFC 768).
#include "lidar/pcap.h"

#include <optional>
#include <stdexcept>

#include "lidar/ipv4_reassembly.h"

namespace rsu::lidar {
namespace {

constexpr std::uint32_t kMagicMicro = 0xa1b2c3d4;
constexpr std::uint32_t kMagicNano = 0xa1b23c4d;
constexpr std::uint32_t kMagicMicroSwapped = 0xd4c3b2a1;
constexpr std::uint32_t kMagicNanoSwapped = 0x4d3cb2a1;
constexpr std::uint32_t kMagicPcapng = 0x0a0d0d0a;  // section header block type, same in both orders
constexpr std::size_t kFileHeaderBytes = 24;
constexpr std::size_t kRecordHeaderBytes = 16;
constexpr std::uint32_t kMaxCapturedLength = 262144;  // libpcap's largest snapshot length
constexpr std::uint32_t kLinkEthernet = 1;
constexpr std::uint32_t kLinkLinuxCooked = 113;

constexpr std::size_t kEthernetBytes = 14;
constexpr std::size_t kLinuxCookedBytes = 16;
constexpr std::size_t kIpv4Bytes = 20;
constexpr std::size_t kUdpBytes = 8;
constexpr std::uint16_t kEtherTypeIpv4 = 0x0800;
constexpr std::uint16_t kEtherTypeVlan = 0x8100;
constexpr std::uint16_t kEtherTypeQinQ = 0x88A8;
constexpr std::uint8_t kProtocolUdp = 17;
constexpr std::size_t kMaxUdpPayload = 65535 - kIpv4Bytes - kUdpBytes;

// Little-endian file fields (we write the host-independent LE form).
void put_le32(std::vector<std::uint8_t>& out, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) {
    out.push_back(static_cast<std::uint8_t>((v >> (8 * i)) & 0xFF));
  }
}
void put_le16(std::vector<std::uint8_t>& out, std::uint16_t v) {
  out.push_back(static_cast<std::uint8_t>(v & 0xFF));
  out.push_back(static_cast<std::uint8_t>(v >> 8));
}
// Network byte order (big-endian) header fields.
void put_be16(std::vector<std::uint8_t>& out, std::uint16_t v) {
  out.push_back(static_cast<std::uint8_t>(v >> 8));
  out.push_back(static_cast<std::uint8_t>(v & 0xFF));
}
void put_be32(std::vector<std::uint8_t>& out, std::uint32_t v) {
  put_be16(out, static_cast<std::uint16_t>(v >> 16));
  put_be16(out, static_cast<std::uint16_t>(v & 0xFFFF));
}

std::uint16_t get_be16(std::span<const std::uint8_t> b, std::size_t at) {
  return static_cast<std::uint16_t>((b[at] << 8) | b[at + 1]);
}
std::uint32_t get_be32(std::span<const std::uint8_t> b, std::size_t at) {
  return (std::uint32_t{get_be16(b, at)} << 16) | get_be16(b, at + 2);
}
std::uint32_t get_u32(std::span<const std::uint8_t> b, std::size_t at, bool big_endian) {
  const std::uint32_t v0 = b[at], v1 = b[at + 1], v2 = b[at + 2], v3 = b[at + 3];
  return big_endian ? (v0 << 24) | (v1 << 16) | (v2 << 8) | v3 : v0 | (v1 << 8) | (v2 << 16) | (v3 << 24);
}

// RFC 1071 ones'-complement sum of 16-bit big-endian words (odd byte padded with zero), not yet
// complemented; `sum` carries a partial sum in.
std::uint32_t ones_complement_add(std::span<const std::uint8_t> bytes, std::uint32_t sum) {
  for (std::size_t i = 0; i < bytes.size(); i += 2) {
    const std::uint32_t hi = bytes[i];
    const std::uint32_t lo = i + 1 < bytes.size() ? bytes[i + 1] : 0;
    sum += (hi << 8) | lo;
    sum = (sum & 0xFFFF) + (sum >> 16);
  }
  return sum;
}
std::uint16_t finish_checksum(std::uint32_t sum) {
  while (sum >> 16) {
    sum = (sum & 0xFFFF) + (sum >> 16);
  }
  return static_cast<std::uint16_t>(~sum & 0xFFFF);
}

// One captured frame -> UDP datagram, or the reason it is not one. A fragment is handed back in
// `fragment` (its data a view into `frame`) for the reassembler.
enum class FrameKind { udp, not_ipv4, not_udp, fragment, malformed };

// The UDP datagram in an IPv4 payload.
FrameKind parse_udp(std::uint32_t src_ip, std::uint32_t dst_ip, std::span<const std::uint8_t> udp,
                    UdpDatagram& out) {
  if (udp.size() < kUdpBytes) {
    return FrameKind::malformed;
  }
  const std::size_t udp_bytes = get_be16(udp, 4);
  if (udp_bytes < kUdpBytes || udp_bytes > udp.size()) {
    return FrameKind::malformed;
  }
  out.src = {src_ip, get_be16(udp, 0)};
  out.dst = {dst_ip, get_be16(udp, 2)};
  const auto payload = udp.subspan(kUdpBytes, udp_bytes - kUdpBytes);
  out.payload.assign(payload.begin(), payload.end());
  return FrameKind::udp;
}

// The IPv4 packet after the link-layer header, or why there is none.
FrameKind link_payload(std::span<const std::uint8_t> frame, std::uint32_t link_type,
                       std::span<const std::uint8_t>& ip) {
  std::size_t l3 = 0;
  std::uint16_t ether_type = 0;
  if (link_type == kLinkEthernet) {
    if (frame.size() < kEthernetBytes) {
      return FrameKind::malformed;
    }
    ether_type = get_be16(frame, 12);
    l3 = kEthernetBytes;
    while (ether_type == kEtherTypeVlan || ether_type == kEtherTypeQinQ) {  // 4-byte 802.1Q tags
      if (frame.size() < l3 + 4) {
        return FrameKind::malformed;
      }
      ether_type = get_be16(frame, l3 + 2);
      l3 += 4;
    }
  } else {  // Linux cooked capture: protocol type at bytes 14..15
    if (frame.size() < kLinuxCookedBytes) {
      return FrameKind::malformed;
    }
    ether_type = get_be16(frame, 14);
    l3 = kLinuxCookedBytes;
  }
  if (ether_type != kEtherTypeIpv4) {
    return FrameKind::not_ipv4;
  }
  ip = frame.subspan(l3);
  return FrameKind::udp;
}

// `whole`: the record holds the frame as it was on the wire (not cut by the snapshot length).
FrameKind parse_frame(std::span<const std::uint8_t> frame, std::uint32_t link_type, bool whole,
                      UdpDatagram& out, Ipv4Fragment& fragment, bool& length_repaired) {
  std::span<const std::uint8_t> ip;
  if (const FrameKind kind = link_payload(frame, link_type, ip); kind != FrameKind::udp) {
    return kind;
  }
  if (ip.size() < kIpv4Bytes || (ip[0] >> 4) != 4) {
    return FrameKind::malformed;
  }
  const std::size_t header_bytes = std::size_t{ip[0] & 0x0Fu} * 4;
  std::size_t total_bytes = get_be16(ip, 2);
  // Early VLP-16 firmware writes its data packets' IPv4 length (1234) into its 554-byte position
  // packets: a frame captured whole that is shorter than its IPv4 length is taken at its own length
  // (the UDP length is still checked), while a datagram cut by the snapshot length is not usable.
  if (whole && total_bytes > ip.size() && ip.size() >= header_bytes) {
    total_bytes = ip.size();
    length_repaired = true;
  }
  if (header_bytes < kIpv4Bytes || total_bytes < header_bytes || total_bytes > ip.size()) {
    return FrameKind::malformed;
  }
  const std::uint16_t flags_offset = get_be16(ip, 6);
  if ((flags_offset & 0x3FFF) != 0) {  // more-fragments flag or a fragment offset
    fragment.src = get_be32(ip, 12);
    fragment.dst = get_be32(ip, 16);
    fragment.protocol = ip[9];
    fragment.identification = get_be16(ip, 4);
    fragment.offset_bytes = std::size_t{flags_offset & 0x1FFFu} * 8;
    fragment.more_fragments = (flags_offset & 0x2000) != 0;
    fragment.data = ip.subspan(header_bytes, total_bytes - header_bytes);
    return FrameKind::fragment;
  }
  if (ip[9] != kProtocolUdp) {
    return FrameKind::not_udp;
  }
  return parse_udp(get_be32(ip, 12), get_be32(ip, 16), ip.subspan(header_bytes, total_bytes - header_bytes),
                   out);
}

}  // namespace

std::vector<std::uint8_t> pcap_global_header() {
  std::vector<std::uint8_t> h;
  h.reserve(kFileHeaderBytes);
  put_le32(h, kMagicMicro);
  put_le16(h, 2);  // version 2.4
  put_le16(h, 4);
  put_le32(h, 0);      // this zone (always 0)
  put_le32(h, 0);      // sigfigs (always 0)
  put_le32(h, 65535);  // snapshot length
  put_le32(h, kLinkEthernet);
  return h;
}

void append_udp_record(std::vector<std::uint8_t>& out, TimeNs time_ns, UdpEndpoint src, UdpEndpoint dst,
                       std::span<const std::uint8_t> payload) {
  if (time_ns < 0 || time_ns / kNsPerSecond > TimeNs{0xFFFFFFFF}) {
    throw std::invalid_argument("append_udp_record: time outside the pcap range [0, 2^32 s)");
  }
  if (payload.size() > kMaxUdpPayload) {
    throw std::invalid_argument("append_udp_record: UDP payload larger than 65507 bytes");
  }
  const auto udp_length = static_cast<std::uint16_t>(kUdpBytes + payload.size());
  const auto ip_length = static_cast<std::uint16_t>(kIpv4Bytes + udp_length);
  const auto frame_length = static_cast<std::uint32_t>(kEthernetBytes + ip_length);

  put_le32(out, static_cast<std::uint32_t>(time_ns / kNsPerSecond));
  put_le32(out, static_cast<std::uint32_t>((time_ns % kNsPerSecond) / kNsPerUs));
  put_le32(out, frame_length);  // captured length
  put_le32(out, frame_length);  // original length

  // Ethernet II: broadcast destination (a Velodyne's default), a locally administered source.
  for (const std::uint8_t byte : {0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0x02, 0x00, 0x00, 0x00, 0x00, 0x01}) {
    out.push_back(byte);
  }
  put_be16(out, kEtherTypeIpv4);

  const std::size_t ip_at = out.size();
  out.push_back(0x45);  // version 4, 5-word header
  out.push_back(0x00);  // DSCP / ECN
  put_be16(out, ip_length);
  put_be16(out, 0);       // identification
  put_be16(out, 0x4000);  // don't fragment
  out.push_back(64);      // TTL
  out.push_back(kProtocolUdp);
  put_be16(out, 0);  // checksum, filled below
  put_be32(out, src.ip);
  put_be32(out, dst.ip);
  const std::uint16_t ip_checksum =
      finish_checksum(ones_complement_add(std::span(out).subspan(ip_at, kIpv4Bytes), 0));
  out[ip_at + 10] = static_cast<std::uint8_t>(ip_checksum >> 8);
  out[ip_at + 11] = static_cast<std::uint8_t>(ip_checksum & 0xFF);

  const std::size_t udp_at = out.size();
  put_be16(out, src.port);
  put_be16(out, dst.port);
  put_be16(out, udp_length);
  put_be16(out, 0);  // checksum, filled below
  out.insert(out.end(), payload.begin(), payload.end());
  // UDP checksum over the pseudo-header (addresses, protocol, UDP length) and the datagram.
  std::uint32_t sum = ones_complement_add(std::span(out).subspan(ip_at + 12, 8), 0);
  sum += kProtocolUdp;
  sum += udp_length;
  sum = ones_complement_add(std::span(out).subspan(udp_at, udp_length), sum);
  std::uint16_t udp_checksum = finish_checksum(sum);
  if (udp_checksum == 0) {
    udp_checksum = 0xFFFF;  // 0 would mean "no checksum" (RFC 768)
  }
  out[udp_at + 6] = static_cast<std::uint8_t>(udp_checksum >> 8);
  out[udp_at + 7] = static_cast<std::uint8_t>(udp_checksum & 0xFF);
}

std::string_view to_string(PcapError error) {
  switch (error) {
    case PcapError::none:
      return "none";
    case PcapError::truncated_file_header:
      return "truncated_file_header";
    case PcapError::bad_magic:
      return "bad_magic";
    case PcapError::pcapng_not_supported:
      return "pcapng_not_supported";
    case PcapError::unsupported_link_type:
      return "unsupported_link_type";
    case PcapError::truncated_record_header:
      return "truncated_record_header";
    case PcapError::truncated_record:
      return "truncated_record";
    case PcapError::bad_record_length:
      return "bad_record_length";
  }
  return "unknown";
}

void PcapReader::feed(std::span<const std::uint8_t> bytes) {
  // Drop what was read once it is most of the buffer, so that the buffer stays about one chunk long.
  if (at_ > 0 && at_ >= buffer_.size() / 2) {
    buffer_.erase(buffer_.begin(), buffer_.begin() + static_cast<std::ptrdiff_t>(at_));
    at_ = 0;
  }
  buffer_.insert(buffer_.end(), bytes.begin(), bytes.end());
}

bool PcapReader::read_header() {
  const std::span<const std::uint8_t> bytes(buffer_);
  switch (get_u32(bytes, 0, false)) {
    case kMagicMicro:
      break;
    case kMagicNano:
      ns_per_fraction_ = 1;
      break;
    case kMagicMicroSwapped:
      big_endian_ = true;
      break;
    case kMagicNanoSwapped:
      big_endian_ = true;
      ns_per_fraction_ = 1;
      break;
    case kMagicPcapng:
      error_ = PcapError::pcapng_not_supported;
      return false;
    default:
      error_ = PcapError::bad_magic;
      return false;
  }
  // The link type is the low 16 bits; newer writers may put FCS information in the top bits.
  link_type_ = get_u32(bytes, 20, big_endian_) & 0xFFFF;
  if (link_type_ != kLinkEthernet && link_type_ != kLinkLinuxCooked) {
    error_ = PcapError::unsupported_link_type;
    return false;
  }
  at_ = kFileHeaderBytes;
  header_read_ = true;
  return true;
}

PcapReader::Next PcapReader::next(UdpDatagram& out) {
  if (error_ != PcapError::none) {
    return Next::error;
  }
  if (!header_read_) {
    if (buffer_.size() < kFileHeaderBytes) {
      return Next::need_more;
    }
    if (!read_header()) {
      return Next::error;
    }
  }
  for (;;) {  // until a datagram, a counted skip or the end of the bytes: fragments only gather
    const std::span<const std::uint8_t> bytes(buffer_);
    if (bytes.size() - at_ < kRecordHeaderBytes) {
      return Next::need_more;
    }
    const std::uint32_t seconds = get_u32(bytes, at_, big_endian_);
    const std::uint32_t fraction = get_u32(bytes, at_ + 4, big_endian_);
    const std::uint32_t captured = get_u32(bytes, at_ + 8, big_endian_);
    const std::uint32_t original = get_u32(bytes, at_ + 12, big_endian_);
    if (captured > kMaxCapturedLength) {
      error_ = PcapError::bad_record_length;
      return Next::error;
    }
    if (bytes.size() - at_ - kRecordHeaderBytes < captured) {
      return Next::need_more;
    }
    const std::span<const std::uint8_t> frame = bytes.subspan(at_ + kRecordHeaderBytes, captured);
    at_ += kRecordHeaderBytes + captured;
    ++records_;

    if (TimeNs{fraction} >= kNsPerSecond / ns_per_fraction_) {
      ++skipped_.malformed;
      return Next::skipped;
    }
    out.time_ns = TimeNs{seconds} * kNsPerSecond + TimeNs{fraction} * ns_per_fraction_;
    Ipv4Fragment fragment;
    fragment.time_ns = out.time_ns;
    bool repaired = false;
    FrameKind kind = parse_frame(frame, link_type_, captured >= original, out, fragment, repaired);
    ip_lengths_repaired_ += repaired ? 1 : 0;
    if (kind == FrameKind::fragment) {
      const std::optional<Ipv4Datagram> whole = reassembler_.add(fragment);
      if (!whole) {
        continue;  // waiting for the rest (or counted by the reassembler)
      }
      out.time_ns = whole->time_ns;
      kind = whole->protocol == kProtocolUdp ? parse_udp(whole->src, whole->dst, whole->payload, out)
                                             : FrameKind::not_udp;
    }
    switch (kind) {
      case FrameKind::udp:
        return Next::datagram;
      case FrameKind::not_ipv4:
        ++skipped_.not_ipv4;
        break;
      case FrameKind::not_udp:
        ++skipped_.not_udp;
        break;
      case FrameKind::fragment:  // handled above
        break;
      case FrameKind::malformed:
        ++skipped_.malformed;
        break;
    }
    return Next::skipped;
  }
}

PcapError PcapReader::finish() {
  reassembler_.finish();
  if (error_ != PcapError::none) {
    return error_;
  }
  const std::size_t left = buffer_.size() - at_;
  if (!header_read_) {
    error_ = PcapError::truncated_file_header;
  } else if (left > 0 && left < kRecordHeaderBytes) {
    error_ = PcapError::truncated_record_header;
  } else if (left > 0) {
    error_ = PcapError::truncated_record;
  }
  return error_;
}

PcapSkipped PcapReader::skipped() const {
  PcapSkipped s = skipped_;
  const ReassemblyStats& r = reassembler_.stats();
  s.fragmented = r.timed_out + r.overlapping + r.too_large;
  return s;
}

PcapParseResult parse_pcap(std::span<const std::uint8_t> bytes) {
  PcapReader reader;
  reader.feed(bytes);
  PcapParseResult result;
  UdpDatagram datagram;
  for (;;) {
    const PcapReader::Next next = reader.next(datagram);
    if (next == PcapReader::Next::datagram) {
      result.datagrams.push_back(std::move(datagram));
    } else if (next != PcapReader::Next::skipped) {
      break;
    }
  }
  result.error = reader.finish();
  result.skipped = reader.skipped();
  result.reassembled = reader.reassembled();
  return result;
}

}  // namespace rsu::lidar
