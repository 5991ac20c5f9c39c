// SPDX-License-Identifier: Apache-2.0
#include "io/mount_calibration_file.h"

#include "io/text_file.h"
#include "io/yaml_field.h"

namespace rsu::io {

MountCalibrationFile read_mount_calibration(const std::string& path) {
  MountCalibrationFile out;
  try {
    const YamlField f(parse_yaml(read_whole_file(path), path), "", path, 1);
    f.expect_map({"verdict", "reason", "mount", "sigma", "covariance", "residuals", "search", "lidar"});
    out.verdict = f.required("verdict").text();
    if (out.verdict != "good" && out.verdict != "ambiguous" && out.verdict != "failed")
      f.child("verdict").fail("expected good, ambiguous or failed, got \"" + out.verdict + "\"");
    out.reason = f.has("reason") ? f.child("reason").text() : "";
    const YamlField m = f.required("mount");
    m.expect_map({"x", "y", "z", "roll_deg", "pitch_deg", "yaw_deg"});
    out.mount = Pose3{m.required("x").number(),
                      m.required("y").number(),
                      m.required("z").number(),
                      deg_to_rad(m.required("roll_deg").number()),
                      deg_to_rad(m.required("pitch_deg").number()),
                      deg_to_rad(m.required("yaw_deg").number())};
  } catch (const YamlError& e) {
    throw MountCalibrationError(e.what());
  } catch (const FileError& e) {
    throw MountCalibrationError(path + ":0: <file>: " + e.problem());
  }
  return out;
}

}  // namespace rsu::io
