// SPDX-License-Identifier: Apache-2.0
// Counts events per value of a reason/outcome enum whose last enumerator is kCount (list them with
// CounterList, counter_list.h).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

namespace rsu {

template <typename Enum>
class EnumCounter {
 public:
  static constexpr std::size_t kSize = static_cast<std::size_t>(Enum::kCount);

  void add(Enum e, std::uint64_t n = 1) {
    const auto i = static_cast<std::size_t>(e);
    if (i < kSize) {
      counts_[i] += n;
    }
  }
  std::uint64_t count(Enum e) const {
    const auto i = static_cast<std::size_t>(e);
    return i < kSize ? counts_[i] : 0;
  }
  std::uint64_t total() const {
    std::uint64_t sum = 0;
    for (const std::uint64_t c : counts_) {
      sum += c;
    }
    return sum;
  }

 private:
  std::array<std::uint64_t, kSize> counts_{};
};

}  // namespace rsu
