// SPDX-License-Identifier: Apache-2.0
// The experiments' worker pool: runs job(i) for every i in [0, count) on `threads` threads (the caller's
// among them), each index once, in no particular order. The jobs write only their own results.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <thread>
#include <vector>

namespace rsu::eval {

template <typename Job>
void run_indices_in_parallel(std::size_t count, int threads, const Job& job) {
  std::atomic<std::size_t> next{0};
  const auto worker = [&] {
    for (std::size_t i = next++; i < count; i = next++)
      job(i);
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < std::max(1, threads); ++t)
    pool.emplace_back(worker);
  worker();
  for (auto& t : pool)
    t.join();
}

}  // namespace rsu::eval
