// SPDX-License-Identifier: Apache-2.0
// Configuration of the vehicle-side EKF that fuses NDT poses with RSU corrections. Defaults suit a car
// in town with 10 Hz NDT and 10 Hz RSU corrections (the paper's rates, Section 4).
#pragma once

#include <Eigen/Core>
#include <cstddef>

#include "common/angles.h"
#include "common/time.h"
#include "fusion/ctrv_model.h"

namespace rsu::fusion {

struct VehicleEkfConfig {
  CtrvNoise process_noise;
  // Longest single linearisation step when predicting over a gap.
  double max_prediction_step_s = 0.05;

  // Chi-square gate on the 3-dof innovation (x, y, yaw): 16.27 is the 99.9 % quantile, so an honest
  // measurement is dropped about once in a thousand while a gross error (an off-by-90 deg box, a wrong
  // cluster) is not let in.
  double gate_chi2 = 16.27;
  // An RSU box yaw differing from the estimate by more than this (after choosing the nearest branch
  // modulo pi) is the off-by-90 deg failure of L-shape fitting (docs/design.md §1); it is rejected whatever
  // covariance the RSU claims, so such a fix never moves the pose.
  double max_rsu_yaw_innovation_rad = kPi / 4.0;

  // Offset of the state's reference point from the footprint box centre in the vehicle frame (x forward,
  // y left), as announced to the RSU. RSU corrections give the box centre and are mapped through it.
  Eigen::Vector2d reference_offset = Eigen::Vector2d::Zero();

  // Measurements are kept this long (and at most max_history of them) so that one arriving late can be
  // inserted in time order and the later ones re-applied. Older ones are refused as too old.
  TimeNs history_window = 2 * kNsPerSecond;
  std::size_t max_history = 256;
  // A full-heading pose arriving this long after the newest fused measurement restarts the filter.
  TimeNs restart_after_gap = 5 * kNsPerSecond;

  // Lock-out recovery. The gate trusts the filter's prediction; once the motion state is wrong (a vehicle
  // that stood still, so its speed variance shrank to the process noise, then jumps to speed at once) the
  // gate refuses every own-localization pose, each farther from the prediction than the last, and the
  // filter never follows the vehicle again. When this many NDT poses in a row fail the gate with no
  // measurement of any source accepted in between, the filter, not the localization, is what is wrong: it
  // restarts from the latest NDT pose with that pose's covariance and the wide initial motion
  // uncertainty, as at start-up. A restart, not a growing process noise: the pose comes back at once
  // instead of after seconds of lag, and the gate stays as tight as before for honest NDT noise. An RSU
  // fix accepted in between (the filter re-anchored at RSU fixes because NDT drifted) breaks the run, so a
  // drifted NDT does not pull the filter back. 5 at 10 Hz NDT: half a second; an honest NDT fails the
  // 99.9 % gate 5 times in a row about once in 10^15.
  int ndt_restart_after_rejections = 5;

  // Uncertainty of the motion states when the filter starts from a pose measurement alone.
  double initial_speed_sigma_mps = 10.0;
  double initial_yaw_rate_sigma_rps = 0.5;
};

}  // namespace rsu::fusion
