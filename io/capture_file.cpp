// SPDX-License-Identifier: Apache-2.0
#include "io/capture_file.h"
#include "io/text_file.h"

namespace rsu::io {
namespace {

constexpr std::size_t kChunkBytes = 1 << 20;

}  // namespace

CaptureFile::CaptureFile(const std::string& path) : path_(path), chunk_(kChunkBytes) {
  open();
  // Read until the header is judged, so that a file we cannot read is refused now, not mid-replay.
  lidar::UdpDatagram first;
  lidar::PcapReader probe;
  std::ifstream head(path_, std::ios::binary);
  std::vector<std::uint8_t> bytes(24);
  head.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  bytes.resize(static_cast<std::size_t>(head.gcount()));
  probe.feed(bytes);
  if (probe.next(first) == lidar::PcapReader::Next::error || bytes.size() < 24) {
    const lidar::PcapError e =
        probe.error() != lidar::PcapError::none ? probe.error() : lidar::PcapError::truncated_file_header;
    switch (e) {
      case lidar::PcapError::pcapng_not_supported:
        throw CaptureError(path_ + ": a pcapng file; convert it to a classic pcap first: editcap -F pcap " +
                           path_ + " capture.pcap (or: tcpdump -r " + path_ + " -w capture.pcap)");
      case lidar::PcapError::unsupported_link_type:
        throw CaptureError(path_ + ": a pcap of a link type other than Ethernet or Linux cooked capture");
      default:
        throw CaptureError(path_ + ": not a pcap capture (" + std::string(to_string(e)) + ")");
    }
  }
}

void CaptureFile::open() {
  in_.close();
  in_.clear();
  in_.open(path_, std::ios::binary);
  if (!in_) {
    throw CaptureError(path_ + ": cannot open: " + errno_text());
  }
  reader_ = lidar::PcapReader();
  at_end_ = false;
  error_ = lidar::PcapError::none;
}

bool CaptureFile::next(lidar::UdpDatagram& out) {
  for (;;) {
    switch (reader_.next(out)) {
      case lidar::PcapReader::Next::datagram:
        return true;
      case lidar::PcapReader::Next::skipped:
        continue;
      case lidar::PcapReader::Next::error:
        error_ = reader_.error();
        return false;
      case lidar::PcapReader::Next::need_more:
        break;
    }
    if (at_end_) {
      error_ = reader_.finish();
      return false;
    }
    in_.read(reinterpret_cast<char*>(chunk_.data()), static_cast<std::streamsize>(chunk_.size()));
    const auto got = static_cast<std::size_t>(in_.gcount());
    if (got == 0) {
      at_end_ = true;
      continue;
    }
    reader_.feed(std::span<const std::uint8_t>(chunk_.data(), got));
  }
}

void CaptureFile::rewind() {
  const lidar::PcapSkipped s = reader_.skipped();
  skipped_before_.not_ipv4 += s.not_ipv4;
  skipped_before_.not_udp += s.not_udp;
  skipped_before_.fragmented += s.fragmented;
  skipped_before_.malformed += s.malformed;
  records_before_ += reader_.records();
  reassembled_before_ += reader_.reassembled();
  repaired_before_ += reader_.ip_lengths_repaired();
  open();
}

lidar::PcapSkipped CaptureFile::skipped() const {
  lidar::PcapSkipped s = reader_.skipped();
  s.not_ipv4 += skipped_before_.not_ipv4;
  s.not_udp += skipped_before_.not_udp;
  s.fragmented += skipped_before_.fragmented;
  s.malformed += skipped_before_.malformed;
  return s;
}

std::uint64_t CaptureFile::records() const {
  return records_before_ + reader_.records();
}

std::uint64_t CaptureFile::ip_lengths_repaired() const {
  return repaired_before_ + reader_.ip_lengths_repaired();
}

std::uint64_t CaptureFile::reassembled() const {
  return reassembled_before_ + reader_.reassembled();
}

}  // namespace rsu::io
