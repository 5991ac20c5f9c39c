// SPDX-License-Identifier: Apache-2.0
// What a mount calibration is worth: its covariance in the mount's parameters and a verdict an operator
// can act on (good / ambiguous / failed, with the reason).
#pragma once

#include <string>

#include "calibration/point_to_plane.h"

namespace rsu::calibration {

enum class Verdict { kGood, kAmbiguous, kFailed };
const char* verdict_name(Verdict v);

struct VerdictLimits {
  std::size_t min_matches = 1000;  // background points matched to map planes
  std::size_t min_vertical_matches =
      200;                  // of those, on walls, poles, trunks (the ground fixes no x, y, yaw)
  double max_rms_m = 0.10;  // residual rms: beyond, the background is not this map
  // The weakest direction's standard deviation from the fit's statistics: beyond, the map does not hold
  // the sensor there (a street with nothing along it).
  double max_sigma_position_m = 0.0067;
  double max_sigma_angle_rad = 0.05 * 3.14159265358979 / 180.0 / 3.0;
};

struct MountUncertainty {
  Matrix6d covariance = Matrix6d::Zero();  // x, y, z (m), roll, pitch, yaw (rad)
  // The weakest-held position direction (unit, map frame) and its standard deviation; the same for the
  // rotation (axis of the weakest-held small rotation about the sensor).
  Eigen::Vector3d weakest_position_direction = Eigen::Vector3d::UnitX();
  double weakest_position_sigma_m = 0.0;
  Eigen::Vector3d weakest_rotation_axis = Eigen::Vector3d::UnitZ();
  double weakest_rotation_sigma_rad = 0.0;
  // Smallest over largest eigenvalue of the information, angles taken at a 10 m lever arm so that both
  // blocks are in m^-2: 1 holds every direction alike, 0 leaves one free.
  double information_ratio = 0.0;
};

// What the fit's own statistics cannot see: errors shared by neighbouring points (the map's sampling, the
// planes fitted to it, beams grazing a surface), measured on simulated backgrounds of known mounts
// (README, "Calibrating the mount"): with the statistics alone the stated sigmas were 3-10x too small.
// Added (as independent variances) to each position and angle.
struct ModelFloor {
  double position_sigma_m = 0.005;
  double angle_sigma_rad = 0.01 * 3.14159265358979 / 180.0;
};

// From the fit's information at the solution (pose: where it was taken) and the floor. A direction with
// no information gets an infinite standard deviation; the weakest directions are the statistics' alone.
MountUncertainty mount_uncertainty(const PlaneFit& fit, const Pose3& pose, const ModelFloor& floor = {});

struct VerdictResult {
  Verdict verdict = Verdict::kFailed;
  std::string reason;
};

VerdictResult judge(const PlaneFit& fit, const MountUncertainty& uncertainty, const VerdictLimits& limits);

}  // namespace rsu::calibration
