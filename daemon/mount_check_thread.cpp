// SPDX-License-Identifier: Apache-2.0
#include "daemon/mount_check_thread.h"

#include <boost/asio/post.hpp>

#include <pthread.h>

#include <algorithm>
#include <memory>
#include <utility>

namespace rsu::daemon {

MountCheckThread::MountCheckThread(boost::asio::io_context& io, Checked checked, std::size_t max_waiting)
    : io_(io), checked_(std::move(checked)), max_waiting_(std::max<std::size_t>(1, max_waiting)) {
  thread_ = std::thread([this] { run(); });
  pthread_setname_np(thread_.native_handle(), "rsud-mount");
}

MountCheckThread::~MountCheckThread() {
  {
    const std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_one();
  thread_.join();
}

void MountCheckThread::submit(core::MountRotations rotations) {
  if (!rotations.reference && !rotations.source)
    return;
  {
    const std::lock_guard lock(mutex_);
    waiting_rotations_ += rotations.rotations.size();
    waiting_.push_back(std::move(rotations));
    while (waiting_rotations_ > max_waiting_ && waiting_.size() > 1 && !waiting_.front().source) {
      waiting_rotations_ -= waiting_.front().rotations.size();
      dropped_.fetch_add(waiting_.front().rotations.size(), std::memory_order_relaxed);
      waiting_.pop_front();
    }
  }
  wake_.notify_one();
}

void MountCheckThread::run() {
  for (;;) {
    core::MountRotations next;
    {
      std::unique_lock lock(mutex_);
      wake_.wait(lock, [this] { return stopping_ || !waiting_.empty(); });
      if (stopping_)
        return;
      next = std::move(waiting_.front());
      waiting_.pop_front();
      waiting_rotations_ -= next.rotations.size();
    }
    auto checks = std::make_shared<const core::MountChecks>(core::check_mount_rotations(std::move(next)));
    // Handlers posted from this one thread run in the order posted: the rotations' order. (The callback
    // is copied: a handler still queued when this object is gone must not reach into it.)
    boost::asio::post(io_, [checked = checked_, checks] { checked(*checks); });
  }
}

}  // namespace rsu::daemon
