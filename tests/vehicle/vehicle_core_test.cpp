// SPDX-License-Identifier: Apache-2.0
// VehicleCore: the vehicle's loop (NDT pose -> corrections -> fuse -> announce) on a simulated straight
// drive, against the test's own truth.
#include "vehicle/vehicle_core.h"

#include <gtest/gtest.h>

#include <cmath>

#include "common/random.h"

namespace rsu::vehicle {
namespace {

constexpr double kSpeed = 8.0;  // m/s along +x
constexpr TimeNs kStart = 20 * kNsPerSecond;
constexpr TimeNs kStep = 100 * kNsPerMs;
constexpr double kNdtSigma = 0.2;
constexpr double kRsuSigma = 0.04;

double truth_x(TimeNs t) {
  return kSpeed * to_seconds(t - kStart);
}

NdtPose ndt_at(int k) {
  const TimeNs t = kStart + k * kStep;
  const NormalPair n = standard_normal_pair(8, 0, static_cast<std::uint64_t>(k));
  return {t,
          {truth_x(t) + kNdtSigma * n.a, kNdtSigma * n.b, 0.0},
          Eigen::Vector3d(kNdtSigma * kNdtSigma, kNdtSigma * kNdtSigma, 0.02 * 0.02).asDiagonal(),
          {}};
}

v2i::Correction fix_at(int k) {
  const TimeNs t = kStart + k * kStep + 40 * kNsPerMs;
  const NormalPair n = standard_normal_pair(8, 1, static_cast<std::uint64_t>(k));
  v2i::Correction c;
  c.rsu_id = 1;
  c.vehicle_id = 1;
  c.sequence = static_cast<std::uint32_t>(k);
  c.sweep_time = t;
  c.pose = {truth_x(t) + kRsuSigma * n.a, kRsuSigma * n.b, kPi};  // a box yaw, backwards
  c.pose_covariance =
      Eigen::Vector3d(kRsuSigma * kRsuSigma, kRsuSigma * kRsuSigma, 0.015 * 0.015).asDiagonal();
  return c;
}

TEST(VehicleCore, FusesCorrectionsAndAnnouncesTheFusedStateWithItsMotionOnceSettled) {
  VehicleCore core;
  double ndt_sq = 0.0, fused_sq = 0.0;
  int counted = 0;
  for (int k = 0; k < 60; ++k) {
    const NdtPose ndt = ndt_at(k);
    const NdtStep step = core.on_ndt(ndt);
    ASSERT_TRUE(step.fused.has_value());
    // The announced state is the fused estimate at the pose's time.
    EXPECT_EQ(step.announce.time, ndt.time);
    EXPECT_DOUBLE_EQ(step.announce.pose.x, step.fused->state(fusion::kX));
    EXPECT_EQ(step.announce.covariance, Eigen::Matrix3d(step.fused->covariance.topLeftCorner<3, 3>()));
    if (k == 0) {
      EXPECT_FALSE(step.announce.speed_mps.has_value());  // the filter has not seen it move yet
      EXPECT_FALSE(step.announce.yaw_rate_rps.has_value());
    }
    if (k >= 30) {
      ASSERT_TRUE(step.announce.speed_mps.has_value());
      EXPECT_NEAR(*step.announce.speed_mps, kSpeed, 0.5);
      ndt_sq += std::pow(ndt.pose.x - truth_x(ndt.time), 2) + ndt.pose.y * ndt.pose.y;
      fused_sq += std::pow(step.fused->state(fusion::kX) - truth_x(ndt.time), 2) +
                  std::pow(step.fused->state(fusion::kY), 2);
      ++counted;
    }
    const CorrectionStep fix = core.on_correction(fix_at(k));
    ASSERT_TRUE(fix.check.has_value());
    if (!fix.check->use()) {
      EXPECT_FALSE(fix.outcome.has_value());
      EXPECT_STREQ(fix.label(), to_string(fix.check->verdict));
      continue;
    }
    ASSERT_TRUE(fix.outcome.has_value());
    if (*fix.outcome == fusion::MeasurementOutcome::kAccepted) {
      ASSERT_TRUE(fix.fused.has_value());
      EXPECT_EQ(fix.fused->time, fix_at(k).sweep_time);
      EXPECT_STREQ(fix.label(), "accepted");
    } else {
      EXPECT_FALSE(fix.fused.has_value());
    }
  }
  EXPECT_LT(std::sqrt(fused_sq / counted), 0.5 * std::sqrt(ndt_sq / counted));
  // The first fixes only prove the RSU consistent (probation); nearly all later ones are fused.
  EXPECT_GE(core.fuser_stats().rsu_accepted, 50U);
  EXPECT_EQ(core.integrity().totals().verdicts.count(FixVerdict::kProbation), 4U);
  // ... and those four are fused, late, once the fifth has admitted the RSU.
  EXPECT_EQ(core.stats().fixes_fused_after_probation, 4U);
}

TEST(VehicleCore, WithoutFusingCorrectionsItIsTheNdtOnlyFilter) {
  VehicleCoreConfig recording;
  recording.fuse_corrections = false;
  VehicleCore core(recording);
  VehicleCore ndt_only;
  for (int k = 0; k < 20; ++k) {
    const NdtStep a = core.on_ndt(ndt_at(k));
    const NdtStep b = ndt_only.on_ndt(ndt_at(k));
    ASSERT_TRUE(a.fused && b.fused);
    EXPECT_EQ(a.fused->state, b.fused->state);
    const CorrectionStep fix = core.on_correction(fix_at(k));
    EXPECT_FALSE(fix.outcome.has_value());
    EXPECT_FALSE(fix.fused.has_value());
    EXPECT_STREQ(fix.label(), "not_fused");
  }
  EXPECT_EQ(core.fuser_stats().rsu_accepted, 0U);
}

TEST(VehicleCore, BeforeAnyNdtPoseNothingIsFusedAndTheNdtPoseItselfIsAnnounced) {
  VehicleCore core;
  const CorrectionStep early = core.on_correction(fix_at(0));
  ASSERT_TRUE(early.outcome.has_value());
  EXPECT_EQ(*early.outcome, fusion::MeasurementOutcome::kRejectedNotInitialized);
  EXPECT_FALSE(core.pose_at(kStart).has_value());
  const NdtPose ndt = ndt_at(0);
  const NdtStep step = core.on_ndt(ndt);
  ASSERT_TRUE(step.fused.has_value());
  EXPECT_DOUBLE_EQ(step.announce.pose.x, ndt.pose.x);  // the filter starts at the first pose
  EXPECT_DOUBLE_EQ(step.announce.pose.y, ndt.pose.y);
}

}  // namespace
}  // namespace rsu::vehicle
