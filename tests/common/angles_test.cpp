// SPDX-License-Identifier: Apache-2.0
// wrap_angle and wrap_angle_positive against the library calls they stand for (std::remainder,
// std::fmod), bit for bit: their fast paths must change no LiDAR point's azimuth nor any fix.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include "common/angles.h"

namespace {

using rsu::kPi;

double remainder_wrap(double a) {
  a = std::remainder(a, 2.0 * kPi);
  return a <= -kPi ? a + 2.0 * kPi : a;
}

// With one change: an angle so little below 0 that adding 2 pi gives 2 pi (above -4.4e-16) wraps to 0,
// as [0, 2 pi) promises; std::fmod's wrap gave 2 pi.
double fmod_wrap(double a) {
  a = std::fmod(a, 2.0 * kPi);
  const double wrapped = a < 0.0 ? a + 2.0 * kPi : a;
  return wrapped == 2.0 * kPi ? 0.0 : wrapped;
}

// The same bits, or both NaN.
bool same(double x, double y) {
  return (std::isnan(x) && std::isnan(y)) ||
         std::bit_cast<std::uint64_t>(x) == std::bit_cast<std::uint64_t>(y);
}

// Every multiple of pi up to 6 (where the fast paths begin and end), and the 4 doubles either side.
std::vector<double> edges() {
  std::vector<double> out{0.0, -0.0};
  for (int k = -6; k <= 6; ++k) {
    double x = k * kPi;
    out.push_back(x);
    double up = x, down = x;
    for (int i = 0; i < 4; ++i) {
      up = std::nextafter(up, std::numeric_limits<double>::infinity());
      down = std::nextafter(down, -std::numeric_limits<double>::infinity());
      out.push_back(up);
      out.push_back(down);
    }
  }
  for (double x : {std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
                   std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::denorm_min(),
                   -std::numeric_limits<double>::denorm_min(), 1e300, -1e300}) {
    out.push_back(x);
  }
  return out;
}

TEST(Angles, WrapAngleIsRemaindersBitForBitAtTheEdges) {
  for (double a : edges()) {
    EXPECT_TRUE(same(rsu::wrap_angle(a), remainder_wrap(a))) << a;
  }
}

TEST(Angles, WrapAnglePositiveIsFmodsBitForBitAtTheEdges) {
  for (double a : edges()) {
    EXPECT_TRUE(same(rsu::wrap_angle_positive(a), fmod_wrap(a))) << a;
  }
}

TEST(Angles, BothWrapsAreTheLibraryCallsBitForBitOverAMillionAngles) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> near(-7.0 * kPi, 7.0 * kPi);
  std::uniform_real_distribution<double> exponent(-30.0, 30.0);
  int mismatches = 0;
  for (int i = 0; i < 1'000'000; ++i) {
    // Most where LiDAR angles lie (within a few turns), some of every magnitude.
    const double a = i % 4 != 0 ? near(rng) : (i % 8 == 0 ? -1.0 : 1.0) * std::exp2(exponent(rng));
    mismatches += !same(rsu::wrap_angle(a), remainder_wrap(a));
    mismatches += !same(rsu::wrap_angle_positive(a), fmod_wrap(a));
  }
  EXPECT_EQ(mismatches, 0);
}

// Angles turns away (a frame assembler's unwrapped azimuth grows a turn per rotation: 864,000 a day at
// 10 Hz), where wrap_angle computes the remainder itself: whole and half turns (where the nearest number of
// turns changes) up to beyond 2^25 rad, and 3 doubles either side of each; a million random angles.
TEST(Angles, WrapAngleIsRemaindersBitForBitTurnsAway) {
  std::vector<double> centres;
  for (double n = 1.0; n < 1e8; n = n < 200.0 ? n + 1.0 : std::floor(n * 1.37)) {
    centres.push_back(n * 2.0 * kPi);
    centres.push_back((n + 0.5) * 2.0 * kPi);
  }
  centres.push_back(0x1p25);
  int checked = 0, mismatches = 0;
  for (double c : centres) {
    for (double sign : {1.0, -1.0}) {
      double up = sign * c, down = sign * c;
      mismatches += !same(rsu::wrap_angle(up), remainder_wrap(up));
      for (int i = 0; i < 3; ++i) {
        up = std::nextafter(up, std::numeric_limits<double>::infinity());
        down = std::nextafter(down, -std::numeric_limits<double>::infinity());
        mismatches += !same(rsu::wrap_angle(up), remainder_wrap(up));
        mismatches += !same(rsu::wrap_angle(down), remainder_wrap(down));
        checked += 2;
      }
    }
  }
  std::mt19937_64 rng(13);
  std::uniform_int_distribution<int> turns(-6'000'000, 6'000'000);
  std::uniform_real_distribution<double> within(-kPi, kPi);
  std::uniform_real_distribution<double> anywhere(-0x1p26, 0x1p26);
  for (int i = 0; i < 1'000'000; ++i) {
    const double a = i % 2 == 0 ? turns(rng) * 2.0 * kPi + within(rng) : anywhere(rng);
    mismatches += !same(rsu::wrap_angle(a), remainder_wrap(a));
    ++checked;
  }
  EXPECT_GT(checked, 1'000'000);
  EXPECT_EQ(mismatches, 0);
}

TEST(Angles, WrapsLandInTheirRanges) {
  for (double a : edges()) {
    if (!std::isfinite(a)) {
      continue;
    }
    const double w = rsu::wrap_angle(a);
    EXPECT_TRUE(w > -kPi && w <= kPi) << a << " -> " << w;
    const double p = rsu::wrap_angle_positive(a);
    EXPECT_TRUE(p >= 0.0 && p < 2.0 * kPi) << a << " -> " << p;
  }
}

}  // namespace
