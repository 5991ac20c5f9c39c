// SPDX-License-Identifier: Apache-2.0
// Scores the realistic experiment against the scenario's truth and writes the paper's table (Table 2:
// mean absolute error for +-36 m and +-50 m along the road) with RMSE, 95th percentile, maximum and the
// share of estimates beyond 3 sigma of their own stated covariance, the same MAE beside the paper's,
// how the fused pose compares with NDT and the RSU alone, every frame's error (frames.csv) and
// summary.json.
#pragma once

#include <limits>
#include <map>
#include <string>
#include <vector>

#include "eval/corridor/experiment_config.h"

namespace rsu::eval {

// One estimate to score: when, where, and where the vehicle truly was then.
struct ScoredEstimate {
  TimeNs time_ns = 0;
  double along_road_m = 0;   // true x relative to the RSU LiDAR
  double error_m = 0;        // planar position error
  double yaw_error_deg = 0;  // mod 180 for RSU fixes (a box has no front)
  double position_nees = 0;  // against the estimate's own stated covariance (eval/consistency.h)
  // RSU fixes: how far the nearest OTHER vehicle of the scenario truly was (NaN: no other vehicle).
  double nearest_other_m = std::numeric_limits<double>::quiet_NaN();
};

struct ErrorStats {
  std::size_t count = 0;
  double mae_m = 0, rmse_m = 0, p95_m = 0, max_m = 0;
  double beyond_3sigma = 0;  // share of the estimates with a position NEES beyond the 3-sigma bound
};

// Traffic (issue 13 item 3), per RSU model: the corrections rsud sent to the connected vehicles, and how
// many went to the WRONG vehicle: addressed to one vehicle (or naming another) but nearer another
// vehicle's true position at the sweep time (any vehicle of the scenario, connected or not); HMI: beyond
// 3 sigma of the stated covariance and more than 0.30 m off the vehicle's own truth.
struct TrafficScores {
  std::size_t vehicle_corrections = 0, vehicle_wrong = 0, vehicle_hmi = 0;  // the experiment's vehicle
  std::size_t fleet_corrections = 0, fleet_wrong = 0, fleet_hmi = 0;        // the other connected vehicles
  ErrorStats fleet_pm50;  // the other connected vehicles' corrections within +-50 m (own vehicle's truth)
};

struct ExperimentScores {
  // method ("ndt", "rsu_vlp16", "fused_vlp16", ...) -> estimates
  std::map<std::string, std::vector<ScoredEstimate>> estimates;
  // method -> range ("pm36", "pm50") -> stats
  std::map<std::string, std::map<std::string, ErrorStats>> stats;
  // NDT frames in each range, for the RSU's coverage (how many got a fix)
  std::map<std::string, std::size_t> frames_in_range;
  // RSU model -> traffic scores; only for a scenario with more than one vehicle
  std::map<std::string, TrafficScores> traffic;
};

// How the fused pose of one RSU model compares in one range with NDT alone and with that RSU, frame for
// frame (issue 13's goals: "at least 80 % lower than NDT's within the RSU's coverage, and never worse than
// the better of NDT and RSU in any range cell"). A frame is one of the vehicle's NDT poses (10 Hz), where
// the fused pose is scored. It is within the RSU's coverage when the RSU swept the vehicle in the frame
// period ending at it (after the previous frame, not after this one) and sent a fix of that sweep: the
// newest fix the fused pose of that frame could rest on. On those frames the fused pose, NDT and the
// RSU's fix (its error at its own sweep time) are compared on the same frames; on the range's frames
// without a fix (beyond the RSU's last fix, a fix refused or lost) the fused pose is compared with NDT
// alone, the only other estimate there. The unpaired MAE of the table (the fused pose over every frame,
// the RSU over its fixes) compare different frames and are not the goals' measure.
struct FusedGoals {
  std::string rsu_model, range;
  std::size_t covered_frames = 0, uncovered_frames = 0;
  // MAE over the covered frames
  double fused_mae_m = 0, ndt_mae_m = 0, rsu_mae_m = 0;
  double best_mae_m = 0;        // the better of NDT's and the RSU's (NDT's if the RSU had no fix)
  double reduction_vs_ndt = 0;  // 1 - fused / NDT
  // MAE over the frames without a fix (0 when there are none)
  double fused_uncovered_mae_m = 0, ndt_uncovered_mae_m = 0;
  // Every frame of the range: 1 - fused / NDT; and the fused MAE against the better one's, frame for frame
  // (on the frames with a fix the better of NDT and the RSU, i.e. best_mae_m; on those without, NDT).
  double reduction_vs_ndt_all_frames = 0;
  double fused_all_mae_m = 0, better_all_mae_m = 0;

  // The goals, compared to the millimetre as the table prints them (live runs differ in the fourth
  // decimal): at least 80 % below NDT within the coverage (met when there is none); over the range's
  // frames no worse than the better of NDT and the RSU. The parts, for the reader: no worse on the frames
  // with a fix, no worse than NDT on those without.
  bool below_ndt_met() const;
  bool no_worse_met() const;
  bool covered_no_worse() const;
  bool uncovered_no_worse() const;
};
std::vector<FusedGoals> fused_goals(const ExperimentScores& scores,
                                    const std::vector<std::string>& rsu_models);

// Reads <dir>/ndt.csv and, per RSU model m, <dir>/corrections_<m>.csv and <dir>/fused_<m>.csv (columns
// named in their header rows; time_ns, x, y, yaw required), and with traffic <dir>/fleet_<m>.corrections
// (rsu-fleet's correction lines). Missing files are reported as errors.
ExperimentScores score_experiment(const CorridorExperimentConfig& config, const std::string& dir);

// Statistics of the errors; nees (empty, or one per error) gives beyond_3sigma.
ErrorStats error_stats(const std::vector<double>& errors, const std::vector<double>& nees = {});

// The table as text, and summary.json.
std::string format_table(const ExperimentScores& scores, const std::vector<std::string>& methods);
// The MAE beside the paper's Table 2, and for each RSU model whether the fused pose meets the goals: at
// least 80 % below NDT's error, and no worse than the better of NDT and that RSU, in each range.
std::string format_paper_comparison(const ExperimentScores& scores,
                                    const std::vector<std::string>& rsu_models);
std::string summary_json(const ExperimentScores& scores, const std::vector<std::string>& methods);
void write_frames_csv(const ExperimentScores& scores, const std::string& path);

}  // namespace rsu::eval
