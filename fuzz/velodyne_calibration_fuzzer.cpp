// SPDX-License-Identifier: Apache-2.0
// Fuzzes the Velodyne calibration reader (io/velodyne_calibration.h, lidar.calibration): any text must
// give a usable sensor model or a YamlError naming the line and field, never a crash or another
// exception. The first byte picks the model (VLP-16, VLP-32C, HDL-32E); the rest is the file.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "io/velodyne_calibration.h"
#include "io/yaml_field.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0)
    return 0;
  const rsu::lidar::SensorModel base = data[0] % 3 == 0   ? rsu::lidar::make_vlp16()
                                       : data[0] % 3 == 1 ? rsu::lidar::make_vlp32c()
                                                          : rsu::lidar::make_hdl32e();
  const std::string text(reinterpret_cast<const char*>(data + 1), size - 1);
  try {
    const rsu::lidar::SensorModel m = rsu::io::apply_velodyne_calibration(base, text, "calibration.yaml");
    if (!rsu::lidar::sensor_model_error(m).empty())
      std::abort();  // an accepted calibration is a usable model
  } catch (const rsu::io::YamlError&) {
    // the documented failure
  }
  return 0;
}
