// SPDX-License-Identifier: Apache-2.0
// PacketOrder (lidar/packet_order.h): a stream whose packets are k * period, impaired in known ways;
// the test knows which packets it dropped, swapped or repeated and checks the released order and the
// counts against that.
#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <vector>

#include "lidar/packet_order.h"

namespace rsu::lidar {
namespace {

constexpr TimeNs kPeriod = 663'552;  // VLP-32C packet period, ns
constexpr TimeNs kMaxGap = 200'000'000;

// A packet of three points stamped with its own time, so the released content identifies it.
std::vector<LidarPoint> packet(TimeNs t) {
  std::vector<LidarPoint> points(3);
  for (LidarPoint& p : points)
    p.time_ns = t;
  return points;
}

// Feeds the times in arrival order; returns the times released, in release order, then flushes.
std::vector<TimeNs> run(PacketOrder& order, const std::vector<TimeNs>& arrivals) {
  std::vector<TimeNs> released;
  std::vector<LidarPoint> out;
  const auto drain = [&](bool everything) {
    while (order.pop(out, everything)) {
      EXPECT_EQ(out.size(), 3U);
      released.push_back(out.front().time_ns);
    }
  };
  for (const TimeNs t : arrivals) {
    order.push(t, packet(t));
    drain(false);
  }
  drain(true);
  return released;
}

std::vector<TimeNs> times(int n, TimeNs start = 1'000'000'000) {
  std::vector<TimeNs> t(static_cast<std::size_t>(n));
  for (int k = 0; k < n; ++k)
    t[static_cast<std::size_t>(k)] = start + k * kPeriod;
  return t;
}

TEST(PacketOrder, InOrderStreamPassesThroughWithNothingCounted) {
  for (const std::size_t depth : {0U, 3U}) {
    PacketOrder order({.depth = depth}, kPeriod, kMaxGap);
    const auto in = times(50);
    EXPECT_EQ(run(order, in), in);
    const PacketOrderStats& s = order.stats();
    EXPECT_EQ(s.released, 50U);
    EXPECT_EQ(s.lost + s.reordered + s.late + s.duplicate + s.stream_gaps, 0U);
  }
}

TEST(PacketOrder, DepthZeroReleasesAtOnceAndDropsLatePackets) {
  PacketOrder order({.depth = 0}, kPeriod, kMaxGap);
  std::vector<LidarPoint> out;
  const auto in = times(4);
  order.push(in[0], packet(in[0]));
  ASSERT_TRUE(order.pop(out));  // no holding: no added latency
  EXPECT_EQ(out.front().time_ns, in[0]);
  order.push(in[2], packet(in[2]));
  ASSERT_TRUE(order.pop(out));
  EXPECT_FALSE(order.push(in[1], packet(in[1])));  // its place was released
  EXPECT_EQ(order.stats().late, 1U);
  EXPECT_EQ(order.stats().lost, 1U);  // in[1]'s period was empty when in[2] went
}

TEST(PacketOrder, SwapsWithinTheDepthArePutBackInOrder) {
  PacketOrder order({.depth = 2}, kPeriod, kMaxGap);
  auto in = times(40);
  std::vector<TimeNs> arrivals = in;
  // Three adjacent swaps and one packet two places late.
  std::swap(arrivals[5], arrivals[6]);
  std::swap(arrivals[17], arrivals[18]);
  std::swap(arrivals[30], arrivals[31]);
  std::rotate(arrivals.begin() + 10, arrivals.begin() + 11, arrivals.begin() + 13);  // 10 after 11, 12
  EXPECT_EQ(run(order, arrivals), in);
  EXPECT_EQ(order.stats().reordered, 4U);
  EXPECT_EQ(order.stats().late + order.stats().lost + order.stats().duplicate, 0U);
}

TEST(PacketOrder, LossIsCountedFromTheTimeGaps) {
  PacketOrder order({.depth = 1}, kPeriod, kMaxGap);
  auto in = times(100);
  std::vector<TimeNs> arrivals;
  std::vector<TimeNs> kept;
  std::uint64_t dropped = 0;
  for (std::size_t k = 0; k < in.size(); ++k) {
    // Drop every 7th packet, and packets 50..53 in a row (a burst); never the first or the last.
    const bool drop = (k % 7 == 3) || (k >= 50 && k <= 53);
    if (drop) {
      ++dropped;
      continue;
    }
    arrivals.push_back(in[k]);
    kept.push_back(in[k]);
  }
  EXPECT_EQ(run(order, arrivals), kept);
  EXPECT_EQ(order.stats().lost, dropped);
}

TEST(PacketOrder, PeriodsRoundedToTheMicrosecondAreNotLoss) {
  // Packet timestamps are whole microseconds: consecutive ones are 663 or 664 us apart.
  PacketOrder order({.depth = 0}, kPeriod, kMaxGap);
  std::vector<TimeNs> in;
  for (int k = 0; k < 30; ++k)
    in.push_back((1'000'000'000 + k * kPeriod) / 1000 * 1000);
  EXPECT_EQ(run(order, in), in);
  EXPECT_EQ(order.stats().lost, 0U);
}

TEST(PacketOrder, DuplicatesAreDroppedHeldOrReleased) {
  PacketOrder order({.depth = 2}, kPeriod, kMaxGap);
  const auto in = times(6);
  // in[1] again while it is held, and again just after its release.
  const std::vector<TimeNs> arrivals = {in[0], in[1], in[1], in[2], in[3], in[1], in[4], in[5]};
  EXPECT_EQ(run(order, arrivals), in);
  EXPECT_EQ(order.stats().duplicate, 2U);
  EXPECT_EQ(order.stats().late, 0U);
}

TEST(PacketOrder, AStreamThatStopsAndRestartsIsAGapNotLoss) {
  PacketOrder order({.depth = 2}, kPeriod, kMaxGap);
  const auto first = times(20);
  const auto second = times(20, first.back() + 3 * kMaxGap);  // silent for 0.6 s, then on
  std::vector<TimeNs> arrivals = first;
  arrivals.insert(arrivals.end(), second.begin(), second.end());
  EXPECT_EQ(run(order, arrivals), arrivals);
  EXPECT_EQ(order.stats().stream_gaps, 1U);
  EXPECT_EQ(order.stats().lost, 0U);
}

TEST(PacketOrder, AClockJumpBackRestartsTheOrderInsteadOfDroppingEverything) {
  PacketOrder order({.depth = 2}, kPeriod, kMaxGap);
  const auto before = times(20, 10'000'000'000);
  const auto after = times(20, 1'000'000'000);  // the sensor's clock went back 9 s
  std::vector<TimeNs> arrivals = before;
  arrivals.insert(arrivals.end(), after.begin(), after.end());
  const std::vector<TimeNs> released = run(order, arrivals);
  // The two packets still held at the jump are given up; everything after it flows.
  std::vector<TimeNs> expected(before.begin(), before.end() - 2);
  expected.insert(expected.end(), after.begin(), after.end());
  EXPECT_EQ(released, expected);
  EXPECT_EQ(order.stats().stream_gaps, 1U);
  EXPECT_EQ(order.stats().lost, 2U);
  EXPECT_EQ(order.stats().late, 0U);
}

TEST(PacketOrder, RejectsANonPositivePeriodOrGap) {
  EXPECT_THROW(PacketOrder({}, 0, kMaxGap), std::invalid_argument);
  EXPECT_THROW(PacketOrder({}, kPeriod, 0), std::invalid_argument);
}

}  // namespace
}  // namespace rsu::lidar
