// SPDX-License-Identifier: Apache-2.0
// Random and mutated packets never crash the decoder, and every rejection has the documented reason.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>
#include <string>

#include "lidar/velodyne_decoder.h"
#include "packet_stream.h"

namespace rsu::lidar {
namespace {

std::uint64_t le32(std::span<const std::uint8_t> b, std::size_t at) {
  return b[at] + (b[at + 1] << 8) + (b[at + 2] << 16) + (std::uint64_t{b[at + 3]} << 24);
}

// The test's own reading of the documented checks, in the documented order, as the name the decoder
// counts the payload under.
std::string expected_outcome(std::span<const std::uint8_t> b) {
  if (b.size() == 512) {
    return le32(b, 198) < 3'600'000'000ULL ? "position" : "timestamp_out_of_range";
  }
  if (b.size() != 1206) {
    return "wrong_size";
  }
  const std::uint8_t id = b[1205];
  if (id != 0x21 && id != 0x22 && id != 0x24 && id != 0x28 && id != 0x31 && id != 0x63) {
    return "unknown_product";
  }
  if (b[1204] != 0x37 && b[1204] != 0x38 && b[1204] != 0x39) {
    return "unsupported_return_mode";
  }
  for (std::size_t blk = 0; blk < 12; ++blk) {
    if (b[100 * blk] != 0xFF || b[100 * blk + 1] != 0xEE) {
      return "bad_block_flag";
    }
  }
  for (std::size_t blk = 0; blk < 12; ++blk) {
    if (b[100 * blk + 2] + 256 * b[100 * blk + 3] >= 36000) {
      return "azimuth_out_of_range";
    }
  }
  if (le32(b, 1200) >= 3'600'000'000ULL) {
    return "timestamp_out_of_range";
  }
  if (b[1204] == 0x39) {
    for (std::size_t blk = 0; blk < 12; blk += 2) {
      if (b[100 * blk + 2] != b[100 * blk + 102] || b[100 * blk + 3] != b[100 * blk + 103]) {
        return "dual_pair_mismatch";
      }
    }
  }
  return "accepted";
}

// Decodes and checks the outcome, that a refusal appends nothing and that accepted points are sane.
void decode_and_check(VelodyneDecoder& decoder, std::span<const std::uint8_t> bytes, TimeNs reference,
                      std::map<std::string, std::uint64_t>& tally) {
  std::vector<LidarPoint> points;
  const std::string expected = expected_outcome(bytes);
  const PacketOutcome got = decoder.decode(bytes, reference, points);
  ASSERT_EQ(got.reason, expected);
  ASSERT_EQ(got.kind, expected == "accepted"   ? PacketKind::data
                      : expected == "position" ? PacketKind::auxiliary
                                               : PacketKind::refused);
  ++tally[expected];
  if (got.kind != PacketKind::data) {
    ASSERT_TRUE(points.empty());
    return;
  }
  ASSERT_LE(points.size(), 384U);
  for (const LidarPoint& p : points) {
    ASSERT_TRUE(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z));
    ASSERT_GE(p.azimuth_rad, 0.0F);
    ASSERT_LT(p.azimuth_rad, 6.2831855F);
    // Within half an hour of the reference, plus the packet's own span (a field-of-view gap inside a
    // packet of garbled azimuths can stretch it to a few turns' time at the slowest believed rate).
    ASSERT_LE(std::abs(p.time_ns - reference), 1800 * kNsPerSecond + kNsPerSecond);
  }
}

// Every payload counted once, under the name the test expected.
void expect_counts_match(const LidarDecoder& decoder, const std::map<std::string, std::uint64_t>& tally,
                         std::uint64_t total) {
  EXPECT_EQ(decoder.packets_seen(), total);
  for (const auto& [name, n] : tally) {
    bool found = false;
    for (const auto& [counter, value] : decoder.counters()) {
      if (counter == name) {
        EXPECT_EQ(value, n) << name;
        found = true;
      }
    }
    EXPECT_TRUE(found) << name;
  }
}

TEST(LidarPacketFuzz, RandomBuffers) {
  std::mt19937_64 rng(2024);
  std::uniform_int_distribution<int> byte(0, 255);
  std::uniform_int_distribution<std::size_t> length(0, 2000);
  std::uniform_int_distribution<int> coin(0, 3);
  VelodyneDecoder decoder(make_vlp16());
  std::map<std::string, std::uint64_t> tally;
  constexpr int kBuffers = 4000;
  for (int i = 0; i < kBuffers; ++i) {
    // Half the buffers have the right size; of those, some get plausible factory bytes and block
    // flags so that the later checks are reached too.
    std::vector<std::uint8_t> b(i % 2 == 0 ? 1206 : i % 10 == 1 ? 512 : length(rng));
    for (auto& v : b) {
      v = static_cast<std::uint8_t>(byte(rng));
    }
    if (b.size() == 512 && coin(rng) != 0) {
      b[201] &= 0x7F;  // timestamp < 2^31 us, mostly below one hour
    }
    if (b.size() == 1206) {
      if (coin(rng) != 0) {
        b[1205] = coin(rng) == 0 ? 0x28 : 0x22;
      }
      const bool dual = coin(rng) == 0;
      if (coin(rng) != 0) {
        b[1204] = dual ? 0x39 : 0x37;
      }
      if (coin(rng) != 0) {
        for (std::size_t blk = 0; blk < 12; ++blk) {
          b[100 * blk] = 0xFF;
          b[100 * blk + 1] = coin(rng) == 0 && blk == 5 ? 0x00 : 0xEE;
          if (coin(rng) != 0) {
            b[100 * blk + 3] &= 0x7F;  // azimuth < 32768
          }
          if (dual && blk % 2 == 1 && coin(rng) != 0) {
            b[100 * blk + 2] = b[100 * blk - 98];  // the pair's azimuths equal
            b[100 * blk + 3] = b[100 * blk - 97];
          }
        }
      }
      if (coin(rng) != 0) {
        b[1203] &= 0x7F;  // timestamp < 2^31 us, mostly below one hour
      }
    }
    decode_and_check(decoder, b, 1'700'000'000 * kNsPerSecond, tally);
  }
  expect_counts_match(decoder, tally, kBuffers);
  // The generator reaches every outcome: accepted, position and the 7 refusal reasons.
  EXPECT_EQ(tally.size(), 9U);
}

TEST(LidarPacketFuzz, MutatedValidPackets) {
  for (const SensorModel& model : {make_vlp16(), make_vlp32c()}) {
    std::mt19937_64 rng(99);
    const FiringSchedule schedule(model, 3 * 3600 * kNsPerSecond - 20 * kNsPerMs, 123.0);
    VelodyneDecoder decoder(model);
    std::map<std::string, std::uint64_t> tally;
    std::uniform_int_distribution<std::size_t> position(0, 1205);
    std::uniform_int_distribution<int> byte(0, 255);
    std::uniform_int_distribution<int> flips(1, 4);
    constexpr int kPackets = 1500;
    for (int i = 0; i < kPackets; ++i) {
      test::EncodedPacket packet = test::make_packet(schedule, i % 40, rng, 0.1);
      for (int f = flips(rng); f > 0; --f) {
        packet.bytes[position(rng)] = static_cast<std::uint8_t>(byte(rng));
      }
      std::span<const std::uint8_t> bytes = packet.bytes;
      if (i % 10 == 0) {
        bytes = bytes.first(position(rng));  // truncated
      }
      decode_and_check(decoder, bytes, packet.returns.blocks.first_firing_ns, tally);
    }
    expect_counts_match(decoder, tally, kPackets);
    EXPECT_GT(tally["accepted"], 0U);
    EXPECT_GT(tally["wrong_size"], 0U);
  }
}

TEST(LidarPacketFuzz, DataBytesNeverCauseRejection) {
  // Distances and reflectivities are arbitrary by nature: any values decode.
  const SensorModel model = make_vlp32c();
  std::mt19937_64 rng(7);
  const FiringSchedule schedule(model, 0);
  VelodyneDecoder decoder(model);
  std::uniform_int_distribution<int> byte(0, 255);
  for (int i = 0; i < 200; ++i) {
    test::EncodedPacket packet = test::make_packet(schedule, i, rng, 0.0);
    for (std::size_t blk = 0; blk < 12; ++blk) {
      for (std::size_t at = 100 * blk + 4; at < 100 * blk + 100; ++at) {
        packet.bytes[at] = static_cast<std::uint8_t>(byte(rng));
      }
    }
    std::vector<LidarPoint> points;
    ASSERT_TRUE(decoder.decode(packet.bytes, packet.returns.blocks.first_firing_ns, points).is_data());
  }
  EXPECT_EQ(decoder.stats().points + decoder.stats().no_return, 200U * 384U);
}

}  // namespace
}  // namespace rsu::lidar
