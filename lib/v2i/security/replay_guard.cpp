// SPDX-License-Identifier: Apache-2.0
#include "v2i/security/replay_guard.h"

#include <algorithm>

namespace rsu::v2i::security {

const char* to_string(ReplayVerdict verdict) {
  switch (verdict) {
    case ReplayVerdict::kFresh:
      return "fresh";
    case ReplayVerdict::kStale:
      return "stale";
    case ReplayVerdict::kFuture:
      return "future";
    case ReplayVerdict::kDuplicate:
      return "duplicate";
    case ReplayVerdict::kTooOld:
      return "too_old";
    case ReplayVerdict::kCount:
      break;
  }
  return "unknown";
}

SequenceWindow::Check SequenceWindow::check(std::uint32_t sequence) const {
  if (!started_) {
    return Check::kNew;
  }
  // RFC 1982: `sequence` is ahead of highest_ when the unsigned difference is in (0, 2^31).
  const std::uint32_t ahead = sequence - highest_;
  if (ahead != 0 && ahead < (1U << 31)) {
    return Check::kNew;
  }
  const std::uint32_t behind = highest_ - sequence;
  if (behind >= kWidth) {
    return Check::kTooOld;
  }
  return (seen_ >> behind) & 1U ? Check::kDuplicate : Check::kNew;
}

void SequenceWindow::accept(std::uint32_t sequence) {
  if (!started_) {
    restart(sequence);
    return;
  }
  const std::uint32_t ahead = sequence - highest_;
  if (ahead != 0 && ahead < (1U << 31)) {
    seen_ = ahead >= kWidth ? 0 : seen_ << ahead;
    seen_ |= 1U;
    highest_ = sequence;
  } else {
    seen_ |= std::uint64_t{1} << (highest_ - sequence);
  }
}

void SequenceWindow::restart(std::uint32_t sequence) {
  started_ = true;
  highest_ = sequence;
  seen_ = 1U;
}

ReplayGuard::SignerState& ReplayGuard::state_for(const KeyId& signer, TimeNs now, bool& fresh) {
  const auto it = signers_.find(signer);
  fresh = it == signers_.end();
  if (!fresh) {
    return it->second;
  }
  if (signers_.size() >= config_.max_signers && !signers_.empty()) {
    const auto oldest = std::min_element(signers_.begin(), signers_.end(), [](const auto& a, const auto& b) {
      return a.second.last_heard < b.second.last_heard;
    });
    signers_.erase(oldest);
    ++stats_.evictions;
  }
  SignerState& state = signers_[signer];
  state.last_heard = now;
  return state;
}

ReplayVerdict ReplayGuard::admit(const KeyId& signer, std::uint32_t sequence, TimeNs generation_time,
                                 TimeNs now) {
  if (generation_time < now - config_.max_age) {
    return ReplayVerdict::kStale;
  }
  if (generation_time > now + config_.max_future) {
    return ReplayVerdict::kFuture;
  }
  bool fresh = false;
  SignerState& s = state_for(signer, now, fresh);
  if (fresh) {
    s.window.restart(sequence);
    s.newest_generation = generation_time;
    return ReplayVerdict::kFresh;
  }
  if (generation_time < s.restarted_at) {
    return ReplayVerdict::kTooOld;  // generated before the signer restarted its counter
  }
  switch (s.window.check(sequence)) {
    case SequenceWindow::Check::kNew:
      s.window.accept(sequence);
      break;
    case SequenceWindow::Check::kDuplicate:
    case SequenceWindow::Check::kTooOld:
      if (generation_time <= s.newest_generation) {
        return s.window.check(sequence) == SequenceWindow::Check::kDuplicate ? ReplayVerdict::kDuplicate
                                                                             : ReplayVerdict::kTooOld;
      }
      // Newer than anything accepted, yet an old number: the signer restarted its counter.
      s.window.restart(sequence);
      s.restarted_at = generation_time;
      ++stats_.restarts;
      break;
  }
  s.newest_generation = std::max(s.newest_generation, generation_time);
  s.last_heard = now;
  return ReplayVerdict::kFresh;
}

ReplayVerdict ReplayGuard::check(const KeyId& signer, std::uint32_t sequence, TimeNs generation_time,
                                 TimeNs now) const {
  if (generation_time < now - config_.max_age) {
    return ReplayVerdict::kStale;
  }
  if (generation_time > now + config_.max_future) {
    return ReplayVerdict::kFuture;
  }
  const auto it = signers_.find(signer);
  if (it == signers_.end()) {
    return ReplayVerdict::kFresh;
  }
  const SignerState& s = it->second;
  if (generation_time < s.restarted_at) {
    return ReplayVerdict::kTooOld;
  }
  const SequenceWindow::Check c = s.window.check(sequence);
  if (c == SequenceWindow::Check::kNew || generation_time > s.newest_generation) {
    return ReplayVerdict::kFresh;  // new, or a restart of the signer's counter
  }
  return c == SequenceWindow::Check::kDuplicate ? ReplayVerdict::kDuplicate : ReplayVerdict::kTooOld;
}

void ReplayGuard::expire(TimeNs now) {
  for (auto it = signers_.begin(); it != signers_.end();) {
    if (now - it->second.last_heard > config_.signer_expiry) {
      it = signers_.erase(it);
      ++stats_.expired;
    } else {
      ++it;
    }
  }
}

}  // namespace rsu::v2i::security
