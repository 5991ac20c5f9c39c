// PCD round trip and clear errors for files that are missing or lack coordinates.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include <unistd.h>

#include "io/pcd_io.h"

namespace rsu::io {
namespace {

std::string temp_path(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("rsu_io_test_" + std::to_string(::getpid()) + "_" + name)).string();
}

TEST(PcdIo, RoundTripKeepsEveryField) {
  std::vector<LidarPoint> points;
  for (int i = 0; i < 100; ++i) {
    LidarPoint p;
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
  const std::string path = temp_path("xyz.pcd");
  {
    std::ofstream out(path);
    out << "VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 2\nHEIGHT 1\n"
           "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\nDATA ascii\n1 2 3\n4 5 6\n";
  }
  const auto points = read_pcd(path);
  std::filesystem::remove(path);
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

}  // namespace
}  // namespace rsu::io
