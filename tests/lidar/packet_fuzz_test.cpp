// Random and mutated packets never crash the decoder, and every rejection has the documented reason.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>

#include "lidar/velodyne_packet.h"
#include "packet_stream.h"

namespace rsu {
namespace {

// The test's own reading of the documented checks, in the documented order.
DecodeResult expected_result(std::span<const std::uint8_t> b, std::uint8_t product) {
  if (b.size() != 1206) {
    return DecodeResult::wrong_size;
  }
  const std::uint8_t id = b[1205];
  if (id != 0x21 && id != 0x22 && id != 0x24 && id != 0x28 && id != 0x31 && id != 0x63) {
    return DecodeResult::unknown_product;
  }
  if (id != product) {
    return DecodeResult::product_mismatch;
  }
  if (b[1204] != 0x37 && b[1204] != 0x38) {
    return DecodeResult::unsupported_return_mode;
  }
  for (std::size_t blk = 0; blk < 12; ++blk) {
    if (b[100 * blk] != 0xFF || b[100 * blk + 1] != 0xEE) {
      return DecodeResult::bad_block_flag;
    }
  }
  for (std::size_t blk = 0; blk < 12; ++blk) {
    if (b[100 * blk + 2] + 256 * b[100 * blk + 3] >= 36000) {
      return DecodeResult::azimuth_out_of_range;
    }
  }
  const std::uint64_t ts = b[1200] + (b[1201] << 8) + (b[1202] << 16) + (std::uint64_t{b[1203]} << 24);
  if (ts >= 3'600'000'000ULL) {
    return DecodeResult::timestamp_out_of_range;
  }
  return DecodeResult::accepted;
}

std::uint64_t count_of(const DecodeStats& s, DecodeResult r) {
  switch (r) {
    case DecodeResult::accepted:
      return s.accepted;
    case DecodeResult::wrong_size:
      return s.wrong_size;
    case DecodeResult::unknown_product:
      return s.unknown_product;
    case DecodeResult::product_mismatch:
      return s.product_mismatch;
    case DecodeResult::unsupported_return_mode:
      return s.unsupported_return_mode;
    case DecodeResult::bad_block_flag:
      return s.bad_block_flag;
    case DecodeResult::azimuth_out_of_range:
      return s.azimuth_out_of_range;
    case DecodeResult::timestamp_out_of_range:
      return s.timestamp_out_of_range;
  }
  return 0;
}

// Decodes and checks the result, that a rejection appends nothing and that accepted points are sane.
void decode_and_check(PacketDecoder& decoder, std::span<const std::uint8_t> bytes, TimeNs reference,
                      std::map<DecodeResult, std::uint64_t>& tally) {
  std::vector<LidarPoint> points;
  const DecodeResult expected = expected_result(bytes, decoder.model().product_id);
  const DecodeResult got = decoder.decode(bytes, reference, points);
  ASSERT_EQ(got, expected) << to_string(got) << " vs " << to_string(expected);
  ++tally[expected];
  if (got != DecodeResult::accepted) {
    ASSERT_TRUE(points.empty());
    return;
  }
  ASSERT_LE(points.size(), 384U);
  for (const LidarPoint& p : points) {
    ASSERT_TRUE(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z));
    ASSERT_GE(p.azimuth_rad, 0.0F);
    ASSERT_LT(p.azimuth_rad, 6.2831855F);
    // Within half an hour of the reference, plus the packet's own 1.3 ms.
    ASSERT_LE(std::abs(p.time_ns - reference), 1800 * kNsPerSecond + 2 * kNsPerMs);
  }
}

void expect_stats_match(const DecodeStats& stats, const std::map<DecodeResult, std::uint64_t>& tally,
                        std::uint64_t total) {
  EXPECT_EQ(stats.packets(), total);
  for (const auto& [result, n] : tally) {
    EXPECT_EQ(count_of(stats, result), n) << to_string(result);
  }
}

TEST(LidarPacketFuzz, RandomBuffers) {
  std::mt19937_64 rng(2024);
  std::uniform_int_distribution<int> byte(0, 255);
  std::uniform_int_distribution<std::size_t> length(0, 2000);
  std::uniform_int_distribution<int> coin(0, 3);
  PacketDecoder decoder(make_vlp16());
  std::map<DecodeResult, std::uint64_t> tally;
  constexpr int kBuffers = 4000;
  for (int i = 0; i < kBuffers; ++i) {
    // Half the buffers have the right size; of those, some get plausible factory bytes and block
    // flags so that the later checks are reached too.
    std::vector<std::uint8_t> b(i % 2 == 0 ? 1206 : length(rng));
    for (auto& v : b) {
      v = static_cast<std::uint8_t>(byte(rng));
    }
    if (b.size() == 1206) {
      if (coin(rng) != 0) {
        b[1205] = coin(rng) == 0 ? 0x28 : 0x22;
      }
      if (coin(rng) != 0) {
        b[1204] = coin(rng) == 0 ? 0x39 : 0x37;
      }
      if (coin(rng) != 0) {
        for (std::size_t blk = 0; blk < 12; ++blk) {
          b[100 * blk] = 0xFF;
          b[100 * blk + 1] = coin(rng) == 0 && blk == 5 ? 0x00 : 0xEE;
          if (coin(rng) != 0) {
            b[100 * blk + 3] &= 0x7F;  // azimuth < 32768
          }
        }
      }
      if (coin(rng) != 0) {
        b[1203] &= 0x7F;  // timestamp < 2^31 us, mostly below one hour
      }
    }
    decode_and_check(decoder, b, 1'700'000'000 * kNsPerSecond, tally);
  }
  expect_stats_match(decoder.stats(), tally, kBuffers);
  // The generator reaches every reason.
  EXPECT_EQ(tally.size(), 8U);
}

TEST(LidarPacketFuzz, MutatedValidPackets) {
  for (const SensorModel& model : {make_vlp16(), make_vlp32c()}) {
    std::mt19937_64 rng(99);
    const FiringSchedule schedule(model, 3 * 3600 * kNsPerSecond - 20 * kNsPerMs, 123.0);
    PacketDecoder decoder(model);
    std::map<DecodeResult, std::uint64_t> tally;
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
    expect_stats_match(decoder.stats(), tally, kPackets);
    EXPECT_GT(tally[DecodeResult::accepted], 0U);
    EXPECT_GT(tally[DecodeResult::wrong_size], 0U);
  }
}

TEST(LidarPacketFuzz, DataBytesNeverCauseRejection) {
  // Distances and reflectivities are arbitrary by nature: any values decode.
  const SensorModel model = make_vlp32c();
  std::mt19937_64 rng(7);
  const FiringSchedule schedule(model, 0);
  PacketDecoder decoder(model);
  std::uniform_int_distribution<int> byte(0, 255);
  for (int i = 0; i < 200; ++i) {
    test::EncodedPacket packet = test::make_packet(schedule, i, rng, 0.0);
    for (std::size_t blk = 0; blk < 12; ++blk) {
      for (std::size_t at = 100 * blk + 4; at < 100 * blk + 100; ++at) {
        packet.bytes[at] = static_cast<std::uint8_t>(byte(rng));
      }
    }
    std::vector<LidarPoint> points;
    ASSERT_EQ(decoder.decode(packet.bytes, packet.returns.blocks.first_firing_ns, points),
              DecodeResult::accepted);
  }
  EXPECT_EQ(decoder.stats().points_decoded + decoder.stats().no_return, 200U * 384U);
}

}  // namespace
}  // namespace rsu
