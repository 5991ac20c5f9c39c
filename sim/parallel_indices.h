// SPDX-License-Identifier: Apache-2.0
// The simulator's and the experiments' worker pool: runs job(i) for every i in [0, count) on `threads`
// threads (the caller's among them), each index once, in no particular order. The jobs write only their
// own results. Threads start per call: meant for work of milliseconds (a frame's packets, an experiment's
// cells), not for a single packet. run_ranges_in_parallel hands out runs of consecutive indices (a
// frame's packets in order).
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <exception>
#include <mutex>
#include <stdexcept>
#include <string>
#include <system_error>
#include <thread>
#include <vector>

namespace rsu::sim {

// A job's exception is rethrown here once every thread has stopped (the first one thrown; the threads
// take no further index after it), rather than ending the process from a worker thread.
template <typename Job>
void run_indices_in_parallel(std::size_t count, int threads, const Job& job) {
  std::atomic<std::size_t> next{0};
  std::exception_ptr failure;
  std::mutex failure_mutex;
  const auto worker = [&] {
    for (std::size_t i = next++; i < count; i = next++) {
      try {
        job(i);
      } catch (...) {
        const std::lock_guard lock(failure_mutex);
        if (!failure)
          failure = std::current_exception();
        next = count;
      }
    }
  };
  // No more threads than indices: a thread with none to take would only cost its start.
  const std::size_t wanted =
      std::min(static_cast<std::size_t>(std::max(1, threads)), std::max<std::size_t>(count, 1));
  std::vector<std::thread> pool;
  for (std::size_t t = 1; t < wanted; ++t) {
    try {
      pool.emplace_back(worker);
    } catch (const std::system_error&) {
      break;  // no thread to be had: the threads started (and the caller's) take every index
    }
  }
  worker();
  for (auto& t : pool)
    t.join();
  if (failure)
    std::rethrow_exception(failure);
}

// The thread count the tools default to: the machine's hardware threads (1 if it cannot tell).
inline int hardware_threads() {
  return static_cast<int>(std::max(1U, std::thread::hardware_concurrency()));
}

// How many runs of consecutive indices run_ranges_in_parallel cuts `count` indices into: one on one
// thread (the single-threaded path, whole); on several, 4 a thread, so that a thread slowed by other work
// on the machine takes fewer; at most `count`.
inline std::size_t range_count(std::size_t count, int threads) {
  return std::min(count, threads <= 1 ? std::size_t{1} : 4 * static_cast<std::size_t>(threads));
}

// job(run, begin, end) for each run r < runs = range_count(count, threads) of the indices
// [count * r / runs, count * (r + 1) / runs), on `threads` threads. Throws std::invalid_argument for
// threads < 1 (a caller's thread count, from an option).
template <typename Job>
void run_ranges_in_parallel(std::size_t count, int threads, const Job& job) {
  if (threads < 1)
    throw std::invalid_argument("simulator: threads must be >= 1, not " + std::to_string(threads));
  const std::size_t runs = range_count(count, threads);
  run_indices_in_parallel(runs, threads,
                          [&](std::size_t r) { job(r, count * r / runs, count * (r + 1) / runs); });
}

}  // namespace rsu::sim
