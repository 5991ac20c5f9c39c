// SPDX-License-Identifier: Apache-2.0
// PointCloud2 -> LidarPoints: every datatype in both byte orders, padding and rows, time semantics,
// ring orders, and every rejection reason. Expected values are the ones the test wrote (cloud_builder.h
// encodes them byte by byte).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>

#include "cloud_builder.h"
#include "lidar/sensor_model.h"
#include "ros/pointcloud2_layout.h"

namespace rsu::ros {
namespace {

using test::build_cloud;
using test::FieldSpec;

constexpr std::uint8_t kI8 = 1, kU8 = 2, kI16 = 3, kU16 = 4, kI32 = 5, kU32 = 6, kF32 = 7, kF64 = 8;
constexpr std::uint8_t kAllTypes[] = {kI8, kU8, kI16, kU16, kI32, kU32, kF32, kF64};

// A value each datatype represents exactly and that tells the types apart (sign, magnitude).
double sample_value(std::uint8_t datatype, int point) {
  switch (datatype) {
    case kI8:
      return -100 + point;
    case kU8:
      return 200 + point;
    case kI16:
      return -30000 + point;
    case kU16:
      return 60000 + point;
    case kI32:
      return -2'000'000'000 + point;
    case kU32:
      return 4'000'000'000.0 + point;
    case kF32:
      return 0.15625 * (point + 1);
    default:
      return 1.0 / 3.0 + point;
  }
}

std::vector<lidar::LidarPoint> decode(test::BuiltCloud& c, std::span<const std::uint16_t> ring_map = {},
                                      CloudDecodeStats* stats = nullptr) {
  const PointCloud2View v = c.view();
  const LayoutResult layout = parse_layout(v);
  EXPECT_TRUE(layout.ok()) << to_string(layout.reject);
  std::vector<lidar::LidarPoint> out;
  if (!layout.ok())
    return out;
  const CloudDecodeStats s = decode_points(v, layout.layout, ring_map, out);
  if (stats != nullptr)
    *stats = s;
  return out;
}

TEST(PointCloud2Layout, CoordinatesInBothFloatTypesAndByteOrders) {
  for (const bool big : {false, true}) {
    for (const std::uint8_t type : {kF32, kF64}) {
      SCOPED_TRACE(testing::Message() << "big_endian " << big << " datatype " << int{type});
      auto c = build_cloud({{"x", type}, {"y", type}, {"z", type}},
                           {{1.5, -2.25, 0.75}, {-10.125, 20.5, 3.0}}, big);
      const auto points = decode(c);
      ASSERT_EQ(points.size(), 2U);
      EXPECT_EQ(points[0].x, 1.5F);
      EXPECT_EQ(points[0].y, -2.25F);
      EXPECT_EQ(points[0].z, 0.75F);
      EXPECT_EQ(points[1].x, -10.125F);
      EXPECT_EQ(points[1].y, 20.5F);
      EXPECT_EQ(points[1].z, 3.0F);
    }
  }
}

TEST(PointCloud2Layout, IntensityInEveryDatatypeAndByteOrder) {
  for (const bool big : {false, true}) {
    for (const std::uint8_t type : kAllTypes) {
      SCOPED_TRACE(testing::Message() << "big_endian " << big << " datatype " << int{type});
      std::vector<std::vector<double>> values;
      for (int p = 0; p < 3; ++p)
        values.push_back({1.0 + p, 2.0, 3.0, sample_value(type, p)});
      auto c = build_cloud({{"x", kF32}, {"y", kF32}, {"z", kF32}, {"intensity", type}}, values, big);
      const auto points = decode(c);
      ASSERT_EQ(points.size(), 3U);
      for (int p = 0; p < 3; ++p) {
        EXPECT_EQ(points[p].intensity, static_cast<float>(sample_value(type, p)));
        EXPECT_EQ(points[p].x, static_cast<float>(1.0 + p));
      }
    }
  }
}

TEST(PointCloud2Layout, RingInEveryDatatypeAndByteOrder) {
  for (const bool big : {false, true}) {
    for (const std::uint8_t type : kAllTypes) {
      SCOPED_TRACE(testing::Message() << "big_endian " << big << " datatype " << int{type});
      auto c = build_cloud({{"x", kF64}, {"y", kF64}, {"z", kF64}, {"ring", type}},
                           {{1, 0, 0, 0}, {1, 0, 0, 31}, {1, 0, 0, 127}}, big);
      const auto points = decode(c);
      ASSERT_EQ(points.size(), 3U);
      EXPECT_EQ(points[0].ring, 0);
      EXPECT_EQ(points[1].ring, 31);
      EXPECT_EQ(points[2].ring, 127);
    }
  }
}

TEST(PointCloud2Layout, TimeFloatSecondsOrIntegerNanosecondsRelativeToStamp) {
  const TimeNs stamp = 1'700'000'000'123'456'789;
  for (const bool big : {false, true}) {
    for (const std::uint8_t type : kAllTypes) {
      SCOPED_TRACE(testing::Message() << "big_endian " << big << " datatype " << int{type});
      const bool floating = type == kF32 || type == kF64;
      // Floating: seconds (0.5 s and -0.25 s, exact in binary); integers: nanoseconds.
      const double a = floating ? 0.5 : 100,
                   b = (type == kU8 || type == kU16 || type == kU32) ? 7 : (floating ? -0.25 : -7);
      auto c = build_cloud({{"x", kF32}, {"y", kF32}, {"z", kF32}, {"time", type}},
                           {{1, 0, 0, a}, {1, 0, 0, b}}, big, 1, 0, 0, stamp);
      const auto points = decode(c);
      ASSERT_EQ(points.size(), 2U);
      const TimeNs scale = floating ? kNsPerSecond : 1;
      EXPECT_EQ(points[0].time_ns, stamp + static_cast<TimeNs>(a * static_cast<double>(scale)));
      EXPECT_EQ(points[1].time_ns, stamp + static_cast<TimeNs>(b * static_cast<double>(scale)));
    }
  }
}

TEST(PointCloud2Layout, OusterTIsNanosecondsAndTimeWinsOverT) {
  const TimeNs stamp = 5 * kNsPerSecond;
  auto ouster = build_cloud({{"x", kF32}, {"y", kF32}, {"z", kF32}, {"t", kU32}}, {{1, 0, 0, 250'000}}, false,
                            1, 0, 0, stamp);
  EXPECT_EQ(decode(ouster).at(0).time_ns, stamp + 250'000);
  auto both = build_cloud({{"x", kF32}, {"y", kF32}, {"z", kF32}, {"t", kU32}, {"time", kF32}},
                          {{1, 0, 0, 9, 0.5}}, false, 1, 0, 0, stamp);
  EXPECT_EQ(decode(both).at(0).time_ns, stamp + kNsPerSecond / 2);
  auto none = build_cloud({{"x", kF32}, {"y", kF32}, {"z", kF32}}, {{1, 0, 0}}, false, 1, 0, 0, stamp);
  EXPECT_EQ(decode(none).at(0).time_ns, stamp);
}

TEST(PointCloud2Layout, AzimuthIsTheBeamsClockwiseFromX) {
  auto c = build_cloud({{"x", kF32}, {"y", kF32}, {"z", kF32}},
                       {{1, 0, 0}, {0, -1, 0}, {-1, 0, 0}, {0, 1, 0}, {1, -1, 0}}, false);
  const auto p = decode(c);
  ASSERT_EQ(p.size(), 5U);
  const double pi = std::numbers::pi;
  EXPECT_NEAR(p[0].azimuth_rad, 0.0, 1e-6);
  EXPECT_NEAR(p[1].azimuth_rad, pi / 2, 1e-6);  // -y is a quarter turn clockwise seen from above
  EXPECT_NEAR(p[2].azimuth_rad, pi, 1e-6);
  EXPECT_NEAR(p[3].azimuth_rad, 3 * pi / 2, 1e-6);
  EXPECT_NEAR(p[4].azimuth_rad, pi / 4, 1e-6);
}

TEST(PointCloud2Layout, PaddingRowsAndRowStepAreHonoured) {
  std::vector<std::vector<double>> values;
  for (int i = 0; i < 6; ++i)
    values.push_back({static_cast<double>(i), 10.0 + i, 20.0 + i, static_cast<double>(i % 4)});
  // Two rows of three, 5 bytes of padding per point and 7 per row.
  auto c = build_cloud({{"x", kF32}, {"y", kF32}, {"z", kF32}, {"ring", kU16}}, values, true, 2, 5, 7);
  const auto p = decode(c);
  ASSERT_EQ(p.size(), 6U);
  for (int i = 0; i < 6; ++i) {
    EXPECT_EQ(p[i].x, static_cast<float>(i));
    EXPECT_EQ(p[i].z, static_cast<float>(20 + i));
    EXPECT_EQ(p[i].ring, i % 4);
  }
  // The last row's padding may be absent (only its points are needed).
  c.data.resize(c.data.size() - 7);
  EXPECT_EQ(decode(c).size(), 6U);
}

TEST(PointCloud2Layout, NonFiniteBadRingAndBadTimePointsAreSkippedAndCounted) {
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  auto c = build_cloud({{"x", kF32}, {"y", kF32}, {"z", kF32}, {"ring", kF32}, {"time", kF64}},
                       {{1, 2, 3, 0, 0},
                        {nan, 2, 3, 0, 0},
                        {1, inf, 3, 0, 0},
                        {1, 2, 3, -1, 0},
                        {1, 2, 3, 1.5, 0},
                        {1, 2, 3, 70000, 0},
                        {1, 2, 3, 0, nan},
                        {1, 2, 3, 0, 1e12},
                        {4, 5, 6, 2, 0.001}},
                       false);
  CloudDecodeStats s;
  const auto p = decode(c, {}, &s);
  ASSERT_EQ(p.size(), 2U);
  EXPECT_EQ(s.points, 2U);
  EXPECT_EQ(s.non_finite_skipped, 2U);
  EXPECT_EQ(s.bad_ring_skipped, 3U);
  EXPECT_EQ(s.bad_time_skipped, 2U);
  EXPECT_EQ(p[1].x, 4.0F);
  EXPECT_EQ(p[1].ring, 2);
}

TEST(PointCloud2Layout, ElevationOrderedRingsMapToChannels) {
  const lidar::SensorModel vlp32 = lidar::make_vlp32c();
  const std::vector<std::uint16_t> map = ring_rank_to_channel(vlp32.elevation_deg);
  ASSERT_EQ(map.size(), 32U);
  // Rank r is the channel with exactly r lower beams (the VLP-32C's elevations are distinct).
  for (std::size_t r = 0; r < 32; ++r) {
    const double e = vlp32.elevation_deg[map[r]];
    std::size_t lower = 0;
    for (const double other : vlp32.elevation_deg)
      lower += other < e ? 1 : 0;
    EXPECT_EQ(lower, r);
  }
  EXPECT_EQ(map.front(), 0);  // -25 deg is channel 0
  EXPECT_EQ(map.back(), 29);  // +15 deg is channel 29
  auto c = build_cloud({{"x", kF32}, {"y", kF32}, {"z", kF32}, {"ring", kU16}},
                       {{1, 0, 0, 0}, {1, 0, 0, 31}, {1, 0, 0, 32}}, false);
  CloudDecodeStats s;
  const auto p = decode(c, map, &s);
  ASSERT_EQ(p.size(), 2U);
  EXPECT_EQ(p[0].ring, 0);
  EXPECT_EQ(p[1].ring, 29);
  EXPECT_EQ(s.bad_ring_skipped, 1U);  // rank 32 does not exist
}

// ---- rejections ----------------------------------------------------------------------------------

CloudReject reject_of(test::BuiltCloud& c, CloudLimits limits = {}) {
  return parse_layout(c.view(), limits).reject;
}

test::BuiltCloud xyz_cloud(std::size_t points = 4) {
  return build_cloud({{"x", kF32}, {"y", kF32}, {"z", kF32}, {"intensity", kU8}},
                     std::vector<std::vector<double>>(points, {1, 2, 3, 4}), false);
}

TEST(PointCloud2LayoutRejects, MissingOrNonFloatCoordinates) {
  auto no_z = build_cloud({{"x", kF32}, {"y", kF32}}, {{1, 2}}, false);
  EXPECT_EQ(reject_of(no_z), CloudReject::kMissingXyz);
  auto int_x = build_cloud({{"x", kI32}, {"y", kF32}, {"z", kF32}}, {{1, 2, 3}}, false);
  EXPECT_EQ(reject_of(int_x), CloudReject::kCoordinateType);
  auto c = xyz_cloud();
  c.fields[1].count = 0;
  EXPECT_EQ(reject_of(c), CloudReject::kCoordinateType);
}

TEST(PointCloud2LayoutRejects, UnknownDatatypeAndDuplicateNames) {
  auto c = xyz_cloud();
  c.fields[3].datatype = 9;
  EXPECT_EQ(reject_of(c), CloudReject::kUnknownDatatype);
  c.fields[3].datatype = 0;
  EXPECT_EQ(reject_of(c), CloudReject::kUnknownDatatype);
  auto d = xyz_cloud();
  d.names[3] = "x";
  EXPECT_EQ(reject_of(d), CloudReject::kDuplicateField);
}

TEST(PointCloud2LayoutRejects, FieldsOutsideThePointOrOverlapping) {
  auto c = xyz_cloud();
  c.fields[3].offset = c.point_step;  // intensity starts where the next point does
  EXPECT_EQ(reject_of(c), CloudReject::kFieldOutsidePoint);
  auto d = xyz_cloud();
  d.fields[1].offset = 2;  // y shares bytes 2..3 with x
  EXPECT_EQ(reject_of(d), CloudReject::kOverlappingFields);
  auto e = xyz_cloud();
  e.fields[0].count = 2;  // x[2] runs into y
  EXPECT_EQ(reject_of(e), CloudReject::kOverlappingFields);
  auto f = xyz_cloud();
  f.fields[3].count = 0xFFFFFFFFU;  // offset + count x size beyond 32 bits
  EXPECT_EQ(reject_of(f), CloudReject::kSizeOverflow);
}

TEST(PointCloud2LayoutRejects, StepsSizesAndCounts) {
  auto c = xyz_cloud();
  c.row_step -= 1;
  EXPECT_EQ(reject_of(c), CloudReject::kRowStepTooSmall);
  auto d = xyz_cloud();
  d.data.pop_back();
  EXPECT_EQ(reject_of(d), CloudReject::kDataTooShort);
  auto e = xyz_cloud();
  e.height = 2;  // the second row's bytes do not exist
  EXPECT_EQ(reject_of(e), CloudReject::kDataTooShort);
  auto f = xyz_cloud();
  f.width = 0x20000000U;  // width x point_step (13 bytes) beyond 32 bits
  f.row_step = 0xFFFFFFFFU;
  EXPECT_EQ(reject_of(f, CloudLimits{1ULL << 40}), CloudReject::kSizeOverflow);
  auto g = xyz_cloud(10);
  EXPECT_EQ(reject_of(g, CloudLimits{9}), CloudReject::kTooManyPoints);
  EXPECT_EQ(reject_of(g, CloudLimits{10}), CloudReject::kNone);
  auto h = xyz_cloud();
  h.width = 1'000'000;
  h.height = 1'000'000;  // 1e12 points claimed
  EXPECT_EQ(reject_of(h), CloudReject::kTooManyPoints);
}

TEST(PointCloud2LayoutRejects, EveryReasonHasAName) {
  for (int i = 0; i < static_cast<int>(CloudReject::kCount); ++i)
    EXPECT_STRNE(to_string(static_cast<CloudReject>(i)), "unknown");
}

TEST(PointCloud2Layout, EmptyCloudIsValidAndDecodesToNothing) {
  auto c = xyz_cloud(0);
  c.width = 0;
  std::vector<lidar::LidarPoint> out;
  const auto v = c.view();
  const auto layout = parse_layout(v);
  ASSERT_TRUE(layout.ok());
  EXPECT_EQ(decode_points(v, layout.layout, {}, out).points, 0U);
  EXPECT_TRUE(out.empty());
}

}  // namespace
}  // namespace rsu::ros
