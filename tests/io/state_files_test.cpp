// SPDX-License-Identifier: Apache-2.0
// rsud's state directory (io/background_state.h, io/mount_calibration_file.h): the background round trip,
// and a clear error, never a crash, for every way the files can be broken or foreign.
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "common/angles.h"
#include "io/background_state.h"
#include "io/mount_calibration_file.h"
#include "io/text_file.h"

namespace rsu::io {
namespace {

class StateDirectory : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("rsu_state_test_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string dir() const { return dir_.string(); }
  std::string file(const char* name) const { return (dir_ / name).string(); }
  void write(const char* name, const std::string& text) const {
    std::ofstream(file(name), std::ios::binary) << text;
  }
  std::string read(const char* name) const { return read_whole_file(file(name)); }
  // The message load_background_state() throws (fails the test when it does not throw).
  std::string load_error() const {
    try {
      (void)load_background_state(dir());
    } catch (const BackgroundStateError& e) {
      return e.what();
    }
    ADD_FAILURE() << "no error";
    return "";
  }

  static PersistedBackground sample() {
    PersistedBackground b;
    b.sensor_model = "vlp32c";
    b.mount = Pose3{0.1, -8.5, 2.0, deg_to_rad(0.3), deg_to_rad(-0.2), deg_to_rad(91.7)};
    for (int f = 0; f < 3; ++f) {
      std::vector<lidar::LidarPoint> frame;
      for (int i = 0; i < 50 + f; ++i) {
        lidar::LidarPoint p;
        p.x = 0.25F * static_cast<float>(i) + static_cast<float>(f);
        p.y = -0.5F * static_cast<float>(i);
        p.z = 0.125F * static_cast<float>(f);
        p.intensity = static_cast<float>(i);
        p.ring = static_cast<std::uint16_t>(i % 32);
        p.azimuth_rad = 0.01F * static_cast<float>(i);
        p.time_ns = 1'000'000'000LL * (f + 1) + 1000LL * i;
        frame.push_back(p);
      }
      b.frames.push_back(frame);
    }
    return b;
  }

 private:
  std::filesystem::path dir_;
};

TEST_F(StateDirectory, NothingSavedIsNoBackground) {
  EXPECT_FALSE(load_background_state(dir()).has_value());
}

TEST_F(StateDirectory, RoundTripKeepsRotationsPointsAndTheExactMount) {
  const PersistedBackground saved = sample();
  save_background_state(dir(), saved);
  EXPECT_FALSE(std::filesystem::exists(file("background.yaml.tmp")));
  EXPECT_FALSE(std::filesystem::exists(file("background.pcd.tmp")));
  const auto loaded = load_background_state(dir());
  ASSERT_TRUE(loaded.has_value());
  EXPECT_EQ(loaded->sensor_model, "vlp32c");
  EXPECT_TRUE(loaded->mount == saved.mount);  // bit for bit: compared with == against the configuration
  ASSERT_EQ(loaded->frames.size(), saved.frames.size());
  for (std::size_t f = 0; f < saved.frames.size(); ++f) {
    ASSERT_EQ(loaded->frames[f].size(), saved.frames[f].size());
    for (std::size_t i = 0; i < saved.frames[f].size(); ++i) {
      const lidar::LidarPoint& a = saved.frames[f][i];
      const lidar::LidarPoint& b = loaded->frames[f][i];
      EXPECT_EQ(a.x, b.x);
      EXPECT_EQ(a.y, b.y);
      EXPECT_EQ(a.z, b.z);
      EXPECT_EQ(a.ring, b.ring);
      EXPECT_EQ(a.azimuth_rad, b.azimuth_rad);
    }
  }
  // Saved again over the old files: the new ones win.
  PersistedBackground next = saved;
  next.frames.pop_back();
  save_background_state(dir(), next);
  EXPECT_EQ(load_background_state(dir())->frames.size(), 2U);
}

TEST_F(StateDirectory, ForeignOrBrokenManifestIsAClearError) {
  save_background_state(dir(), sample());
  const std::string good = read("background.yaml");
  const auto replaced = [&](const std::string& from, const std::string& to) {
    std::string text = good;
    text.replace(text.find(from), from.size(), to);
    return text;
  };
  write("background.yaml", replaced("format: rsud-background", "format: something-else"));
  EXPECT_NE(load_error().find("not an rsud background"), std::string::npos);
  write("background.yaml", replaced("version: 1", "version: 2"));
  EXPECT_NE(load_error().find("this rsud reads version 1"), std::string::npos);
  write("background.yaml", "{{{ not yaml");
  EXPECT_NE(load_error().find("background.yaml"), std::string::npos);
  write("background.yaml", "");
  EXPECT_NE(load_error().find("expected a mapping"), std::string::npos);
  write("background.yaml", replaced("frame_points: [50", "frame_points: [-3"));
  EXPECT_NE(load_error().find("expected a point count"), std::string::npos);
  write("background.yaml", replaced("frame_points: [50", "frame_points: [49"));  // counts do not add up
  EXPECT_NE(load_error().find("counts"), std::string::npos);
}

TEST_F(StateDirectory, PointsFileCutOffMissingOrFromAnotherRunIsAClearError) {
  save_background_state(dir(), sample());
  const std::string points = read("background.pcd");
  write("background.pcd", points.substr(0, points.size() / 2));
  EXPECT_NE(load_error().find("hash differs"), std::string::npos);
  std::filesystem::remove(file("background.pcd"));
  EXPECT_NE(load_error().find("cannot open"), std::string::npos);
  PersistedBackground other = sample();
  other.frames[0][0].x += 1.0F;
  save_background_state(dir(), other);
  const std::string manifest = read("background.yaml");
  save_background_state(dir(), sample());
  write("background.yaml", manifest);  // the manifest of one run, the points of another
  EXPECT_NE(load_error().find("hash differs"), std::string::npos);
}

TEST_F(StateDirectory, SavingIntoAMissingDirectoryThrowsNamingTheFile) {
  try {
    save_background_state(file("no/such/dir"), sample());
    FAIL() << "no error";
  } catch (const BackgroundStateError& e) {
    EXPECT_NE(std::string(e.what()).find("background.pcd"), std::string::npos) << e.what();
  }
}

TEST_F(StateDirectory, CalibrationReportGivesVerdictAndMount) {
  // What rsu-calibrate --out writes (tools/rsu_calibrate/main.cpp), shortened.
  write("calibration.yaml",
        "verdict: good\nreason: \"\"\n"
        "mount: {x: 0.0012, y: -8.4983, z: 2.0052, roll_deg: 0.0150, pitch_deg: -0.0030, yaw_deg: -0.0090}\n"
        "sigma: {x_m: 0.005, y_m: 0.005, z_m: 0.005, roll_deg: 0.01, pitch_deg: 0.01, yaw_deg: 0.01}\n"
        "covariance: [1, 0]\nresiduals: {rms_m: 0.028}\nsearch: {iterations: 40}\n"
        "# paste into rsud's configuration:\nlidar:\n  mount: {x: 0.0012}\n");
  const MountCalibrationFile c = read_mount_calibration(file("calibration.yaml"));
  EXPECT_EQ(c.verdict, "good");
  EXPECT_DOUBLE_EQ(c.mount.y, -8.4983);
  EXPECT_NEAR(c.mount.yaw, deg_to_rad(-0.009), 1e-12);
  write("calibration.yaml", "verdict: maybe\nmount: {x: 0}\n");
  EXPECT_THROW(read_mount_calibration(file("calibration.yaml")), MountCalibrationError);
  write("calibration.yaml", "verdict: good\nmount: {x: one}\n");
  try {
    read_mount_calibration(file("calibration.yaml"));
    FAIL() << "no error";
  } catch (const MountCalibrationError& e) {
    EXPECT_NE(std::string(e.what()).find("mount.x"), std::string::npos) << e.what();
  }
  EXPECT_THROW(read_mount_calibration(file("missing.yaml")), MountCalibrationError);
}

}  // namespace
}  // namespace rsu::io
