// SPDX-License-Identifier: Apache-2.0
// Velodyne calibration files (io/velodyne_calibration.h): the drivers' factory files are our built-in
// tables, and a broken file is refused naming the line and the field.
#include "io/velodyne_calibration.h"

#include <gtest/gtest.h>

#include <string>

#include "io/yaml_field.h"

namespace rsu::io {
namespace {

std::string real_calibration(const std::string& name) {
  return read_text_file(std::string(RSU_SOURCE_DIR) + "/tests/data/real/nebula_calibration/" + name);
}

// The built-in tables are the factory defaults: nebula's (and the ROS velodyne driver's) calibration
// files, read by the same parser lidar.calibration uses.
void expect_equal_tables(const lidar::SensorModel& built_in, const lidar::SensorModel& from_file) {
  ASSERT_EQ(built_in.laser_count(), from_file.laser_count());
  for (std::size_t i = 0; i < built_in.laser_count(); ++i) {
    EXPECT_NEAR(from_file.elevation_deg[i], built_in.elevation_deg[i], 1e-9) << "laser " << i;
    EXPECT_NEAR(from_file.azimuth_offset_deg[i], built_in.azimuth_offset_deg[i], 1e-9) << "laser " << i;
  }
  EXPECT_DOUBLE_EQ(from_file.distance_unit_m, built_in.distance_unit_m);
}

TEST(VelodyneCalibration, BuiltInTablesAreTheFactoryFiles) {
  const lidar::SensorModel vlp16 = lidar::make_vlp16();
  expect_equal_tables(vlp16, apply_velodyne_calibration(vlp16, real_calibration("VLP16.yaml"), "VLP16.yaml"));
  const lidar::SensorModel vlp32c = lidar::make_vlp32c();
  expect_equal_tables(vlp32c,
                      apply_velodyne_calibration(vlp32c, real_calibration("VLP32.yaml"), "VLP32.yaml"));
}

TEST(VelodyneCalibration, FileTablesReplaceTheBuiltInOnes) {
  // Laser ids in any order; rot_correction (rad) becomes the negated azimuth offset (deg).
  const std::string text =
      "lasers:\n"
      "  - {laser_id: 1, vert_correction: 0.1, rot_correction: 0.01}\n"
      "  - {laser_id: 0, vert_correction: -0.2, rot_correction: -0.02, dist_correction: 0.0}\n" +
      [] {
        std::string rest;
        for (int i = 2; i < 16; ++i)
          rest += "  - {laser_id: " + std::to_string(i) + ", vert_correction: 0.0, rot_correction: 0.0}\n";
        return rest;
      }() +
      "num_lasers: 16\ndistance_resolution: 0.002\n";
  const lidar::SensorModel m = apply_velodyne_calibration(lidar::make_vlp16(), text, "unit.yaml");
  EXPECT_NEAR(m.elevation_deg[0], -0.2 * 180.0 / kPi, 1e-12);
  EXPECT_NEAR(m.elevation_deg[1], 0.1 * 180.0 / kPi, 1e-12);
  EXPECT_NEAR(m.azimuth_offset_deg[0], 0.02 * 180.0 / kPi, 1e-12);
  EXPECT_NEAR(m.azimuth_offset_deg[1], -0.01 * 180.0 / kPi, 1e-12);
  EXPECT_EQ(m.elevation_deg[5], 0.0);
  EXPECT_EQ(m.name, "vlp16");
}

// The message of what apply_velodyne_calibration throws for `text` (empty if it does not throw).
std::string error_of(const std::string& text) {
  try {
    (void)apply_velodyne_calibration(lidar::make_vlp16(), text, "bad.yaml");
  } catch (const YamlError& e) {
    return e.what();
  }
  return {};
}

std::string lasers(int count, const std::string& extra_for_laser_3 = "") {
  std::string out = "lasers:\n";
  for (int i = 0; i < count; ++i) {
    out += "  - {laser_id: " + std::to_string(i) + ", vert_correction: 0.0, rot_correction: 0.0" +
           (i == 3 ? extra_for_laser_3 : "") + "}\n";
  }
  return out;
}

TEST(VelodyneCalibration, BrokenFilesAreRefusedWithTheirLine) {
  EXPECT_NE(error_of(lasers(15)).find("has 15 lasers, the vlp16 has 16"), std::string::npos)
      << error_of(lasers(15));
  EXPECT_NE(error_of(lasers(16) + "num_lasers: 32\n").find("bad.yaml:18: num_lasers: must be 16"),
            std::string::npos)
      << error_of(lasers(16) + "num_lasers: 32\n");
  EXPECT_NE(error_of(lasers(16, ", horiz_offset_correction: 0.02"))
                .find("bad.yaml:5: lasers[3].horiz_offset_correction: non-zero"),
            std::string::npos)
      << error_of(lasers(16, ", horiz_offset_correction: 0.02"));
  EXPECT_NE(error_of(lasers(16, ", rot_correction2: 1")).find("unknown field"), std::string::npos);
  std::string twice = lasers(16);
  twice.replace(twice.find("laser_id: 2,"), 12, "laser_id: 1,");
  EXPECT_NE(error_of(twice).find("laser 1 is listed twice"), std::string::npos) << error_of(twice);
  EXPECT_NE(error_of("lasers: [\n").find("bad.yaml:"), std::string::npos);
  std::string word = lasers(16);
  word.replace(word.find("laser_id: 3, vert_correction: 0.0"), 33, "laser_id: 3, vert_correction: two");
  EXPECT_NE(error_of(word).find("bad.yaml:5: lasers[3].vert_correction: expected a number, got \"two\""),
            std::string::npos)
      << error_of(word);
  EXPECT_NE(error_of("nothing: 1\n").find("unknown field"), std::string::npos);
  EXPECT_TRUE(error_of(lasers(16)).empty());
}

}  // namespace
}  // namespace rsu::io
