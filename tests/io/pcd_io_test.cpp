// SPDX-License-Identifier: Apache-2.0
// PCD round trip and clear errors for files that are missing or lack coordinates.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <vector>

#include <unistd.h>

#include "io/pcd_io.h"

namespace rsu::io {
namespace {

std::string temp_path(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("rsu_io_test_" + std::to_string(::getpid()) + "_" + name))
      .string();
}

// The points of a PCD file with `text` (written to a temporary file, removed afterwards).
std::vector<lidar::LidarPoint> read_text(const std::string& name, const std::string& text) {
  const std::string path = temp_path(name);
  {
    std::ofstream out(path, std::ios::binary);
    out << text;
  }
  std::vector<lidar::LidarPoint> points = read_pcd(path);
  std::filesystem::remove(path);
  return points;
}

TEST(PcdIo, RoundTripKeepsEveryField) {
  std::vector<lidar::LidarPoint> points;
  for (int i = 0; i < 100; ++i) {
    lidar::LidarPoint p;
    p.x = 0.5F * static_cast<float>(i);
    p.y = -1.25F * static_cast<float>(i);
    p.z = 0.01F * static_cast<float>(i);
    p.intensity = static_cast<float>(i % 256);
    p.ring = static_cast<std::uint16_t>(i % 32);
    p.azimuth_rad = 0.05F * static_cast<float>(i);
    p.time_ns = 1'000'000'000LL + 55'296LL * i;
    points.push_back(p);
  }
  const std::string path = temp_path("roundtrip.pcd");
  write_pcd(path, points);
  const auto back = read_pcd(path);
  std::filesystem::remove(path);
  ASSERT_EQ(back.size(), points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    EXPECT_EQ(back[i].x, points[i].x);
    EXPECT_EQ(back[i].y, points[i].y);
    EXPECT_EQ(back[i].z, points[i].z);
    EXPECT_EQ(back[i].intensity, points[i].intensity);
    EXPECT_EQ(back[i].ring, points[i].ring);
    EXPECT_EQ(back[i].azimuth_rad, points[i].azimuth_rad);
    // Time is stored as float64 seconds: exact to well under a microsecond at these magnitudes.
    EXPECT_NEAR(static_cast<double>(back[i].time_ns), static_cast<double>(points[i].time_ns), 1.0);
  }
}

TEST(PcdIo, ReadsForeignFileWithOnlyXyz) {
  const auto points =
      read_text("xyz.pcd",
                "VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 2\nHEIGHT 1\n"
                "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\nDATA ascii\n1 2 3\n4 5 6\n");
  ASSERT_EQ(points.size(), 2u);
  EXPECT_EQ(points[1].x, 4.0F);
  EXPECT_EQ(points[1].z, 6.0F);
  EXPECT_EQ(points[1].ring, 0u);
}

TEST(PcdIo, MissingCoordinatesIsAClearError) {
  const std::string path = temp_path("noxyz.pcd");
  {
    std::ofstream out(path);
    out << "VERSION .7\nFIELDS a b\nSIZE 4 4\nTYPE F F\nCOUNT 1 1\nWIDTH 1\nHEIGHT 1\n"
           "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 1\nDATA ascii\n1 2\n";
  }
  EXPECT_THROW(read_pcd(path), PcdError);
  std::filesystem::remove(path);
}

TEST(PcdIo, MissingFileNamesThePath) {
  try {
    read_pcd("/nonexistent/frame.pcd");
    FAIL();
  } catch (const PcdError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/frame.pcd"), std::string::npos);
  }
}

// Inputs found by fuzz/pcd_fuzzer that crashed PCL's reader (the one used before io/pcd_header.h) or
// escaped it as another exception: each must be a PcdError naming the file.
struct MalformedPcd {
  const char* label;
  const char* text;
};

class PcdIoMalformed : public ::testing::TestWithParam<MalformedPcd> {};

TEST_P(PcdIoMalformed, IsAPcdErrorNamingTheFile) {
  const std::string path = temp_path(std::string(GetParam().label) + ".pcd");
  {
    std::ofstream out(path, std::ios::binary);
    out << GetParam().text;
  }
  try {
    read_pcd(path);
    ADD_FAILURE() << "expected a PcdError";
  } catch (const PcdError& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
  std::filesystem::remove(path);
}

INSTANTIATE_TEST_SUITE_P(
    FuzzFindings, PcdIoMalformed,
    ::testing::Values(
        // PCL 1.13 dereferenced the first of no fields (SEGV).
        MalformedPcd{"empty", ""}, MalformedPcd{"newline_only", "\n"},
        MalformedPcd{"version_only", "VERSION .7\n"},
        // PCL's header parser threw std::out_of_range on a DATA line without a separate type.
        MalformedPcd{"data_without_type",
                     "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
                     "WIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA'ascii\n1 2 3\n"},
        // PCL allocated the declared cloud (here 12 GB) before reading a byte of data.
        MalformedPcd{"declares_billions",
                     "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
                     "WIDTH 1000000000\nHEIGHT 1\nPOINTS 1000000000\nDATA ascii\n1 2 3\n"},
        MalformedPcd{"size_not_a_number",
                     "VERSION 0.7\nFIELDS x y z\nSIZE 4 43333333333333333333 4\nTYPE F F F\n"
                     "COUNT 1 1 1\nWIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA ascii\n1 2 3\n"},
        // A COUNT that wraps PCL's uint32 point size let its ASCII reader write outside the cloud.
        MalformedPcd{"count_negative",
                     "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 -1\n"
                     "WIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA ascii\n1 2 3\n"},
        MalformedPcd{"count_huge",
                     "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNTS 1 1 2147483647\n"
                     "WIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA ascii\n1 2 3\n"},
        // FIELDS again after POINTS: PCL sized its buffer for one float per point, then wrote three.
        MalformedPcd{"fields_after_points",
                     "VERSION 0.7\nFIELDS x\nSIZE 4\nTYPE F\nCOUNT 1\nWIDTH 1\nHEIGHT 1\n"
                     "POINTS 1\nFIELDS x y z\nDATA ascii\n1 2 3\n"},
        // PCL parses header lines after DATA too: this COUNT grew the layout after the buffer was sized.
        MalformedPcd{"count_after_data",
                     "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 1\n"
                     "HEIGHT 1\nPOINTS 1\nDATA ascii\nCOUNT 1 1 64\n1 2 3\n"},
        // A keyword behind a vertical tab is still one to PCL (it trims the line first).
        MalformedPcd{"keyword_after_vertical_tab",
                     "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
                     "WIDTH 1\nHEIGHT 1\nPOINTS 1\n\vFIELDS x y z w\nDATA ascii\n1 2 3\n"},
        // A ring or time that does not fit its integer type was cast anyway (undefined behaviour).
        MalformedPcd{"ring_too_large",
                     "VERSION 0.7\nFIELDS x y z ring\nSIZE 4 4 4 4\nTYPE F F F F\nCOUNT 1 1 1 1\n"
                     "WIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA ascii\n1 2 3 542328000\n"},
        MalformedPcd{"ring_negative",
                     "VERSION 0.7\nFIELDS x y z ring\nSIZE 4 4 4 4\nTYPE F F F F\nCOUNT 1 1 1 1\n"
                     "WIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA ascii\n1 2 3 -1\n"},
        MalformedPcd{"time_beyond_clock",
                     "VERSION 0.7\nFIELDS x y z time\nSIZE 4 4 4 8\nTYPE F F F F\n"
                     "COUNT 1 1 1 1\nWIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA ascii\n1 2 3 1e12\n"}),
    [](const ::testing::TestParamInfo<MalformedPcd>& param_info) {
      return std::string(param_info.param.label);
    });

// binary_compressed data states its uncompressed size, which PCL allocated (here 1 GB) and unpacked
// every declared point into, whatever it said.
TEST(PcdIo, CompressedSizeDisagreeingWithTheHeaderIsAPcdError) {
  const std::string path = temp_path("compressed.pcd");
  {
    std::ofstream out(path, std::ios::binary);
    out << "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 1\nHEIGHT 1\nPOINTS 1\n"
           "DATA binary_compressed\n";
    const std::uint32_t sizes[2] = {4, 1'000'000'000};  // compressed, uncompressed (the header says 12)
    out.write(reinterpret_cast<const char*>(sizes), sizeof(sizes));
    out << "abcd";
  }
  EXPECT_THROW(read_pcd(path), PcdError);
  std::filesystem::remove(path);
}

// binary_compressed data: the fields one after the other (all x, then all y, then all z), LZF-packed.
// Here x is a literal run, y a back reference to x (the same bytes), z another literal run.
TEST(PcdIo, ReadsCompressedData) {
  const float x[2] = {1.5F, -2.0F}, z[2] = {0.25F, 3.0F};
  std::vector<std::uint8_t> packed;
  auto literal = [&packed](const float* values) {
    packed.push_back(7);  // 8 literal bytes follow
    const auto* bytes = reinterpret_cast<const std::uint8_t*>(values);
    packed.insert(packed.end(), bytes, bytes + 8);
  };
  literal(x);
  packed.push_back((8 - 2) << 5);  // a back reference of 8 bytes ...
  packed.push_back(8 - 1);         // ... 8 bytes back: x again
  literal(z);
  const std::string path = temp_path("compressed_ok.pcd");
  {
    std::ofstream out(path, std::ios::binary);
    out << "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 2\nHEIGHT 1\nPOINTS 2\n"
           "DATA binary_compressed\n";
    const std::uint32_t sizes[2] = {static_cast<std::uint32_t>(packed.size()), 24};
    out.write(reinterpret_cast<const char*>(sizes), sizeof(sizes));
    out.write(reinterpret_cast<const char*>(packed.data()), static_cast<std::streamsize>(packed.size()));
  }
  const auto points = read_pcd(path);
  std::filesystem::remove(path);
  ASSERT_EQ(points.size(), 2U);
  for (int i = 0; i < 2; ++i) {
    EXPECT_EQ(points[static_cast<std::size_t>(i)].x, x[i]);
    EXPECT_EQ(points[static_cast<std::size_t>(i)].y, x[i]);
    EXPECT_EQ(points[static_cast<std::size_t>(i)].z, z[i]);
  }
}

// ASCII with a field of several values before the ones read, integer types and an organised cloud's
// hole (NaN coordinates: skipped).
TEST(PcdIo, ReadsAsciiWithArraysAndHoles) {
  const auto points =
      read_text("ascii_arrays.pcd",
                "# written by hand\nVERSION 0.7\nFIELDS normal x y z ring\nSIZE 4 4 4 4 2\nTYPE F F F F U\n"
                "COUNT 3 1 1 1 1\nWIDTH 3\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 3\nDATA ascii\n"
                "0 0 1 1.5 2.5 3.5 7\n0 0 1 nan nan nan 8\n0 0 1 -1 -2 -3 9\n");
  ASSERT_EQ(points.size(), 2U);
  EXPECT_EQ(points[0].x, 1.5F);
  EXPECT_EQ(points[0].z, 3.5F);
  EXPECT_EQ(points[0].ring, 7U);
  EXPECT_EQ(points[1].y, -2.0F);
  EXPECT_EQ(points[1].ring, 9U);
}

}  // namespace
}  // namespace rsu::io
