// SPDX-License-Identifier: Apache-2.0
// Velodyne calibration files as the ROS velodyne driver and nebula (Autoware's driver) read them:
//
//   lasers:
//     - {laser_id: 0, vert_correction: -0.2618, rot_correction: 0.0, dist_correction: 0.0, ...}
//   num_lasers: 16
//   distance_resolution: 0.002
//
// Angles in radians. vert_correction is the laser's elevation; rot_correction is subtracted from the
// block azimuth by those drivers, so it becomes the negated azimuth offset of our model
// (lidar/sensor_model.h). The remaining fields move points only for sensors with per-laser distance
// and origin offsets (the HDL-64E); for the VLP-16, VLP-32C and HDL-32E they are zero in the factory
// files and a non-zero one is refused, named, rather than silently ignored. focal_distance,
// focal_slope, min_intensity and max_intensity only rescale intensities and are ignored.
#pragma once

#include <string>

#include "lidar/sensor_model.h"

namespace rsu::io {

// `base` with its elevation and azimuth offset tables (and distance unit) replaced by the file's.
// Throws YamlError "<source>:<line>: <field>: <what>" for a malformed file, a laser count other than
// the model's, laser ids that are not 0..N-1 once each, or an unsupported non-zero correction.
lidar::SensorModel apply_velodyne_calibration(const lidar::SensorModel& base, const std::string& yaml_text,
                                              const std::string& source_name);

}  // namespace rsu::io
