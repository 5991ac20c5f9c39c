// SPDX-License-Identifier: Apache-2.0
// The paper's pilot experiment (Sec. 3.1, Table 1; docs/design.md §2), reproduced: a LiDAR above an empty
// ground plane (2 m in the paper), the vehicle spinning about its centre at 20 deg/s while the LiDAR runs
// at 10 Hz (2 deg per frame), one full turn per distance, distances 3 m to 40 m in 0.5 m steps. Each
// frame is a cell (distance, yaw) of the paper's heat maps; every cell is measured three ways, all
// through the fix function rsud runs (perception::fix_vehicle) with rsud's configuration: the raw
// L-shape box the fix starts from (`lshape`), Algorithm 1 (`algorithm1`) and the improved correction
// (`improved`, given a yaw prior with a uniform error of up to +-prior_error_deg).
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "common/time.h"
#include "perception/vehicle_fix.h"
#include "sim/scene.h"

namespace rsu::eval {

struct PilotConfig {
  std::string model_name = "vlp16";
  double lidar_height_m = 2.0;  // Table 1
  double distance_min_m = 3.0;  // Sec. 3.1: 3 m to 40 m
  double distance_max_m = 40.0;
  double distance_step_m = 0.5;
  double spin_rate_deg_s = 20.0;        // Table 1: 20 deg/s at 10 Hz = 2 deg per frame
  double prior_error_deg = 10.0;        // the improved correction's yaw prior error bound (issue target)
  double prior_sigma_deg = 10.0;        // the sigma the prior is announced with
  double ground_filter_height_m = 0.2;  // the pilot's "drop zero-height points"
  std::string vehicle_name = "suv";     // for reports
  sim::VehicleShape vehicle;            // Lexus RX450h by default
  sim::NoiseModel noise;                // docs/design.md §2 defaults
  // The fix's configuration: rsud's (the library defaults, deploy/rsud.yaml). The method field is
  // overridden per measured method.
  perception::VehicleFixConfig fix;
  int threads = 2;
};

enum class PilotMethod { lshape, algorithm1, improved };
inline constexpr std::array<PilotMethod, 3> kPilotMethods = {PilotMethod::lshape, PilotMethod::algorithm1,
                                                             PilotMethod::improved};
const char* to_string(PilotMethod method);

// One method's result in one cell; NaN where there is no fix (or, for lshape, no covariance).
struct MethodCell {
  static constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  double center_err_m = kNaN;
  double yaw_err_deg = kNaN;    // length axis vs the true one, mod 180, in [0, 90]
  double sigma_m = kNaN;        // sqrt of the larger eigenvalue of the stated position covariance
  double yaw_sigma_deg = kNaN;  // sqrt of the stated yaw variance
  double position_nees = kNaN;  // e^T P^-1 e of the centre error against the stated covariance
  std::string status;           // "ok" or why there is no fix (perception::CorrectionStatus)

  bool fixed() const { return status == "ok"; }
};

// One frame of the experiment.
struct PilotCell {
  double distance_m = 0;
  int frame_in_turn = 0;      // 0 .. frames_per_turn - 1
  double yaw_deg = 0;         // true yaw at the sweep time, [0, 360)
  TimeNs sweep_ns = 0;        // median firing time of the vehicle's points
  std::size_t points = 0;     // foreground points (all on the vehicle: the scene is empty)
  bool outline_seen = false;  // the points show the footprint's place (outline_observability.h)
  bool fit_ok = false;
  double area_err_m2 = MethodCell::kNaN;  // fitted area - true area
  std::array<MethodCell, 3> methods;      // indexed by PilotMethod
  std::string improved_resolution;        // how the improved correction settled length vs width

  const MethodCell& of(PilotMethod m) const { return methods[static_cast<std::size_t>(m)]; }
  const MethodCell& improved() const { return of(PilotMethod::improved); }
};

struct PilotResult {
  PilotConfig config;
  int frames_per_turn = 0;
  std::vector<double> distances;
  // Distances left out because the vehicle, spinning there, would reach into a LiDAR mounted lower
  // than its roof (the LiDAR cannot be inside the vehicle).
  std::vector<double> skipped_distances;
  std::vector<PilotCell> cells;  // distance-major
  double wall_seconds = 0;
  std::uint64_t rays_cast = 0;
};

PilotResult run_pilot(const PilotConfig& config);

}  // namespace rsu::eval
