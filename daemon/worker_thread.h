// SPDX-License-Identifier: Apache-2.0
// A thread of rsud's that takes pure work off the event loop (issue 16: correction latency; what the
// loop computes holds the LiDAR's packets behind it). The loop submits jobs that RsuCore handed out; the
// thread runs `work` on each, in order, and posts each result back to the io_context, where `done` runs
// on the loop's thread: RsuCore's state is the loop's alone. rsud runs the mount check on one
// (core::check_mount_rotations on RsuCore::take_mount_rotations) and, with perception.prepare_thread, the
// preparation of fits and fixes ahead of their release on another (core::prepare on
// RsuCore::take_preparation).
//
// Bounded: at most `max_waiting` units of work wait (Bound::weight: a job's units); beyond that the
// oldest jobs are dropped and their units counted (a thread starved for seconds must not grow memory,
// and its results must stay recent), except those Bound::keep says must be run.
#pragma once

#include <utility>  // before Asio: Boost 1.74's awaitable.hpp uses std::exchange under C++20

#include <boost/asio/io_context.hpp>
#include <boost/asio/post.hpp>

#include <pthread.h>

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

namespace rsu::daemon {

template <class Job, class Result>
class WorkerThread {
 public:
  struct Bound {
    std::size_t max_waiting = 1;
    std::function<std::size_t(const Job&)> weight = [](const Job&) { return std::size_t{1}; };
    std::function<bool(const Job&)> keep = [](const Job&) { return false; };  // never dropped
  };
  using Work = std::function<Result(Job)>;
  using Done = std::function<void(Result&&)>;

  // `name`: the thread's name (at most 15 characters: top, ps -L).
  WorkerThread(boost::asio::io_context& io, const std::string& name, Work work, Done done, Bound bound)
      : io_(io), work_(std::move(work)), done_(std::move(done)), bound_(std::move(bound)) {
    bound_.max_waiting = std::max<std::size_t>(1, bound_.max_waiting);
    thread_ = std::thread([this] { run(); });
    pthread_setname_np(thread_.native_handle(), name.substr(0, 15).c_str());
  }
  ~WorkerThread() {
    {
      const std::lock_guard lock(mutex_);
      stopping_ = true;
    }
    wake_.notify_one();
    thread_.join();
  }
  WorkerThread(const WorkerThread&) = delete;
  WorkerThread& operator=(const WorkerThread&) = delete;

  // From the event loop.
  void submit(Job job) {
    {
      const std::lock_guard lock(mutex_);
      waiting_units_ += bound_.weight(job);
      waiting_.push_back(std::move(job));
      while (waiting_units_ > bound_.max_waiting && waiting_.size() > 1 && !bound_.keep(waiting_.front())) {
        const std::size_t units = bound_.weight(waiting_.front());
        waiting_units_ -= units;
        dropped_.fetch_add(units, std::memory_order_relaxed);
        waiting_.pop_front();
      }
    }
    wake_.notify_one();
  }
  // Units of work dropped unrun because the thread lagged.
  std::uint64_t dropped() const { return dropped_.load(std::memory_order_relaxed); }

 private:
  void run() {
    for (;;) {
      Job next;
      {
        std::unique_lock lock(mutex_);
        wake_.wait(lock, [this] { return stopping_ || !waiting_.empty(); });
        if (stopping_)
          return;
        next = std::move(waiting_.front());
        waiting_.pop_front();
        waiting_units_ -= bound_.weight(next);
      }
      auto result = std::make_shared<Result>(work_(std::move(next)));
      // Handlers posted from this one thread run in the order posted: the jobs' order. (The callback is
      // copied: a handler still queued when this object is gone must not reach into it.)
      boost::asio::post(io_, [done = done_, result] { done(std::move(*result)); });
    }
  }

  boost::asio::io_context& io_;
  Work work_;
  Done done_;
  Bound bound_;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<Job> waiting_;
  std::size_t waiting_units_ = 0;
  bool stopping_ = false;
  std::atomic<std::uint64_t> dropped_{0};
  std::thread thread_;  // last: started once the rest is built
};

}  // namespace rsu::daemon
