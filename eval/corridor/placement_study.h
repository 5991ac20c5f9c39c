// SPDX-License-Identifier: Apache-2.0
// Where to put the RSU's LiDAR (the paper's third open item, Sec. 5; issue 13 item 4): mount height x
// lateral position x LiDAR model in a street with traffic (scenarios/corridor_degraded_traffic.yaml).
//
// Each placement runs the fix rsud runs for each vehicle (perception::fix_vehicle, with rsud's
// configuration: the library defaults, which deploy/rsud.yaml keeps) over every simulated rotation of the
// drive, for every vehicle of the scenario as if it were connected (it announces its true size and a
// yaw prior off by up to +-10 deg, as in the pilot). It does NOT run rsud's segmentation and association:
// a vehicle's points are the returns the simulator says hit it (perfect segmentation), and the other
// vehicles' returns and the static objects' (lamp posts, hedges) are passed as occluders (rsud passes the
// sweep's other detections and the background's returns above the road, core/sweep_occluders.h). So it
// measures the fix at each placement, with the occlusion traffic causes; wrong-vehicle corrections need the
// live run (run_experiment.py with the traffic experiment). This is what makes 36 placements fit in minutes
// on two cores.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "sim/scenario.h"

namespace rsu::eval {

struct PlacementStudyConfig {
  std::vector<double> heights_m = {2.0, 4.0, 6.0, 8.0};
  // Lateral positions (name, map y of the mount); the mount's x is the scenario's.
  std::vector<std::pair<std::string, double>> laterals = {{"curb", -8.5}, {"median", 0.0}, {"across", 8.5}};
  std::vector<std::string> models = {"vlp16", "vlp32c", "generic128"};
  double duration_s = 10.8;
  int rotation_stride = 1;         // every n-th rotation is scored (1: all)
  double coverage_radius_m = 50;   // rsud's perception.coverage_radius_m
  double coverage_bin_m = 2.0;     // the road is scored in bins of this length along it
  double bin_covered_share = 0.8;  // a bin is covered when this share of its vehicle-rotations got a fix
                                   // under accurate_m
  double accurate_m = 0.10;
  double hmi_m = 0.30;            // HMI: beyond 3 sigma of the stated covariance and more than this off
  double prior_error_deg = 10.0;  // the announced yaw's error bound (uniform), as the pilot's
  std::uint64_t seed = 11;
  int threads = 2;
};

// One vehicle in one rotation, within the coverage radius.
struct PlacementSample {
  std::uint32_t vehicle_id = 0;
  double along_road_m = 0;  // true x relative to the mount
  double lane_y_m = 0;
  std::size_t points = 0;
  bool occluded = false;  // other vehicles' returns lie nearer the LiDAR within its azimuth span
  bool fixed = false;
  double error_m = 0, nees = 0;  // when fixed
  std::string status;            // "ok" or why no fix (perception::CorrectionStatus)
};

struct PlacementResult {
  std::string model, lateral;
  double height_m = 0, mount_y_m = 0;
  std::vector<PlacementSample> samples;
  // Summaries over the samples
  std::size_t vehicle_rotations = 0, fixes = 0, accurate = 0, hmi = 0, beyond_3sigma = 0;
  std::size_t occluded = 0, occlusion_losses = 0;  // occluded samples; of them without a fix under accurate_m
  double mae_m = 0, p95_m = 0;                     // over the fixes
  double coverage_m = 0;                           // metres of road in covered bins
  double seconds = 0;                              // wall time of this placement
  std::vector<double> bin_share;                   // per bin: share fixed under accurate_m (NaN: no sample)
};

std::vector<PlacementResult> run_placement_study(const sim::Scenario& scenario,
                                                 const PlacementStudyConfig& config);

// Every placement as a CSV row, every vehicle-rotation of every placement as a CSV row, the table
// (Markdown) and summary.json.
std::string placement_csv(const std::vector<PlacementResult>& results);
std::string placement_samples_csv(const std::vector<PlacementResult>& results);
std::string placement_table(const std::vector<PlacementResult>& results, const PlacementStudyConfig& config);
std::string placement_json(const std::vector<PlacementResult>& results, const PlacementStudyConfig& config,
                           const std::string& scenario_source);

}  // namespace rsu::eval
