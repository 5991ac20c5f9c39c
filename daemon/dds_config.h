// SPDX-License-Identifier: Apache-2.0
// The `dds:` section of rsud.yaml and the `lidar.input.dds_pointcloud2` input (deploy/rsud.yaml
// documents every key). Errors name the file, the line and the field, as in config.h.
#pragma once

#include <filesystem>

#include "daemon/config.h"
#include "io/yaml_field.h"

namespace rsu::daemon {

// Relative paths (cyclone_config) are taken relative to `base`, the configuration file's folder.
// `peers` receives the per-origin-RSU limit of dds.peers (the core applies it).
DdsConfig read_dds_config(const io::YamlField& field, const std::filesystem::path& base,
                          core::PeerConfig& peers);
DdsPointCloud2Input read_dds_pointcloud2_input(const io::YamlField& field);

// The ROS topic name of `vehicle_id`'s poses: `pattern` with "{vehicle_id}" replaced.
std::string vehicle_pose_topic(const std::string& pattern, std::uint64_t vehicle_id);

}  // namespace rsu::daemon
