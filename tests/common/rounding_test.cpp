// SPDX-License-Identifier: Apache-2.0
// round_half_away against std::round, bit for bit: the clusterer's unwrap must not move a point.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include "common/rounding.h"

namespace {

bool same_bits(double x, double y) {
  return (std::isnan(x) && std::isnan(y)) ||
         std::bit_cast<std::uint64_t>(x) == std::bit_cast<std::uint64_t>(y);
}

// Whole numbers and halves (where rounding turns) from 0 to 2^54 and the 3 doubles either side of each,
// both signs; zeros, infinities, NaN, the smallest doubles.
std::vector<double> rounding_edges() {
  std::vector<double> centres{0.5, 1.5, 2.5, 1e6 + 0.5, 0x1p51 + 0.5, 0x1p52, 0x1p52 + 1.0, 0x1p53, 0x1p54};
  for (int k = 0; k <= 40; ++k) {
    centres.push_back(k);
    centres.push_back(k + 0.5);
  }
  for (int e = 1; e <= 53; ++e) {
    centres.push_back(std::exp2(e) - 0.5);
    centres.push_back(std::exp2(e));
  }
  std::vector<double> out{0.0,
                          -0.0,
                          std::numeric_limits<double>::infinity(),
                          -std::numeric_limits<double>::infinity(),
                          std::numeric_limits<double>::quiet_NaN(),
                          std::numeric_limits<double>::denorm_min(),
                          -std::numeric_limits<double>::denorm_min(),
                          std::numeric_limits<double>::max(),
                          -std::numeric_limits<double>::max()};
  for (double c : centres) {
    for (double sign : {1.0, -1.0}) {
      double up = sign * c, down = sign * c;
      out.push_back(up);
      for (int i = 0; i < 3; ++i) {
        up = std::nextafter(up, std::numeric_limits<double>::infinity());
        down = std::nextafter(down, -std::numeric_limits<double>::infinity());
        out.push_back(up);
        out.push_back(down);
      }
    }
  }
  return out;
}

TEST(Rounding, RoundHalfAwayIsStdRoundBitForBitAtTheEdges) {
  const std::vector<double> xs = rounding_edges();
  ASSERT_GT(xs.size(), 1000u);
  for (double x : xs) {
    EXPECT_TRUE(same_bits(rsu::round_half_away(x), std::round(x))) << std::hexfloat << x;
  }
  // The classic trap of floor(x + 0.5): the double below a half.
  EXPECT_EQ(rsu::round_half_away(0.49999999999999994), 0.0);
  EXPECT_TRUE(std::signbit(rsu::round_half_away(-0.3)));
}

TEST(Rounding, RoundHalfAwayIsStdRoundBitForBitOverAMillionNumbers) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> small(-4.0, 4.0);
  std::uniform_real_distribution<double> exponent(-40.0, 60.0);
  int mismatches = 0;
  for (int i = 0; i < 1'000'000; ++i) {
    const double x = i % 2 == 0 ? small(rng) : (i % 4 == 1 ? -1.0 : 1.0) * std::exp2(exponent(rng));
    mismatches += !same_bits(rsu::round_half_away(x), std::round(x));
  }
  EXPECT_EQ(mismatches, 0);
}

}  // namespace
