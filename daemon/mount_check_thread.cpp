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
  if (!rotations.reference || rotations.rotations.empty())
    return;
  {
    const std::lock_guard lock(mutex_);
    // One rotation an entry, so that the bound counts rotations and the oldest go first.
    for (lidar::LidarFrame& rotation : rotations.rotations) {
      std::vector<lidar::LidarFrame> one;
      one.push_back(std::move(rotation));
      waiting_.push_back(core::MountRotations{rotations.reference, std::move(one)});
    }
    while (waiting_.size() > max_waiting_) {
      waiting_.pop_front();
      dropped_.fetch_add(1, std::memory_order_relaxed);
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
    }
    auto drifts = std::make_shared<std::vector<calibration::MountDrift>>();
    for (const lidar::LidarFrame& rotation : next.rotations)
      drifts->push_back(next.reference->estimate(rotation.points, Pose3{}));
    // Handlers posted from this one thread run in the order posted: the rotations' order.
    // (The callback is copied: a handler still queued when this object is gone must not reach into it.)
    boost::asio::post(
        io_, [checked = checked_, done = std::make_shared<core::MountRotations>(std::move(next)), drifts] {
          checked(*done, *drifts);
        });
  }
}

}  // namespace rsu::daemon
