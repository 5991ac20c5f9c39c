// SPDX-License-Identifier: Apache-2.0
// rsud's mount check thread: registers each rotation's static scene against the mount's reference
// (core::check_mount_rotations: 2-3 ms of CPU a rotation of a 128 x 2048 LiDAR, and once, after
// learning, 40-52 ms to build the reference) off the event loop, which had held the LiDAR's packets
// behind it for as long (issue 16: correction latency). The loop hands over
// RsuCore::take_mount_rotations(); the checks come back to it, posted to the io_context in the order the
// rotations were swept, for RsuCore::record_mount_checks: the monitor's state (serving or stopped) is the
// loop's alone. The reference is immutable, and the background it is built from no longer changes.
#pragma once

#include <utility>  // before Asio: Boost 1.74's awaitable.hpp uses std::exchange under C++20

#include <boost/asio/io_context.hpp>

#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

#include "core/rsu_core.h"

namespace rsu::daemon {

class MountCheckThread {
 public:
  using Checked = std::function<void(const core::MountChecks&)>;

  // `checked` runs on `io`'s thread. At most `max_waiting` rotations wait: beyond that the oldest are
  // dropped and counted (a thread starved for seconds must not grow memory, and its verdicts must stay
  // recent: the fixes stop within a second of a bump); never the batch that builds the reference.
  MountCheckThread(boost::asio::io_context& io, Checked checked, std::size_t max_waiting);
  ~MountCheckThread();
  MountCheckThread(const MountCheckThread&) = delete;
  MountCheckThread& operator=(const MountCheckThread&) = delete;

  // From the event loop. A batch with nothing to check is ignored.
  void submit(core::MountRotations rotations);
  // Rotations dropped unchecked because the thread lagged (mount.rotations_dropped_busy).
  std::uint64_t dropped() const { return dropped_.load(std::memory_order_relaxed); }

 private:
  void run();

  boost::asio::io_context& io_;
  Checked checked_;
  std::size_t max_waiting_;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<core::MountRotations> waiting_;
  std::size_t waiting_rotations_ = 0;
  bool stopping_ = false;
  std::atomic<std::uint64_t> dropped_{0};
  std::thread thread_;  // last: started once the rest is built
};

}  // namespace rsu::daemon
