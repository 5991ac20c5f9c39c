// SPDX-License-Identifier: Apache-2.0
// The report rsu-calibrate writes with --out (README, "Calibrating the mount"), read back by rsud from
// its state directory: the verdict and the mount. Only a `good` calibration is used; the rest of the
// report (sigmas, covariance, residuals) is for the operator.
#pragma once

#include <stdexcept>
#include <string>

#include "common/pose.h"

namespace rsu::io {

class MountCalibrationError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct MountCalibrationFile {
  std::string verdict;  // good | ambiguous | failed
  std::string reason;
  Pose3 mount;
};

// Throws MountCalibrationError "<path>:<line>: <field>: <what is wrong>" for a file that cannot be read
// or is not rsu-calibrate's report (no verdict, no mount, a mount field not a number).
MountCalibrationFile read_mount_calibration(const std::string& path);

}  // namespace rsu::io
