// SPDX-License-Identifier: Apache-2.0
#include "io/velodyne_calibration.h"

#include <cmath>
#include <vector>

#include "common/angles.h"
#include "io/yaml_field.h"

namespace rsu::io {

lidar::SensorModel apply_velodyne_calibration(const lidar::SensorModel& base, const std::string& yaml_text,
                                              const std::string& source_name) {
  const YAML::Node root = parse_yaml(yaml_text, source_name);
  const YamlField file(root, "", source_name, 1);
  file.expect_map({"lasers", "num_lasers", "distance_resolution"});
  const std::vector<YamlField> lasers = file.required("lasers").items();
  const std::size_t n = base.laser_count();
  if (lasers.size() != n) {
    file.child("lasers").fail("has " + std::to_string(lasers.size()) + " lasers, the " + base.name + " has " +
                              std::to_string(n));
  }
  if (file.has("num_lasers") && file.child("num_lasers").number() != static_cast<double>(n)) {
    file.child("num_lasers").fail("must be " + std::to_string(n) + " for the " + base.name);
  }
  lidar::SensorModel m = base;
  m.distance_unit_m = file.positive_or("distance_resolution", base.distance_unit_m);
  if (m.distance_unit_m > 0.1) {
    file.child("distance_resolution").fail("must be <= 0.1 m");
  }
  std::vector<bool> seen(n, false);
  for (const YamlField& laser : lasers) {
    laser.expect_map({"laser_id", "vert_correction", "rot_correction", "dist_correction", "dist_correction_x",
                      "dist_correction_y", "vert_offset_correction", "horiz_offset_correction",
                      "focal_distance", "focal_slope", "min_intensity", "max_intensity"});
    const double id_value = laser.required("laser_id").number();
    if (id_value < 0 || id_value >= static_cast<double>(n) || id_value != std::floor(id_value)) {
      laser.child("laser_id").fail("must be a whole number within [0, " + std::to_string(n - 1) + "]");
    }
    const auto id = static_cast<std::size_t>(id_value);
    if (seen[id]) {
      laser.child("laser_id").fail("laser " + std::to_string(id) + " is listed twice");
    }
    seen[id] = true;
    const double vertical = laser.required("vert_correction").number();
    const double rotation = laser.required("rot_correction").number();
    if (std::abs(vertical) > kPi / 2) {
      laser.child("vert_correction").fail("must be within [-pi/2, pi/2] rad");
    }
    if (std::abs(rotation) > kPi) {
      laser.child("rot_correction").fail("must be within [-pi, pi] rad");
    }
    for (const char* field : {"dist_correction", "dist_correction_x", "dist_correction_y",
                              "vert_offset_correction", "horiz_offset_correction"}) {
      if (laser.number_or(field, 0.0) != 0.0) {
        laser.child(field).fail(
            std::string("non-zero ") + field + " is not supported for the " + base.name +
            " (only vert_correction and rot_correction are applied; its factory file has 0)");
      }
    }
    m.elevation_deg[id] = rad_to_deg(vertical);
    m.azimuth_offset_deg[id] = -rad_to_deg(rotation);  // the drivers subtract rot_correction
  }
  if (const std::string error = lidar::sensor_model_error(m); !error.empty()) {
    file.fail(error);
  }
  return m;
}

}  // namespace rsu::io
