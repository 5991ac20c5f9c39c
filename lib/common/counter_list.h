// Counters as ("area.name", value) pairs in a stable order: what rsud's stats file and logs print, and
// what tests look up by name. Every part that counts reports into one CounterList, so a counter is
// named in one place (the part that counts it) and listed the same way everywhere.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "common/enum_counter.h"

namespace rsu {

class CounterList {
 public:
  using Entry = std::pair<std::string, std::uint64_t>;

  void add(std::string_view area, std::string_view name, std::uint64_t value) {
    std::string key;
    key.reserve(area.size() + 1 + name.size());
    key.append(area).append(".").append(name);
    entries_.emplace_back(std::move(key), value);
  }

  // Every value of the enum from `first` on (zeros included), named by its to_string (found by
  // argument-dependent lookup in the enum's namespace).
  template <typename Enum>
  void add_all(std::string_view area, const EnumCounter<Enum>& counts, Enum first = Enum{}) {
    for (auto i = static_cast<std::size_t>(first); i < EnumCounter<Enum>::kSize; ++i) {
      const auto e = static_cast<Enum>(i);
      add(area, to_string(e), counts.count(e));
    }
  }

  const std::vector<Entry>& entries() const { return entries_; }
  std::vector<Entry> take() { return std::move(entries_); }

 private:
  std::vector<Entry> entries_;
};

}  // namespace rsu
