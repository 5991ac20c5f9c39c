// SPDX-License-Identifier: Apache-2.0
// Counters as ("area.name", value) pairs in a stable order: what rsud's stats file, its Prometheus
// metrics and its logs print, and what tests look up by name. Every part that counts reports into one
// CounterList, so a counter is named in one place (the part that counts it) and listed the same way
// everywhere. Each entry also says what kind of number it is: a count since start (a Prometheus
// counter), a current level such as how many vehicles are registered, or a measured value such as the
// sensor clock's offset (both Prometheus gauges).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "common/enum_counter.h"

namespace rsu {

enum class StatKind {
  kCount,     // events since start: only ever grows (a restart starts it at 0 again)
  kLevel,     // a whole number that goes up and down (vehicles registered, keys trusted)
  kMeasured,  // a measured value, possibly fractional or NaN (unknown yet)
};

struct Stat {
  std::string name;  // "area.name"
  StatKind kind = StatKind::kCount;
  std::uint64_t count = 0;  // kCount and kLevel
  double measured = 0.0;    // kMeasured
};

class CounterList {
 public:
  using Entry = std::pair<std::string, std::uint64_t>;

  void add(std::string_view area, std::string_view name, std::uint64_t value) {
    stats_.push_back({key(area, name), StatKind::kCount, value, 0.0});
  }
  void add_level(std::string_view area, std::string_view name, std::uint64_t value) {
    stats_.push_back({key(area, name), StatKind::kLevel, value, 0.0});
  }
  void add_measured(std::string_view area, std::string_view name, double value) {
    stats_.push_back({key(area, name), StatKind::kMeasured, 0, value});
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

  const std::vector<Stat>& stats() const { return stats_; }
  // The counts and levels as (name, value), in order (measured values are left out).
  std::vector<Entry> entries() const {
    std::vector<Entry> out;
    for (const Stat& s : stats_) {
      if (s.kind != StatKind::kMeasured)
        out.emplace_back(s.name, s.count);
    }
    return out;
  }

 private:
  // An empty area names the stat by `name` alone (rsud's own: uptime_s, corrections_sent, ...).
  static std::string key(std::string_view area, std::string_view name) {
    if (area.empty())
      return std::string(name);
    std::string k;
    k.reserve(area.size() + 1 + name.size());
    k.append(area).append(".").append(name);
    return k;
  }

  std::vector<Stat> stats_;
};

}  // namespace rsu
