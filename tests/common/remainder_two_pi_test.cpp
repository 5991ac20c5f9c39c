// SPDX-License-Identifier: Apache-2.0
// detail::remainder_two_pi (angles.h) called directly: std::remainder(a, 2 pi) bit for bit (its contract),
// with values checked by hand where the turn count is plain, and the edges: zero's sign, half turns
// (rounded to an even number of turns), beyond 2^25 rad, NaN and infinity.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>

#include "common/angles.h"

namespace rsu {
namespace remainder_two_pi_test {

bool same_bits(double x, double y) {
  return (std::isnan(x) && std::isnan(y)) ||
         std::bit_cast<std::uint64_t>(x) == std::bit_cast<std::uint64_t>(y);
}

// Within a turn of zero nothing is taken off; whole turns come off (to within the rounding of n 2 pi).
TEST(RemainderTwoPi, TakesOffTheNearestWholeNumberOfTurns) {
  EXPECT_EQ(detail::remainder_two_pi(0.25), 0.25);
  EXPECT_EQ(detail::remainder_two_pi(-3.0), -3.0);
  EXPECT_NEAR(detail::remainder_two_pi(0.25 + 2.0 * kPi), 0.25, 1e-15);
  EXPECT_NEAR(detail::remainder_two_pi(0.25 - 6.0 * kPi), 0.25, 1e-14);
  EXPECT_NEAR(detail::remainder_two_pi(-1.0 + 1000.0 * 2.0 * kPi), -1.0, 1e-12);
  // 5 rad is nearer one turn (6.283) than none: 5 - 2 pi = -1.283.
  EXPECT_NEAR(detail::remainder_two_pi(5.0), 5.0 - 2.0 * kPi, 1e-15);
  // A million turns and a bit (a frame assembler's azimuth after a day): within (-pi, pi].
  const double far = 1e6 * 2.0 * kPi + 2.5;
  EXPECT_NEAR(detail::remainder_two_pi(far), 2.5, 1e-9);
}

TEST(RemainderTwoPi, ExactZeroHasTheSignOfTheAngle) {
  EXPECT_TRUE(same_bits(detail::remainder_two_pi(0.0), 0.0));
  EXPECT_TRUE(same_bits(detail::remainder_two_pi(-0.0), -0.0));
  EXPECT_TRUE(same_bits(detail::remainder_two_pi(2.0 * kPi), 0.0));
  EXPECT_TRUE(same_bits(detail::remainder_two_pi(-2.0 * kPi), -0.0));
}

// pi is half a turn: the quotient 0.5 rounds to the even 0, so pi stays pi and -pi stays -pi.
TEST(RemainderTwoPi, HalfTurnsRoundToAnEvenNumberOfTurns) {
  EXPECT_EQ(detail::remainder_two_pi(kPi), kPi);
  EXPECT_EQ(detail::remainder_two_pi(-kPi), -kPi);
}

TEST(RemainderTwoPi, NotANumberAndInfinityGiveNan) {
  EXPECT_TRUE(std::isnan(detail::remainder_two_pi(std::numeric_limits<double>::quiet_NaN())));
  EXPECT_TRUE(std::isnan(detail::remainder_two_pi(std::numeric_limits<double>::infinity())));
  EXPECT_TRUE(std::isnan(detail::remainder_two_pi(-std::numeric_limits<double>::infinity())));
}

// The contract: std::remainder(a, 2 pi) bit for bit, on and around every half turn up to 40 turns, at and
// beyond 2^25 rad (the library path), and on random angles up to 2^27 rad.
TEST(RemainderTwoPi, IsTheLibraryRemainderBitForBit) {
  int mismatches = 0;
  auto check = [&](double a) {
    if (!same_bits(detail::remainder_two_pi(a), std::remainder(a, 2.0 * kPi))) {
      ++mismatches;
      ADD_FAILURE() << std::hexfloat << a;
    }
  };
  for (int half_turns = -80; half_turns <= 80; ++half_turns) {
    double up = half_turns * kPi, down = up;
    check(up);
    for (int i = 0; i < 4; ++i) {
      up = std::nextafter(up, 1e300);
      down = std::nextafter(down, -1e300);
      check(up);
      check(down);
    }
  }
  for (const double a : {0x1p25, -0x1p25, std::nextafter(0x1p25, 0.0), 0x1p30 + 0.5, -0x1p40, 1e300})
    check(a);
  std::mt19937_64 rng(29);
  std::uniform_real_distribution<double> anywhere(-0x1p27, 0x1p27);
  for (int i = 0; i < 200'000; ++i)
    check(anywhere(rng));
  EXPECT_EQ(mismatches, 0);
}

}  // namespace remainder_two_pi_test
}  // namespace rsu
