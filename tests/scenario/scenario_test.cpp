// SPDX-License-Identifier: Apache-2.0
// Scenario files: the shipped examples load as written, and every kind of broken file is rejected with
// an error naming the file, the line and the field.
#include <gtest/gtest.h>

#include <string>
#include <variant>

#include "common/angles.h"
#include "sim/scenario.h"

namespace rsu::sim {
namespace {

std::string error_of(const std::string& yaml) {
  try {
    parse_scenario(yaml, "broken.yaml");
  } catch (const ScenarioError& e) {
    return e.what();
  }
  return "<no error>";
}

TEST(Scenario, PilotFileMatchesThePaper) {
  const Scenario s = load_scenario_file(RSU_SOURCE_DIR "/scenarios/pilot.yaml");
  EXPECT_EQ(s.lidar.model_name, "vlp16");
  EXPECT_EQ(s.lidar.model.laser_count(), 16u);
  EXPECT_DOUBLE_EQ(s.lidar.mount.z, 2.0);
  EXPECT_DOUBLE_EQ(s.lidar.noise.range_sigma_m, 0.02);
  EXPECT_DOUBLE_EQ(s.lidar.noise.angle_sigma_rad, 0.001);
  ASSERT_EQ(s.scene.vehicles.size(), 1u);
  const Vehicle& v = s.scene.vehicles[0];
  EXPECT_DOUBLE_EQ(v.shape.length, 4.89);
  EXPECT_DOUBLE_EQ(v.shape.width, 1.92);
  EXPECT_DOUBLE_EQ(v.shape.height, 1.70);
  ASSERT_TRUE(std::holds_alternative<Spin>(v.trajectory));
  EXPECT_NEAR(std::get<Spin>(v.trajectory).rate_rad_s, deg_to_rad(20.0), 1e-12);
}

TEST(Scenario, CorridorFileExpandsRepeatedObjects) {
  const Scenario s = load_scenario_file(RSU_SOURCE_DIR "/scenarios/corridor.yaml");
  EXPECT_EQ(s.lidar.model_name, "vlp32c");
  EXPECT_DOUBLE_EQ(s.lidar.mount.z, 2.0);
  EXPECT_DOUBLE_EQ(s.lidar.mount.roll, 0.0);
  EXPECT_DOUBLE_EQ(s.lidar.mount.pitch, 0.0);
  EXPECT_EQ(s.scene.shrubs.size(), 30u + 29u);
  EXPECT_EQ(s.scene.poles.size(), 10u + 9u + 4u);
  // Repeated lamps are spaced by dx.
  EXPECT_DOUBLE_EQ(s.scene.poles[1].x - s.scene.poles[0].x, 25.0);
  ASSERT_EQ(s.scene.vehicles.size(), 1u);
  const auto& w = std::get<Waypoints>(s.scene.vehicles[0].trajectory);
  EXPECT_TRUE(w.smooth);
  EXPECT_EQ(w.points.front().pose.x, -60.0);
  EXPECT_EQ(w.points.back().pose.x, 60.0);
}

TEST(Scenario, MinimalFileTakesDefaults) {
  const Scenario s = parse_scenario("lidar: {model: vlp32c}\n", "min.yaml");
  EXPECT_EQ(s.lidar.model.laser_count(), 32u);
  EXPECT_DOUBLE_EQ(s.lidar.noise.range_sigma_m, 0.02);
  EXPECT_TRUE(s.scene.vehicles.empty());
  EXPECT_EQ(s.name, "min.yaml");
}

TEST(Scenario, GenericModelsByName) {
  EXPECT_EQ(parse_scenario("lidar: {model: generic128}\n", "g.yaml").lidar.model.laser_count(), 128u);
}

struct BrokenCase {
  const char* label;
  const char* yaml;
  const char* expected;  // substring: file, line and field
};

class BrokenScenario : public ::testing::TestWithParam<BrokenCase> {};

TEST_P(BrokenScenario, ErrorNamesFileLineAndField) {
  const BrokenCase& c = GetParam();
  const std::string error = error_of(c.yaml);
  EXPECT_NE(error.find(c.expected), std::string::npos) << "error was: " << error;
}

INSTANTIATE_TEST_SUITE_P(
    Cases, BrokenScenario,
    ::testing::Values(
        BrokenCase{"not_a_number", "lidar:\n  model: vlp16\n  mount:\n    z: two\n",
                   "broken.yaml:4: lidar.mount.z: expected a number, got \"two\""},
        BrokenCase{"unknown_field", "lidar:\n  model: vlp16\n  mont: {z: 2}\n",
                   "broken.yaml:3: lidar.mont: unknown field"},
        BrokenCase{"missing_model", "name: x\nlidar:\n  rpm: 600\n",
                   "broken.yaml:3: lidar: missing required field \"model\""},
        BrokenCase{"unknown_model", "lidar:\n  model: hdl64\n",
                   "broken.yaml:2: lidar.model: unknown LiDAR model"},
        BrokenCase{"negative_sigma", "lidar:\n  model: vlp16\n  noise:\n    range_sigma_m: -1\n",
                   "broken.yaml:4: lidar.noise.range_sigma_m: must be >= 0"},
        BrokenCase{"waypoints_not_increasing",
                   "lidar: {model: vlp16}\nvehicles:\n  - id: 1\n    trajectory:\n      waypoints:\n"
                   "        - {t_s: 1, x: 0}\n        - {t_s: 1, x: 5}\n",
                   "broken.yaml:7: vehicles[0].trajectory.waypoints[1].t_s: times must increase"},
        BrokenCase{"two_trajectories",
                   "lidar: {model: vlp16}\nvehicles:\n  - id: 1\n    trajectory:\n      static: {x: 1}\n"
                   "      spin: {x: 1}\n",
                   "vehicles[0].trajectory: exactly one of static, spin, waypoints"},
        BrokenCase{"duplicate_vehicle",
                   "lidar: {model: vlp16}\nvehicles:\n  - {id: 1, trajectory: {static: {x: 1}}}\n"
                   "  - {id: 1, trajectory: {static: {x: 2}}}\n",
                   "broken.yaml:4: vehicles[1].id: duplicate vehicle id"},
        BrokenCase{"absurd_vehicle",
                   "lidar: {model: vlp16}\nvehicles:\n  - id: 1\n    shape: {length: 100}\n"
                   "    trajectory: {static: {x: 1}}\n",
                   "broken.yaml:4: vehicles[0].shape: vehicle larger than"},
        BrokenCase{"syntax_error", "lidar:\n  model: [vlp16\n", "broken.yaml:"},
        BrokenCase{"list_expected", "lidar: {model: vlp16}\nscene:\n  poles: {x: 1}\n",
                   "broken.yaml:3: scene.poles: expected a list"},
        BrokenCase{"bad_repeat",
                   "lidar: {model: vlp16}\nscene:\n  poles:\n    - {x: 1, repeat: {count: 0}}\n",
                   "broken.yaml:4: scene.poles[0].repeat.count: must be an integer"},
        BrokenCase{
            "bad_interpolation",
            "lidar: {model: vlp16}\nvehicles:\n  - id: 1\n    trajectory:\n      interpolation: cubic\n"
            "      waypoints: [{t_s: 0, x: 0}]\n",
            "broken.yaml:5: vehicles[0].trajectory.interpolation: must be linear or smooth"},
        BrokenCase{
            "interpolated_static",
            "lidar: {model: vlp16}\nvehicles:\n  - id: 1\n    trajectory:\n      interpolation: smooth\n"
            "      static: {x: 1}\n",
            "vehicles[0].trajectory.interpolation: only waypoints are interpolated"},
        BrokenCase{"infinite", "lidar:\n  model: vlp16\n  mount: {x: .inf}\n",
                   "lidar.mount.x: expected a finite number"},
        // Found by fuzz/scenario_fuzzer: a complex key used to escape as yaml-cpp's TypedBadConversion.
        BrokenCase{"complex_key", "lidar:\n  model: vlp16\n  ? [a, b]\n  : 1\n",
                   "broken.yaml:3: lidar: expected a field name, got a complex key"},
        BrokenCase{"complex_key_at_top", "? {lidar: 1}\n: 2\n",
                   "broken.yaml:1: <document>: expected a field name, got a complex key"}),
    [](const ::testing::TestParamInfo<BrokenCase>& param_info) {
      return std::string(param_info.param.label);
    });

TEST(Scenario, MissingFileIsNamed) {
  try {
    load_scenario_file("/nonexistent/scenario.yaml");
    FAIL() << "expected an error";
  } catch (const ScenarioError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/scenario.yaml"), std::string::npos);
  }
}

}  // namespace
}  // namespace rsu::sim
