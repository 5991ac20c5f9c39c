// SPDX-License-Identifier: Apache-2.0
// rsud's learned background kept in its state directory (systemd's StateDirectory=), so that a restart
// serves at once instead of learning again with no vehicle in view (README, "Calibrating the mount").
//
// Two files, each written to a temporary name, flushed to disk and renamed over the old one (a crash
// leaves the old file or the new one, never half of one):
//   background.pcd   every learned rotation in the SENSOR frame, one after the other (io/pcd_io.h);
//   background.yaml  what they are: format rsud-background, version 1, the sensor model, the mount in
//                    effect when they were learned (radians, exact), the points per rotation, and the
//                    FNV-1a 64 hash of background.pcd (the pair written by one run, whole).
// The manifest is written last: a crash between the two leaves a hash that does not match, refused.
#pragma once

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/pose.h"
#include "lidar/point.h"

namespace rsu::io {

class BackgroundStateError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct PersistedBackground {
  std::string sensor_model;
  // The mount in effect when the rotations were learned: under another one (a recalibration), they
  // describe where the sensor stood before and are not used.
  Pose3 mount;
  std::vector<std::vector<lidar::LidarPoint>> frames;  // sensor frame
};

inline constexpr int kBackgroundStateVersion = 1;

// Writes both files into `directory` (which must exist). Throws BackgroundStateError naming the file
// and the system's reason (full disk, read-only, permission).
void save_background_state(const std::string& directory, const PersistedBackground& background);

// nullopt when the directory holds no background.yaml. Throws BackgroundStateError naming the file and
// what is wrong when one is there but unusable: not YAML, another format or version, a points file
// missing, cut off or not the one the manifest describes (hash), point counts that do not add up.
std::optional<PersistedBackground> load_background_state(const std::string& directory);

// FNV-1a, 64 bits, of `bytes`: the manifest's check that the points file is the one written with it.
std::uint64_t fnv1a64(const std::string& bytes);

}  // namespace rsu::io
