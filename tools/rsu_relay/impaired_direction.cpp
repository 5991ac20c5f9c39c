// SPDX-License-Identifier: Apache-2.0
#include "tools/rsu_relay/impaired_direction.h"

#include <algorithm>

#include "common/random.h"

namespace rsu::tools {
namespace {

// The random streams of one datagram's decisions.
constexpr std::uint64_t kLossDraw = 1;
constexpr std::uint64_t kReorderDraw = 2;
constexpr std::uint64_t kJitterDraw = 3;

}  // namespace

ImpairedDirection::ImpairedDirection(const LinkImpairment& link, std::uint64_t seed, std::uint64_t direction,
                                     TimeNs reorder_timeout)
    : link_(link), seed_(seed), direction_(direction), reorder_timeout_(reorder_timeout) {}

double ImpairedDirection::draw(std::uint64_t kind) const {
  return uniform_open01(mix64(seed_ ^ mix64((direction_ << 8 | kind) ^ mix64(index_))));
}

void ImpairedDirection::enqueue(TimeNs due, Datagram bytes) {
  queue_.emplace(Key{due, order_++}, std::move(bytes));
}

void ImpairedDirection::push(TimeNs now, Datagram bytes) {
  ++stats_.received;
  const bool lost = link_.loss > 0.0 && draw(kLossDraw) < link_.loss;
  const bool hold = !lost && !held_ && link_.reorder > 0.0 && draw(kReorderDraw) < link_.reorder;
  const double jitter_ms = link_.jitter_ms * (2.0 * draw(kJitterDraw) - 1.0);
  ++index_;
  if (lost) {
    ++stats_.dropped;
    return;
  }
  const TimeNs due = now + static_cast<TimeNs>(std::max(0.0, link_.delay_ms + jitter_ms) * 1e6);
  if (hold) {
    ++stats_.reordered;
    held_ = Held{due, std::move(bytes)};
    return;
  }
  enqueue(due, std::move(bytes));
  if (held_) {
    // The held one leaves right after this one (and never before its own time).
    enqueue(std::max(due, held_->due), std::move(held_->bytes));
    held_.reset();
  }
}

std::vector<ImpairedDirection::Datagram> ImpairedDirection::pop_due(TimeNs now) {
  if (held_ && held_->due + reorder_timeout_ <= now) {
    enqueue(held_->due + reorder_timeout_, std::move(held_->bytes));
    held_.reset();
  }
  std::vector<Datagram> out;
  while (!queue_.empty() && queue_.begin()->first.first <= now) {
    out.push_back(std::move(queue_.begin()->second));
    queue_.erase(queue_.begin());
  }
  stats_.forwarded += out.size();
  return out;
}

std::optional<TimeNs> ImpairedDirection::next_due() const {
  std::optional<TimeNs> next;
  if (!queue_.empty())
    next = queue_.begin()->first.first;
  if (held_) {
    const TimeNs release = held_->due + reorder_timeout_;
    next = next ? std::min(*next, release) : release;
  }
  return next;
}

}  // namespace rsu::tools
