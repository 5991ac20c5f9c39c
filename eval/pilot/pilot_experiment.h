// The paper's pilot experiment (Sec. 3.1, Table 1; DESIGN.md §2), reproduced: a LiDAR 2 m above an
// empty ground plane, the vehicle spinning about its centre at 20 deg/s while the LiDAR runs at 10 Hz
// (2 deg per frame), one full turn per distance, distances 3 m to 40 m in 0.5 m steps. Each frame is a
// cell (distance, yaw) of the paper's heat maps; every cell is measured three ways: the raw L-shape box
// (`lshape`), Algorithm 1 (`algorithm1`) and the improved correction (`improved`, given a yaw prior with
// a uniform error of up to +-prior_error_deg).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "common/time.h"
#include "eval/consistency.h"
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
  sim::VehicleShape vehicle;            // Lexus RX450h by default
  sim::NoiseModel noise;                // DESIGN.md §2 defaults
  int threads = 2;
};

// One frame of the experiment.
struct PilotCell {
  double distance_m = 0;
  int frame_in_turn = 0;   // 0 .. frames_per_turn - 1
  double yaw_deg = 0;      // true yaw at the sweep time, [0, 360)
  TimeNs sweep_ns = 0;     // median firing time of the vehicle's points
  std::size_t points = 0;  // foreground points (all on the vehicle: the scene is empty)
  bool fit_ok = false;
  double lshape_center_err_m = 0;  // NaN when no fit
  double area_err_m2 = 0;          // fitted area - true area
  double lshape_yaw_err_deg = 0;   // longer fitted edge vs the true length axis, mod 180, in [0, 90]
  double alg1_center_err_m = 0;
  double alg1_yaw_err_deg = 0;
  double improved_center_err_m = 0;
  double improved_yaw_err_deg = 0;
  double improved_sigma_m = 0;        // sqrt of the larger eigenvalue of the reported position covariance
  double improved_yaw_sigma_deg = 0;  // sqrt of the reported yaw variance
  double improved_position_nees = 0;  // e^T P^-1 e of the centre error against the reported covariance
  std::string improved_resolution;
};

struct PilotResult {
  PilotConfig config;
  int frames_per_turn = 0;
  std::vector<double> distances;
  std::vector<PilotCell> cells;  // distance-major
  double wall_seconds = 0;
  std::uint64_t rays_cast = 0;
};

PilotResult run_pilot(const PilotConfig& config);

// Summary figures per method, as summary.json holds them.
struct MethodSummary {
  double share_below_0p10_6_36m = 0;  // cells from 6 to 36 m with centre error < 0.10 m (no fit = not)
  int off_by_90_cells = 0;            // yaw error > 45 deg
  double median_error_m = 0;          // over cells with a fit, all distances
  double p95_error_m = 0;
  int no_fit_cells = 0;
};
MethodSummary summarize(const PilotResult& result, const std::string& method);

// Is the improved correction's stated covariance honest? Over the fixed cells: the mean stated sigmas and
// the share of fixes whose error lies beyond the 3-sigma bound (yaw: |error| > 3 sigma; position: the
// 2-dof NEES beyond its 99.73 % quantile, the same tail as 3 sigma in one dimension). An honest model
// has about 0.27 % beyond for a Gaussian error; a much larger share means overconfident fixes, which the
// vehicle's gate and EKF then trust too much.
struct ConsistencySummary {
  int fixes = 0;
  double mean_yaw_sigma_deg = 0;
  double yaw_beyond_3sigma = 0;  // share of fixes
  double mean_position_sigma_m = 0;
  double position_beyond_3sigma = 0;
};
ConsistencySummary summarize_consistency(const PilotResult& result);

void write_cells_csv(const PilotResult& result, const std::string& path, bool append);
std::string summary_json_entry(const PilotResult& result);  // {"lshape": {...}, "algorithm1": ..., ...}

}  // namespace rsu::eval
