// SPDX-License-Identifier: Apache-2.0
// The vehicle's own localization over the drive: its roof LiDAR simulated frame by frame (carried by the
// vehicle, each ray at its own firing time), de-skewed with the velocity of the last two NDT poses, and
// matched against the map by NDT with the initial guess from the previous pose plus constant-velocity
// motion (paper Sec. 4.1: scan matching only).
#pragma once

#include <functional>
#include <vector>

#include "eval/corridor/experiment_config.h"

namespace rsu::eval {

struct NdtSample {
  TimeNs time_ns = 0;  // the scan's reference time (its last firing)
  Pose2 pose;          // NDT's vehicle pose
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  bool converged = false;
  int iterations = 0;
  double fitness = 0.0;        // m^2 (NdtResult)
  double degeneracy = 1.0;     // NdtResult
  double weak_axis_rad = 0.0;  // NdtResult
  Pose2 truth;                 // the true pose at time_ns
};

// Each frame is simulated on `threads` threads (the same frame on any count); progress(done, total) is
// called after each frame.
std::vector<NdtSample> run_vehicle_ndt(const CorridorExperimentConfig& config, int threads,
                                       const std::function<void(int, int)>& progress = {});

}  // namespace rsu::eval
