// SPDX-License-Identifier: Apache-2.0
// A histogram over fixed bucket bounds, as Prometheus keeps one: how many observations fell at or
// below each upper bound, their count and their sum. Observing is a binary search over a few bounds,
// cheap enough for every LiDAR packet.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <utility>
#include <vector>

namespace rsu {

class Histogram {
 public:
  // `upper_bounds` strictly ascending and finite; a last bucket (+Inf) is implied. Throws
  // std::invalid_argument otherwise.
  explicit Histogram(std::vector<double> upper_bounds)
      : bounds_(std::move(upper_bounds)), counts_(bounds_.size() + 1, 0) {
    for (std::size_t i = 0; i < bounds_.size(); ++i) {
      if (!std::isfinite(bounds_[i]) || (i > 0 && bounds_[i] <= bounds_[i - 1]))
        throw std::invalid_argument("histogram bounds must be finite and strictly ascending");
    }
  }

  // A non-finite value is not observed (it has no bucket and would poison the sum).
  void observe(double value) {
    if (!std::isfinite(value))
      return;
    const auto bucket = std::lower_bound(bounds_.begin(), bounds_.end(), value) - bounds_.begin();
    ++counts_[static_cast<std::size_t>(bucket)];
    sum_ += value;
  }

  const std::vector<double>& upper_bounds() const { return bounds_; }
  // Observations <= upper_bounds()[i]; i == upper_bounds().size() is the +Inf bucket (all of them).
  std::uint64_t cumulative(std::size_t i) const {
    std::uint64_t n = 0;
    for (std::size_t k = 0; k <= i && k < counts_.size(); ++k)
      n += counts_[k];
    return n;
  }
  std::uint64_t count() const { return cumulative(bounds_.size()); }
  double sum() const { return sum_; }

 private:
  std::vector<double> bounds_;
  std::vector<std::uint64_t> counts_;  // per bucket, not cumulative; the last is above every bound
  double sum_ = 0.0;
};

}  // namespace rsu
