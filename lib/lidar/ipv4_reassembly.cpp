// SPDX-License-Identifier: Apache-2.0
// IPv4 fragment reassembly (see ipv4_reassembly.h).
#include "lidar/ipv4_reassembly.h"

#include <algorithm>
#include <stdexcept>

namespace rsu::lidar {
namespace {

constexpr std::size_t kMaxIpPayload = 65535 - 20;  // total length field minus the smallest header

}  // namespace

Ipv4Reassembler::Ipv4Reassembler(TimeNs timeout_ns, std::size_t max_pending)
    : timeout_ns_(timeout_ns), max_pending_(max_pending) {
  if (timeout_ns <= 0 || max_pending == 0) {
    throw std::invalid_argument("Ipv4Reassembler: timeout and capacity must be positive");
  }
}

void Ipv4Reassembler::expire(TimeNs now) {
  std::erase_if(pending_, [&](const auto& entry) {
    const bool old = now - entry.second.first_ns > timeout_ns_;
    stats_.timed_out += old ? 1 : 0;
    return old;
  });
}

void Ipv4Reassembler::finish() {
  stats_.timed_out += pending_.size();
  pending_.clear();
}

bool Ipv4Reassembler::merge(Pending& p, const Ipv4Fragment& f) {
  const std::size_t end = f.offset_bytes + f.data.size();
  if (!f.more_fragments) {
    if (p.total && *p.total != end) {
      return false;  // two different ends
    }
    p.total = end;
  }
  if (p.total && end > *p.total) {
    return false;  // past the end the last fragment set
  }
  if (p.bytes.size() < end) {
    p.bytes.resize(end, 0);
    p.covered.resize(end, false);
  }
  for (std::size_t i = 0; i < f.data.size(); ++i) {
    const std::size_t at = f.offset_bytes + i;
    if (p.covered[at]) {
      if (p.bytes[at] != f.data[i]) {
        return false;  // overlapping fragments that disagree
      }
      continue;
    }
    p.bytes[at] = f.data[i];
    p.covered[at] = true;
    ++p.covered_count;
  }
  return true;
}

std::optional<Ipv4Datagram> Ipv4Reassembler::add(const Ipv4Fragment& fragment) {
  ++stats_.fragments;
  expire(fragment.time_ns);
  if (fragment.offset_bytes + fragment.data.size() > kMaxIpPayload) {
    ++stats_.too_large;
    return std::nullopt;
  }
  const Key key{fragment.src, fragment.dst, fragment.protocol, fragment.identification};
  auto it = pending_.find(key);
  if (it == pending_.end()) {
    if (pending_.size() >= max_pending_) {
      const auto oldest = std::min_element(
          pending_.begin(), pending_.end(),
          [](const auto& a, const auto& b) { return a.second.first_ns < b.second.first_ns; });
      pending_.erase(oldest);
      ++stats_.timed_out;
    }
    it = pending_.emplace(key, Pending{}).first;
    it->second.first_ns = fragment.time_ns;
  }
  Pending& p = it->second;
  if (!merge(p, fragment)) {
    pending_.erase(it);
    ++stats_.overlapping;
    return std::nullopt;
  }
  if (!p.total || p.covered_count != *p.total) {
    return std::nullopt;
  }
  Ipv4Datagram d{fragment.src, fragment.dst, fragment.protocol, fragment.time_ns, std::move(p.bytes)};
  pending_.erase(it);
  ++stats_.reassembled;
  return d;
}

}  // namespace rsu::lidar
