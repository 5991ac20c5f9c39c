// SPDX-License-Identifier: Apache-2.0
// Is the RSU's stated fix covariance honest? The pilot experiment (the Embree simulator's car, not a box,
// spinning through every aspect) over the paper's range of claims, 6 m to 36 m (Sec. 3.2), scored against
// the simulator's ground truth: the share of improved-correction fixes whose yaw error lies beyond 3 stated
// sigma, and whose position error lies beyond the 2-dof 3-sigma bound (NEES). For a Gaussian error 0.27 %
// would be; an overconfident model (the handover's 3.7 deg yaw error under a stated 0.78 deg) shows as a
// share of several percent. The stated yaw sigma must stay near the real error too: an inflated model
// would pass the tail test trivially.
#include <gtest/gtest.h>

#include <cmath>

#include "eval/pilot/pilot_experiment.h"
#include "eval/pilot/pilot_summary.h"

namespace rsu::eval {
namespace {

PilotResult consistency_run(const std::string& model) {
  PilotConfig config;
  config.model_name = model;
  config.distance_min_m = 6.0;
  config.distance_max_m = 36.0;
  config.distance_step_m = 1.0;
  config.spin_rate_deg_s = 60.0;  // 6 deg per frame: 60 aspects per distance keeps the test short
  config.threads = 2;
  return run_pilot(config);
}

double rms_yaw_error_deg(const PilotResult& result) {
  double sum_sq = 0.0;
  int n = 0;
  for (const PilotCell& c : result.cells) {
    if (std::isfinite(c.improved().yaw_err_deg) && std::isfinite(c.improved().yaw_sigma_deg)) {
      sum_sq += c.improved().yaw_err_deg * c.improved().yaw_err_deg;
      ++n;
    }
  }
  return n > 0 ? std::sqrt(sum_sq / n) : 0.0;
}

// Yaw over 6-36 m. Position over 6-33 m: beyond 33 m a VLP-16 sees the car with one ring at window height,
// the cabin's outline without hood and boot, and the size correction from that corner is off by up to a
// metre: a failure of the fix, not of its covariance, which needs the points' heights to detect (a known
// shortfall; rsud's coverage radius keeps such fixes out).
void expect_honest(const std::string& model) {
  const PilotResult result = consistency_run(model);
  const ConsistencySummary k = summarize_consistency(result);
  const ConsistencySummary near = summarize_consistency(up_to(result, 33.0));
  const double rms = rms_yaw_error_deg(result);
  ::testing::Test::RecordProperty("fixes", k.fixes);
  ::testing::Test::RecordProperty("yaw_beyond_3sigma", std::to_string(k.yaw_beyond_3sigma));
  ::testing::Test::RecordProperty("mean_yaw_sigma_deg", std::to_string(k.mean_yaw_sigma_deg));
  ::testing::Test::RecordProperty("position_beyond_3sigma", std::to_string(k.position_beyond_3sigma));
  ::testing::Test::RecordProperty("position_beyond_3sigma_6_33m",
                                  std::to_string(near.position_beyond_3sigma));
  ::testing::Test::RecordProperty("mean_position_sigma_m", std::to_string(k.mean_position_sigma_m));
  // rsud's configuration withholds fixes whose box the points do not decide (about 2 % of the VLP-16's
  // cells here; the target is at most 5 %); before the pilot measured rsud's configuration, 99 % were fixed.
  ASSERT_GE(k.fixes, static_cast<int>(0.97 * 31 * 60));
  EXPECT_LE(k.yaw_beyond_3sigma, 0.01)
      << model << ": mean stated yaw sigma " << k.mean_yaw_sigma_deg << " deg, rms error " << rms << " deg";
  // Honest, not inflated: the stated sigma is of the size of the real error, not many times it.
  EXPECT_LT(k.mean_yaw_sigma_deg, 4.0 * rms) << model;
  EXPECT_LE(near.position_beyond_3sigma, 0.01)
      << model << ": mean stated sigma " << near.mean_position_sigma_m;
  EXPECT_LT(near.mean_position_sigma_m, 0.1) << model;  // still a fix of a few cm, not inflated
}

TEST(FixConsistency, Vlp16CovarianceIsHonestFrom6To36m) {
  expect_honest("vlp16");
}

TEST(FixConsistency, Vlp32cCovarianceIsHonestFrom6To36m) {
  expect_honest("vlp32c");
}

}  // namespace
}  // namespace rsu::eval
