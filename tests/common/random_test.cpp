// SPDX-License-Identifier: Apache-2.0
// The counter-based random numbers the simulator's noise is drawn from (common/random.h): SplitMix64's
// published outputs, the open unit interval's ends, the normal quantile against the normal distribution
// function (erfc) and its published values, and the Box-Muller pair's moments.
#include "common/random.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>

namespace rsu {
namespace {

// Phi(x), the standard normal distribution function, from the C library's erfc.
double normal_cdf(double x) {
  return 0.5 * std::erfc(-x / std::sqrt(2.0));
}

TEST(Random, Mix64IsSplitMix64) {
  // SplitMix64 seeded with 0 (Steele, Lea, Flood 2014): its first two outputs. mix64 adds the golden
  // gamma itself, so mix64(k * gamma) is the generator's output k + 1.
  EXPECT_EQ(mix64(0), 0xe220a8397b1dcdafULL);
  EXPECT_EQ(mix64(0x9e3779b97f4a7c15ULL), 0x6e789e6aa1b965f4ULL);
}

TEST(Random, UniformOpen01NeverReachesItsEnds) {
  EXPECT_GT(uniform_open01(0), 0.0);
  EXPECT_LT(uniform_open01(~0ULL), 1.0);
  EXPECT_DOUBLE_EQ(uniform_open01(0), 0.5 / 9007199254740992.0);
  EXPECT_DOUBLE_EQ(uniform_open01(1ULL << 63), 0.5 + 0.5 / 9007199254740992.0);
  EXPECT_DOUBLE_EQ(uniform_open01(~0ULL), 1.0 - 1.0 / 9007199254740992.0);  // 1 - 2^-54 would round to 1
  EXPECT_DOUBLE_EQ(uniform_open01(~0ULL << 11 >> 1), (4503599627370495.5) / 9007199254740992.0);
  EXPECT_TRUE(std::isfinite(std::log(uniform_open01(0))));
  EXPECT_TRUE(std::isfinite(normal_quantile(uniform_open01(~0ULL))));
  EXPECT_TRUE(std::isfinite(normal_quantile(uniform_open01(0))));
}

TEST(Random, NormalQuantileInvertsTheDistributionFunction) {
  // Published values: the 97.5 % and 99.865 % (3 sigma) points, the median.
  EXPECT_NEAR(normal_quantile(0.975), 1.959963984540054, 3e-9);
  EXPECT_NEAR(normal_quantile(normal_cdf(3.0)), 3.0, 4e-9);
  EXPECT_NEAR(normal_quantile(0.5), 0.0, 1e-15);
  // Across both of its regions (the switch at 0.02425) and far into the tails: the relative error against
  // x refined by one Newton step on Phi(x) = p is below the approximation's 1.2e-9.
  for (double lg = -15.0; lg <= std::log10(0.5); lg += 0.05) {
    for (const double p : {std::pow(10.0, lg), 0.02425, 0.0242, 0.0243}) {
      const double x = normal_quantile(p);
      const double density = std::exp(-0.5 * x * x) / std::sqrt(2.0 * std::numbers::pi);
      const double refined = x - (normal_cdf(x) - p) / density;
      EXPECT_LE(std::abs(x - refined), 1.2e-9 * std::max(1.0, std::abs(refined))) << "p " << p;
      EXPECT_LT(x, 0.0 + 1e-15) << "p " << p;  // the lower half
      if (p >= 1e-7) {                         // symmetric, where 1 - p keeps the digits that matter
        EXPECT_NEAR(normal_quantile(1.0 - p), -x, 2e-8) << "p " << p;
      }
    }
  }
  // Increasing.
  double last = -std::numeric_limits<double>::infinity();
  for (double p = 1e-6; p < 1.0 - 1e-6; p += 1e-3) {
    EXPECT_GT(normal_quantile(p), last) << "p " << p;
    last = normal_quantile(p);
  }
}

TEST(Random, NormalPairsAreReproducibleAndStandard) {
  const NormalPair first = standard_normal_pair(7, 3, 12345);
  const NormalPair again = standard_normal_pair(7, 3, 12345);
  EXPECT_EQ(first.a, again.a);
  EXPECT_EQ(first.b, again.b);
  EXPECT_NE(standard_normal_pair(7, 4, 12345).a, first.a);  // another stream
  double sa = 0, sb = 0, saa = 0, sbb = 0, sab = 0;
  int beyond3 = 0;
  constexpr int kN = 200000;
  for (int i = 0; i < kN; ++i) {
    const NormalPair z = standard_normal_pair(1, 2, static_cast<std::uint64_t>(i));
    sa += z.a;
    sb += z.b;
    saa += z.a * z.a;
    sbb += z.b * z.b;
    sab += z.a * z.b;
    beyond3 += (std::abs(z.a) > 3.0) + (std::abs(z.b) > 3.0);
  }
  // Sampling errors at 200,000: mean 0.0022, variance 0.0032 (one sigma); bounds at 5 sigma.
  EXPECT_NEAR(sa / kN, 0.0, 0.011);
  EXPECT_NEAR(sb / kN, 0.0, 0.011);
  EXPECT_NEAR(saa / kN, 1.0, 0.016);
  EXPECT_NEAR(sbb / kN, 1.0, 0.016);
  EXPECT_NEAR(sab / kN, 0.0, 0.011);
  // 0.27 % beyond 3 sigma: 1,080 of 400,000 expected, sigma 33.
  EXPECT_NEAR(beyond3, 400000 * 2.0 * normal_cdf(-3.0), 165.0);
}

}  // namespace
}  // namespace rsu
