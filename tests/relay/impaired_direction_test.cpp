// SPDX-License-Identifier: Apache-2.0
// ImpairedDirection (tools/rsu_relay): datagrams k = 0, 1, ... pushed 10 ms apart, each carrying
// its own index, so that what leaves when can be checked against each impairment's definition.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "tools/rsu_relay/impaired_direction.h"

namespace rsu::tools {
namespace {

constexpr TimeNs kSpacing = 10 * kNsPerMs;

struct Sent {
  std::uint32_t index;
  TimeNs at;
};

ImpairedDirection::Datagram datagram(std::uint32_t k) {
  return {static_cast<std::uint8_t>(k), static_cast<std::uint8_t>(k >> 8), static_cast<std::uint8_t>(k >> 16),
          static_cast<std::uint8_t>(k >> 24)};
}

// Pushes n datagrams kSpacing apart and pops whatever is due, at every push and every due time, until
// nothing waits: returns what left and when.
std::vector<Sent> run(ImpairedDirection& link, std::uint32_t n) {
  std::vector<Sent> sent;
  const auto pop = [&](TimeNs now) {
    for (const auto& d : link.pop_due(now))
      sent.push_back({static_cast<std::uint32_t>(d[0] | d[1] << 8 | d[2] << 16 | d[3] << 24), now});
  };
  TimeNs now = 0;
  for (std::uint32_t k = 0; k < n; ++k) {
    now = k * kSpacing;
    // Everything due before this arrival leaves first, each at its own due time.
    while (link.next_due() && *link.next_due() < now)
      pop(*link.next_due());
    link.push(now, datagram(k));
    pop(now);
  }
  for (int guard = 0; guard < 100000 && link.next_due(); ++guard)
    pop(*link.next_due());
  return sent;
}

TEST(ImpairedDirection, UnimpairedForwardsEverythingAtOnceInOrder) {
  ImpairedDirection link({}, 1, 0);
  const auto sent = run(link, 100);
  ASSERT_EQ(sent.size(), 100u);
  for (std::uint32_t k = 0; k < 100; ++k) {
    EXPECT_EQ(sent[k].index, k);
    EXPECT_EQ(sent[k].at, k * kSpacing);
  }
  EXPECT_EQ(link.stats().forwarded, 100u);
  EXPECT_FALSE(link.next_due());
}

TEST(ImpairedDirection, DelayShiftsEveryDatagram) {
  ImpairedDirection link({.delay_ms = 200.0}, 1, 0);
  link.push(5 * kNsPerMs, datagram(0));
  EXPECT_TRUE(link.pop_due(204 * kNsPerMs).empty());
  EXPECT_EQ(*link.next_due(), 205 * kNsPerMs);
  EXPECT_EQ(link.pop_due(205 * kNsPerMs).size(), 1u);
  const auto sent = run(link, 50);
  for (std::uint32_t k = 0; k < 50; ++k)
    EXPECT_EQ(sent[k].at, k * kSpacing + 200 * kNsPerMs);
}

TEST(ImpairedDirection, LossDropsTheStatedShareReproducibly) {
  const std::uint32_t n = 20000;
  const double loss = 0.3;
  ImpairedDirection a({.loss = loss}, 7, 1), b({.loss = loss}, 7, 1), other_seed({.loss = loss}, 8, 1);
  const auto sa = run(a, n), sb = run(b, n), so = run(other_seed, n);
  // Binomial: within 5 standard deviations of n * loss.
  const double sd = std::sqrt(n * loss * (1 - loss));
  EXPECT_NEAR(static_cast<double>(a.stats().dropped), n * loss, 5 * sd);
  EXPECT_EQ(a.stats().dropped + a.stats().forwarded, n);
  ASSERT_EQ(sa.size(), sb.size());
  bool same_as_other_seed = sa.size() == so.size();
  for (std::size_t i = 0; i < sa.size(); ++i) {
    EXPECT_EQ(sa[i].index, sb[i].index);  // the same seed drops the same datagrams
    same_as_other_seed = same_as_other_seed && sa[i].index == so[i].index;
  }
  EXPECT_FALSE(same_as_other_seed);
  // The directions draw independently.
  ImpairedDirection up({.loss = loss}, 7, 0);
  const auto su = run(up, n);
  bool same_as_uplink = su.size() == sa.size();
  for (std::size_t i = 0; same_as_uplink && i < sa.size(); ++i)
    same_as_uplink = su[i].index == sa[i].index;
  EXPECT_FALSE(same_as_uplink);
}

TEST(ImpairedDirection, JitterStaysWithinItsBoundAndLetsDatagramsOvertake) {
  const double delay_ms = 50.0, jitter_ms = 30.0;
  ImpairedDirection link({.delay_ms = delay_ms, .jitter_ms = jitter_ms}, 3, 0);
  const auto sent = run(link, 2000);
  ASSERT_EQ(sent.size(), 2000u);
  double sum_ms = 0;
  int overtaken = 0;
  for (std::size_t i = 0; i < sent.size(); ++i) {
    const double latency_ms = static_cast<double>(sent[i].at - sent[i].index * kSpacing) / kNsPerMs;
    EXPECT_GE(latency_ms, delay_ms - jitter_ms - 1e-6);
    EXPECT_LE(latency_ms, delay_ms + jitter_ms + 1e-6);
    sum_ms += latency_ms;
    overtaken += i > 0 && sent[i].index < sent[i - 1].index ? 1 : 0;
  }
  // Uniform within +-30 ms: mean 50 ms (standard error 0.4 ms); spacing 10 ms < 60 ms of spread, so some
  // datagrams leave after a later one.
  EXPECT_NEAR(sum_ms / 2000.0, delay_ms, 2.0);
  EXPECT_GT(overtaken, 100);
}

TEST(ImpairedDirection, JitterNeverSendsBeforeArrival) {
  ImpairedDirection link({.delay_ms = 5.0, .jitter_ms = 20.0}, 3, 0);
  for (const Sent& s : run(link, 500))
    EXPECT_GE(s.at, s.index * kSpacing);
}

TEST(ImpairedDirection, ReorderedDatagramLeavesRightAfterTheNextOne) {
  const double reorder = 0.2;
  ImpairedDirection link({.reorder = reorder}, 11, 1);
  const auto sent = run(link, 5000);
  ASSERT_EQ(sent.size(), 5000u);
  EXPECT_GT(link.stats().reordered, 500u);
  // Every held datagram k leaves right after k + 1 and at its time: the output is the input with
  // `reordered` adjacent pairs swapped, nothing else moved; except that the last datagram, if held, has
  // no successor and leaves at the timeout.
  std::uint64_t swaps = 0;
  const bool last_held = sent.back().at != sent.back().index * kSpacing;
  if (last_held) {
    EXPECT_EQ(sent.back().index, 4999u);
    EXPECT_EQ(sent.back().at, 4999 * kSpacing + 100 * kNsPerMs);
  }
  for (std::size_t i = 0; i + (last_held ? 1 : 0) < sent.size();) {
    if (sent[i].index == i) {
      EXPECT_EQ(sent[i].at, sent[i].index * kSpacing);
      ++i;
      continue;
    }
    ASSERT_LT(i + 1, sent.size());
    EXPECT_EQ(sent[i].index, i + 1);
    EXPECT_EQ(sent[i + 1].index, i);
    EXPECT_EQ(sent[i + 1].at, sent[i].at);
    ++swaps;
    i += 2;
  }
  EXPECT_EQ(swaps + (last_held ? 1 : 0), link.stats().reordered);
}

TEST(ImpairedDirection, HeldDatagramLeavesAfterTheTimeoutWhenNothingFollows) {
  // reorder just below 1: the first datagram is held (a draw above 0.999999 is a one-in-a-million event
  // this seed does not hit, checked by the reordered count).
  ImpairedDirection link({.reorder = 0.999999}, 5, 0, 100 * kNsPerMs);
  link.push(0, datagram(0));
  ASSERT_EQ(link.stats().reordered, 1u);
  EXPECT_TRUE(link.pop_due(99 * kNsPerMs).empty());
  EXPECT_EQ(*link.next_due(), 100 * kNsPerMs);
  EXPECT_EQ(link.pop_due(100 * kNsPerMs).size(), 1u);
  EXPECT_FALSE(link.next_due());
}

}  // namespace
}  // namespace rsu::tools
