// SPDX-License-Identifier: Apache-2.0
// The pilot experiment at a few distances: the paper's claims hold (Algorithm 1 mostly under 0.1 m,
// off-by-90 deg spots in the raw fit) and the improved correction removes the off-by-90 deg errors.
#include <gtest/gtest.h>

#include <cmath>

#include "eval/pilot/pilot_experiment.h"
#include "eval/pilot/pilot_summary.h"

namespace rsu::eval {
namespace {

PilotResult short_pilot(const std::string& model) {
  PilotConfig config;
  config.model_name = model;
  config.distance_min_m = 10.0;
  config.distance_max_m = 20.0;
  config.distance_step_m = 5.0;  // 10, 15, 20 m: one full turn each
  config.threads = 1;
  return run_pilot(config);
}

TEST(Pilot, Vlp16ReproducesThePaperAndTheImprovedCorrectionRemovesOffBy90) {
  const PilotResult result = short_pilot("vlp16");
  ASSERT_EQ(result.frames_per_turn, 180);  // 20 deg/s at 10 Hz: 2 deg per frame
  ASSERT_EQ(result.cells.size(), 3u * 180u);

  const MethodSummary lshape = summarize(result, PilotMethod::lshape);
  const MethodSummary alg1 = summarize(result, PilotMethod::algorithm1);
  const MethodSummary improved = summarize(result, PilotMethod::improved);
  // Paper Sec. 3.1: the raw box centre is off by about half a vehicle; the yaw is off by 90 deg where only
  // the front or back was seen.
  EXPECT_LT(lshape.share_below_0p10_6_36m, 0.2);
  EXPECT_GT(lshape.off_by_90_cells, 0);
  // Paper Sec. 3.2: after Algorithm 1, most cells are under 0.1 m, but the off-by-90 deg cells remain.
  EXPECT_GT(alg1.share_below_0p10_6_36m, 0.85);
  EXPECT_EQ(alg1.off_by_90_cells, lshape.off_by_90_cells);
  // The improved correction, with a yaw prior within +-10 deg: no off-by-90 deg, almost every cell < 0.1 m.
  EXPECT_EQ(improved.off_by_90_cells, 0);
  EXPECT_GE(improved.share_below_0p10_6_36m, 0.97);
  EXPECT_LT(improved.median_error_m, alg1.median_error_m);
  EXPECT_EQ(improved.no_fit_cells, 0);
  // 2 m up the sides and ends show in most frames (outline_observability.h), and there the fix is right.
  EXPECT_GT(improved.outline_seen_6_36m_30pts, 0.8);
  EXPECT_GE(improved.share_below_0p10_outline_seen, 0.97);
}

// 8 m up, a VLP-32C's rings cross the car's roof and glasshouse in most frames: the oracle finds the
// footprint's outline in under two thirds of them (the matrix: 26.8-38.0 % over 6-36 m); where it is
// missing, a fix told only the size places the box to 0.10 m only by luck.
TEST(Pilot, FromAMastTheOutlineIsOftenUnseen) {
  PilotConfig config;
  config.model_name = "vlp32c";
  config.lidar_height_m = 8.0;
  config.distance_min_m = 14.0;
  config.distance_max_m = 22.0;
  config.distance_step_m = 4.0;  // 14, 18, 22 m
  config.threads = 1;
  const PilotResult result = run_pilot(config);
  const MethodSummary improved = summarize(result, PilotMethod::improved);
  ASSERT_GT(improved.cells_6_36m_30pts, 100);
  EXPECT_LT(improved.outline_seen_6_36m_30pts, 0.67);
  EXPECT_GT(improved.outline_seen_6_36m_30pts, 0.0);  // the oracle does mark some cells
}

TEST(Pilot, PointCountFallsWithDistance) {
  const PilotResult result = short_pilot("vlp32c");
  double mean_points[3] = {0, 0, 0};
  for (const PilotCell& c : result.cells) {
    mean_points[static_cast<int>(std::lround((c.distance_m - 10.0) / 5.0))] +=
        static_cast<double>(c.points) / 180.0;
  }
  EXPECT_GT(mean_points[0], mean_points[1]);
  EXPECT_GT(mean_points[1], mean_points[2]);
  // A VLP-32C sees hundreds of points on a car at 10 m (32 rings, 0.2 deg steps).
  EXPECT_GT(mean_points[0], 300.0);
}

TEST(Pilot, SameSeedSameResult) {
  PilotConfig config;
  config.distance_min_m = config.distance_max_m = 12.0;
  config.threads = 2;
  const PilotResult a = run_pilot(config);
  config.threads = 1;
  const PilotResult b = run_pilot(config);
  ASSERT_EQ(a.cells.size(), b.cells.size());
  for (std::size_t i = 0; i < a.cells.size(); ++i) {
    EXPECT_EQ(a.cells[i].points, b.cells[i].points);
    EXPECT_EQ(a.cells[i].improved().center_err_m, b.cells[i].improved().center_err_m);
  }
}

TEST(Pilot, RejectsBadConfiguration) {
  PilotConfig config;
  config.model_name = "hdl64";
  EXPECT_THROW(run_pilot(config), std::invalid_argument);
  config.model_name = "vlp16";
  config.distance_step_m = 0.0;
  EXPECT_THROW(run_pilot(config), std::invalid_argument);
}

}  // namespace
}  // namespace rsu::eval
