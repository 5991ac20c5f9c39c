// SPDX-License-Identifier: Apache-2.0
#include "lidar/packet_order.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <stdexcept>

namespace rsu::lidar {

PacketOrder::PacketOrder(const PacketOrderConfig& config, TimeNs packet_period_ns, TimeNs max_gap_ns)
    : config_(config), period_ns_(packet_period_ns), max_gap_ns_(max_gap_ns) {
  if (packet_period_ns <= 0 || max_gap_ns <= 0)
    throw std::invalid_argument("PacketOrder: packet period and maximum gap must be positive");
}

bool PacketOrder::push(TimeNs t, std::span<const LidarPoint> points, TimeNs next_due_ns) {
  if (released_any_ || !held_.empty()) {
    const TimeNs reference = held_.empty() ? last_released_ : newest_;
    if (t < reference - max_gap_ns_) {
      // Far back in time: the stream restarted (e.g. the sensor's clock was reset). What is held
      // belongs to the old stream and would make every new packet "late": given up as lost.
      stats_.lost += held_.size();
      held_.clear();
      released_any_ = false;
      ++stats_.stream_gaps;
    }
  }
  if (released_any_ && t <= last_released_) {
    ++(t == last_released_ ? stats_.duplicate : stats_.late);
    return false;
  }
  auto it = held_.end();
  while (it != held_.begin() && std::prev(it)->time >= t)
    --it;
  if (it != held_.end() && it->time == t) {
    ++stats_.duplicate;
    return false;
  }
  if (!held_.empty() && t < newest_)
    ++stats_.reordered;
  newest_ = held_.empty() && !released_any_ ? t : std::max(newest_, t);
  Held h;
  h.time = t;
  h.next_due = next_due_ns > t ? next_due_ns : t + period_ns_;
  if (!spare_.empty()) {
    h.points = std::move(spare_.back());
    spare_.pop_back();
  }
  h.points.assign(points.begin(), points.end());
  held_.insert(it, std::move(h));
  return true;
}

bool PacketOrder::pop(std::vector<LidarPoint>& out, bool everything) {
  if (held_.empty() || (!everything && held_.size() <= config_.depth))
    return false;
  Held& next = held_.front();
  if (released_any_)
    count_gap(last_released_next_due_, next.time);
  last_released_ = next.time;
  last_released_next_due_ = next.next_due;
  released_any_ = true;
  ++stats_.released;
  out.swap(next.points);
  next.points.clear();
  if (spare_.size() <= config_.depth + 1)
    spare_.push_back(std::move(next.points));
  held_.pop_front();
  return true;
}

void PacketOrder::count_gap(TimeNs previous_next_due, TimeNs next) {
  const TimeNs gap = next - previous_next_due;  // 0 when nothing is missing
  if (gap > max_gap_ns_) {
    ++stats_.stream_gaps;
    return;
  }
  const auto periods = std::llround(static_cast<double>(gap) / static_cast<double>(period_ns_));
  if (periods > 0)
    stats_.lost += static_cast<std::uint64_t>(periods);
}

}  // namespace rsu::lidar
