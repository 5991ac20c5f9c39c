// SPDX-License-Identifier: Apache-2.0
// A capture file (classic pcap) read datagram by datagram in chunks, so that a recording of any length
// replays in constant memory (lib/lidar/pcap.h parses the bytes). Used by rsud's capture input and
// rsu-decode.
#pragma once

#include <cstdint>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "lidar/pcap.h"

namespace rsu::io {

class CaptureError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class CaptureFile {
 public:
  // Opens `path` and reads its header. Throws CaptureError naming the file for a missing file, a
  // pcapng file (with the command that converts it), or anything else that is not a classic pcap of a
  // link type we read.
  explicit CaptureFile(const std::string& path);

  // The next UDP datagram; false at the end of the file or where the file stops being readable
  // (error() then says why: a capture cut off mid-record).
  bool next(lidar::UdpDatagram& out);
  // Back to the first record (the counts go on).
  void rewind();

  lidar::PcapError error() const { return error_; }
  lidar::PcapSkipped skipped() const;  // over every pass
  std::uint64_t records() const;
  std::uint64_t reassembled() const;
  std::uint64_t ip_lengths_repaired() const;  // lib/lidar/pcap.h
  const std::string& path() const { return path_; }

 private:
  void open();

  std::string path_;
  std::ifstream in_;
  lidar::PcapReader reader_;
  std::vector<std::uint8_t> chunk_;
  lidar::PcapError error_ = lidar::PcapError::none;
  bool at_end_ = false;
  // Counts of the passes before the current one (rewind() starts a fresh reader).
  lidar::PcapSkipped skipped_before_;
  std::uint64_t records_before_ = 0;
  std::uint64_t reassembled_before_ = 0;
  std::uint64_t repaired_before_ = 0;
};

}  // namespace rsu::io
