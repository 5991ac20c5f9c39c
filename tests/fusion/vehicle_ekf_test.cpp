// SPDX-License-Identifier: Apache-2.0
#include "fusion/vehicle_ekf.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <map>
#include <vector>

#include "common/angles.h"
#include "common/random.h"
#include "fusion/measurement_model.h"

namespace rsu::fusion {
namespace {

// A car driving straight at 10 m/s, heading 0.3 rad, its reference point (rear axle) 1.35 m behind
// the footprint box centre.
constexpr double kHeading = 0.3;
constexpr double kTruthSpeed = 10.0;
const Eigen::Vector2d kOffset(-1.35, 0.0);
constexpr TimeNs kStart = 1000 * kNsPerSecond;

Eigen::Vector2d truth_reference(TimeNs t) {
  const double s = to_seconds(t - kStart);
  return {5.0 + kTruthSpeed * s * std::cos(kHeading), -3.0 + kTruthSpeed * s * std::sin(kHeading)};
}

Eigen::Vector2d truth_centre(TimeNs t) {
  return truth_reference(t) -
         Eigen::Vector2d(std::cos(kHeading) * kOffset.x() - std::sin(kHeading) * kOffset.y(),
                         std::sin(kHeading) * kOffset.x() + std::cos(kHeading) * kOffset.y());
}

PoseMeasurement ndt_at(TimeNs t, std::uint64_t index, double sigma = 0.2) {
  const auto n = standard_normal_pair(11, 1, index);
  const auto m = standard_normal_pair(11, 2, index);
  PoseMeasurement out;
  out.time = t;
  out.source = MeasurementSource::kNdt;
  const Eigen::Vector2d p = truth_reference(t);
  out.pose = {p.x() + sigma * n.a, p.y() + sigma * n.b, wrap_angle(kHeading + 0.02 * m.a)};
  out.covariance = Eigen::Vector3d(sigma * sigma, sigma * sigma, 0.02 * 0.02).asDiagonal();
  return out;
}

// An RSU fix of the box centre; half of them report the box yaw pointing backwards (modulo pi).
PoseMeasurement rsu_at(TimeNs t, std::uint64_t index, double sigma = 0.05) {
  const auto n = standard_normal_pair(22, 1, index);
  const auto m = standard_normal_pair(22, 2, index);
  PoseMeasurement out;
  out.time = t;
  out.source = MeasurementSource::kRsu;
  const Eigen::Vector2d c = truth_centre(t);
  const double flip = index % 2 == 0 ? 0.0 : kPi;
  out.pose = {c.x() + sigma * n.a, c.y() + sigma * n.b, wrap_angle(kHeading + flip + 0.01 * m.a)};
  out.covariance = Eigen::Vector3d(sigma * sigma, sigma * sigma, 0.01 * 0.01).asDiagonal();
  return out;
}

VehicleEkfConfig config_with_offset() {
  VehicleEkfConfig c;
  c.reference_offset = kOffset;
  return c;
}

// The interleaved stream: NDT at k * 100 ms, RSU at k * 100 ms + 50 ms.
std::vector<PoseMeasurement> drive(int ticks, bool with_rsu) {
  std::vector<PoseMeasurement> out;
  for (int k = 0; k < ticks; ++k) {
    const TimeNs t = kStart + k * 100 * kNsPerMs;
    out.push_back(ndt_at(t, static_cast<std::uint64_t>(k)));
    if (with_rsu) {
      out.push_back(rsu_at(t + 50 * kNsPerMs, static_cast<std::uint64_t>(k)));
    }
  }
  return out;
}

double position_error(const VehicleEkf& ekf, TimeNs t) {
  const auto e = ekf.estimate_at(t);
  return (Eigen::Vector2d(e->state(kX), e->state(kY)) - truth_reference(t)).norm();
}

TEST(VehicleEkf, RsuFixesBeatNdtAlone) {
  VehicleEkf ndt_only(config_with_offset());
  VehicleEkf fused(config_with_offset());
  // Errors against the true trajectory at each NDT time, right after that pose is fused, after a 2 s
  // settling period.
  double raw_ndt_sq = 0.0;
  double raw_rsu_sq = 0.0;
  double ndt_ekf_sq = 0.0;
  double fused_sq = 0.0;
  int n = 0;
  for (int k = 0; k < 100; ++k) {
    const TimeNs t = kStart + k * 100 * kNsPerMs;
    const PoseMeasurement ndt = ndt_at(t, static_cast<std::uint64_t>(k));
    const PoseMeasurement rsu = rsu_at(t - 50 * kNsPerMs, static_cast<std::uint64_t>(k));
    ndt_only.add(ndt);
    if (k > 0) {
      fused.add(rsu);
    }
    fused.add(ndt);
    if (k < 20) {
      continue;
    }
    raw_ndt_sq += (Eigen::Vector2d(ndt.pose.x, ndt.pose.y) - truth_reference(t)).squaredNorm();
    raw_rsu_sq += (Eigen::Vector2d(rsu.pose.x, rsu.pose.y) - truth_centre(rsu.time)).squaredNorm();
    ndt_ekf_sq += std::pow(position_error(ndt_only, t), 2);
    fused_sq += std::pow(position_error(fused, t), 2);
    ++n;
  }
  ASSERT_EQ(n, 80);
  const double raw_ndt = std::sqrt(raw_ndt_sq / n);
  const double raw_rsu = std::sqrt(raw_rsu_sq / n);
  const double ndt_ekf = std::sqrt(ndt_ekf_sq / n);
  const double fused_rmse = std::sqrt(fused_sq / n);
  EXPECT_LT(fused_rmse, 0.5 * raw_ndt) << "fused " << fused_rmse << " raw NDT " << raw_ndt;
  EXPECT_LT(fused_rmse, ndt_ekf) << "fused " << fused_rmse << " NDT-only EKF " << ndt_ekf;
  EXPECT_LT(fused_rmse, raw_rsu) << "fused " << fused_rmse << " raw RSU " << raw_rsu;
  // Honest data is almost never gated out (99.9 % gate), whichever way the RSU box pointed.
  EXPECT_LE(fused.stats().rejected(), 2U);
  EXPECT_GE(fused.stats().count(MeasurementOutcome::kAccepted), 196U);
  // Speed and heading were learned from positions alone.
  EXPECT_NEAR(fused.latest()->state(kSpeed), kTruthSpeed, 0.3);
  EXPECT_NEAR(angle_distance(fused.latest()->state(kYaw), kHeading), 0.0, 0.02);
}

TEST(VehicleEkf, LateRsuFixGivesTheInOrderResult) {
  const std::vector<PoseMeasurement> stream = drive(40, true);
  VehicleEkf in_order(config_with_offset());
  for (const auto& m : stream) {
    in_order.add(m);
  }
  // Deliver the RSU fix swept at 2.05 s after the NDT pose of 2.3 s.
  const TimeNs late_time = kStart + 2050 * kNsPerMs;
  const TimeNs delivered_after = kStart + 2300 * kNsPerMs;
  VehicleEkf late(config_with_offset());
  PoseMeasurement held;
  int overtaken = 0;
  for (const auto& m : stream) {
    if (m.time == late_time) {
      held = m;
      continue;
    }
    late.add(m);
    overtaken += m.time > late_time && m.time <= delivered_after ? 1 : 0;
    if (m.time == delivered_after) {
      EXPECT_EQ(late.add(held), MeasurementOutcome::kAccepted);
    }
  }
  ASSERT_EQ(overtaken, 5);  // NDT 2.1, 2.2, 2.3 and RSU 2.15, 2.25
  EXPECT_EQ(late.stats().late, 1U);
  EXPECT_EQ(late.stats().reapplied, 5U);
  const auto a = in_order.latest();
  const auto b = late.latest();
  ASSERT_TRUE(a && b);
  EXPECT_EQ(a->time, b->time);
  EXPECT_NEAR((a->state - b->state).cwiseAbs().maxCoeff(), 0.0, 1e-9);
  EXPECT_NEAR((a->covariance - b->covariance).cwiseAbs().maxCoeff(), 0.0, 1e-12);
  EXPECT_EQ(a->time, b->time);
  EXPECT_EQ(in_order.stats().accepted(), late.stats().accepted());
}

// NDT poses fused at one covariance and given another afterwards (reweigh_ndt) leave the filter where
// the stream with those covariances in the first place takes it.
TEST(VehicleEkf, ReweighedNdtPosesGiveTheResultOfTheirNewCovariances) {
  const std::vector<PoseMeasurement> stream = drive(30, true);
  const Eigen::Matrix3d weak = Eigen::Vector3d(0.9 * 0.9, 0.2 * 0.2, 0.02 * 0.02).asDiagonal();
  const auto reweighed = [&](const PoseMeasurement& m) {
    return m.source == MeasurementSource::kNdt && m.time >= kStart + 1500 * kNsPerMs &&
           m.time <= kStart + 2200 * kNsPerMs;
  };
  VehicleEkf direct(config_with_offset());
  VehicleEkf afterwards(config_with_offset());
  std::map<TimeNs, Eigen::Matrix3d> covariances;
  for (const auto& m : stream) {
    PoseMeasurement weakened = m;
    if (reweighed(m)) {
      weakened.covariance = weak;
      covariances[m.time] = weak;
    }
    direct.add(weakened);
    afterwards.add(m);
  }
  const auto before = afterwards.latest();
  // An RSU time and an unknown time are ignored; the eight poses from 1.5 s to 2.2 s change.
  covariances[kStart + 1550 * kNsPerMs] = weak;
  covariances[kStart + 1234 * kNsPerMs] = weak;
  EXPECT_EQ(afterwards.reweigh_ndt(covariances), 8U);
  const auto a = direct.latest();
  const auto b = afterwards.latest();
  ASSERT_TRUE(a && b && before);
  EXPECT_GT((before->covariance - b->covariance).cwiseAbs().maxCoeff(), 1e-6);  // it did change
  EXPECT_NEAR((a->state - b->state).cwiseAbs().maxCoeff(), 0.0, 1e-9);
  EXPECT_NEAR((a->covariance - b->covariance).cwiseAbs().maxCoeff(), 0.0, 1e-12);
  EXPECT_EQ(afterwards.reweigh_ndt(covariances), 0U);  // already so
}

TEST(VehicleEkf, MeasurementOlderThanTheHistoryIsRefused) {
  VehicleEkfConfig config = config_with_offset();
  config.history_window = 1 * kNsPerSecond;
  VehicleEkf ekf(config);
  for (const auto& m : drive(30, false)) {  // 0 .. 2.9 s
    ekf.add(m);
  }
  const auto before = ekf.latest();
  EXPECT_EQ(ekf.add(rsu_at(kStart + 1500 * kNsPerMs, 15)), MeasurementOutcome::kRejectedTooOld);
  EXPECT_EQ(ekf.stats().count(MeasurementOutcome::kRejectedTooOld), 1U);
  EXPECT_EQ(ekf.latest()->state, before->state);
  // Inside the window it is taken.
  EXPECT_EQ(ekf.add(rsu_at(kStart + 2450 * kNsPerMs, 24)), MeasurementOutcome::kAccepted);
}

TEST(VehicleEkf, OffBy90DegreeFixIsRejectedAndThePoseDoesNotMove) {
  VehicleEkf ekf(config_with_offset());
  for (const auto& m : drive(30, true)) {
    ekf.add(m);
  }
  const TimeNs t = kStart + 3 * kNsPerSecond;
  const TimeNs query = t + 200 * kNsPerMs;
  const auto before_latest = ekf.latest();
  const auto before_query = ekf.estimate_at(query);
  // The box centre is right but the yaw is the short edge's: off by 90 degrees. Even a fix that claims
  // a very uncertain yaw (which a chi-square gate alone would let in) must not move the pose.
  for (const double yaw_sigma : {0.01, 1.0}) {
    PoseMeasurement bad = rsu_at(t, 30);
    bad.pose.yaw = wrap_angle(kHeading + kPi / 2.0);
    bad.covariance(2, 2) = yaw_sigma * yaw_sigma;
    EXPECT_EQ(ekf.add(bad), MeasurementOutcome::kRejectedYawBranch);
  }
  EXPECT_EQ(ekf.stats().count(MeasurementOutcome::kRejectedYawBranch), 2U);
  const auto after_latest = ekf.latest();
  const auto after_query = ekf.estimate_at(query);
  EXPECT_EQ(after_latest->state, before_latest->state);
  EXPECT_EQ(after_latest->covariance, before_latest->covariance);
  EXPECT_EQ(after_query->state, before_query->state);

  // A box whose centre is 2 m off (its size correction went the wrong way) fails the chi-square gate.
  PoseMeasurement shifted = rsu_at(t + 10 * kNsPerMs, 31);
  shifted.pose.x += 2.0;
  EXPECT_EQ(ekf.add(shifted), MeasurementOutcome::kRejectedGate);
  EXPECT_EQ(ekf.estimate_at(query)->state, before_query->state);
}

StateEstimate still_at(double yaw, double yaw_sigma) {
  StateEstimate s;
  s.time = kStart;
  s.state << 0.0, 0.0, yaw, 0.0, 0.0;
  s.covariance = Eigen::Matrix<double, 5, 1>(0.01, 0.01, yaw_sigma * yaw_sigma, 0.01, 0.001).asDiagonal();
  return s;
}

PoseMeasurement pose_fix(MeasurementSource source, double x, double y, double yaw, double yaw_sigma) {
  PoseMeasurement m;
  m.time = kStart + 10 * kNsPerMs;
  m.source = source;
  m.pose = {x, y, yaw};
  m.covariance = Eigen::Vector3d(0.01, 0.01, yaw_sigma * yaw_sigma).asDiagonal();
  return m;
}

TEST(VehicleEkf, RsuYawTakesTheBranchNearestTheEstimate) {
  // Estimate 0.10 rad; the RSU box says 0.14 rad but pointing backwards (0.14 - pi). The fused yaw
  // moves towards 0.14 and stays near it instead of being dragged towards pi.
  VehicleEkf ekf;
  ekf.initialize(still_at(0.10, 0.05));
  EXPECT_EQ(ekf.add(pose_fix(MeasurementSource::kRsu, 0.0, 0.0, wrap_angle(0.14 - kPi), 0.01)),
            MeasurementOutcome::kAccepted);
  const double yaw = ekf.latest()->state(kYaw);
  EXPECT_GT(yaw, 0.12);
  EXPECT_LT(yaw, 0.14 + 1e-9);

  // An NDT heading is a full heading: the same backwards value is a gross error and is gated out.
  VehicleEkf ndt;
  ndt.initialize(still_at(0.10, 0.05));
  EXPECT_EQ(ndt.add(pose_fix(MeasurementSource::kNdt, 0.0, 0.0, wrap_angle(0.14 - kPi), 0.01)),
            MeasurementOutcome::kRejectedGate);
}

TEST(VehicleEkf, YawUpdatesWrapAcrossPi) {
  // Estimate pi - 0.02; the truth is pi + 0.01 (just across the wrap, i.e. -pi + 0.01).
  const double truth = wrap_angle(kPi + 0.01);
  for (const auto source : {MeasurementSource::kNdt, MeasurementSource::kRsu}) {
    VehicleEkf ekf;
    ekf.initialize(still_at(kPi - 0.02, 0.05));
    // The RSU reports the box yaw in its other branch, near 0.01.
    const double measured = source == MeasurementSource::kRsu ? 0.01 : truth;
    EXPECT_EQ(ekf.add(pose_fix(source, 0.0, 0.0, measured, 0.005)), MeasurementOutcome::kAccepted);
    const double yaw = ekf.latest()->state(kYaw);
    EXPECT_LT(angle_distance(yaw, truth), 0.01);
    EXPECT_GT(std::abs(yaw), 3.0);  // still pointing west, not flipped
    EXPECT_LE(std::abs(yaw), kPi);
  }
}

TEST(VehicleEkf, RsuCorrectionIsMappedThroughTheReferenceOffset) {
  // Rear axle at the origin facing +x; the box centre is 1.35 m ahead of it.
  VehicleEkfConfig config;
  config.reference_offset = kOffset;
  VehicleEkf consistent(config);
  consistent.initialize(still_at(0.0, 0.01));
  EXPECT_EQ(consistent.add(pose_fix(MeasurementSource::kRsu, 1.35, 0.0, 0.0, 0.01)),
            MeasurementOutcome::kAccepted);
  EXPECT_NEAR(consistent.latest()->state(kX), 0.0, 1e-9);
  EXPECT_NEAR(consistent.latest()->state(kY), 0.0, 1e-9);
  // Without the offset the same fix would drag the rear axle forward.
  VehicleEkf naive;
  naive.initialize(still_at(0.0, 0.01));
  naive.add(pose_fix(MeasurementSource::kRsu, 0.3, 0.0, 0.0, 0.01));
  EXPECT_GT(naive.latest()->state(kX), 0.1);
}

TEST(VehicleEkf, BadMeasurementsAreCountedNotFused) {
  VehicleEkf ekf;
  // An RSU box cannot start the filter: its yaw is ambiguous.
  EXPECT_EQ(ekf.add(pose_fix(MeasurementSource::kRsu, 0, 0, 0, 0.01)),
            MeasurementOutcome::kRejectedNotInitialized);
  EXPECT_FALSE(ekf.estimate_at(kStart).has_value());
  EXPECT_EQ(ekf.add(pose_fix(MeasurementSource::kNdt, 1, 2, 0.5, 0.01)), MeasurementOutcome::kInitialized);
  EXPECT_NEAR(ekf.latest()->state(kX), 1.0, 1e-12);

  PoseMeasurement nan_pose =
      pose_fix(MeasurementSource::kNdt, std::numeric_limits<double>::quiet_NaN(), 0, 0, 0.01);
  EXPECT_EQ(ekf.add(nan_pose), MeasurementOutcome::kRejectedInvalid);
  PoseMeasurement indefinite = pose_fix(MeasurementSource::kNdt, 1, 2, 0.5, 0.01);
  indefinite.covariance(0, 1) = indefinite.covariance(1, 0) = 0.5;
  EXPECT_EQ(ekf.add(indefinite), MeasurementOutcome::kRejectedInvalid);
  PoseMeasurement asymmetric = pose_fix(MeasurementSource::kNdt, 1, 2, 0.5, 0.01);
  asymmetric.covariance(0, 1) = 0.001;
  EXPECT_EQ(ekf.add(asymmetric), MeasurementOutcome::kRejectedInvalid);
  EXPECT_EQ(ekf.stats().count(MeasurementOutcome::kRejectedInvalid), 3U);
  EXPECT_EQ(ekf.stats().rejected(), 4U);
  EXPECT_NEAR(ekf.latest()->state(kX), 1.0, 1e-12);
}

TEST(VehicleEkf, EstimateAtDoesNotChangeTheFilter) {
  VehicleEkf ekf(config_with_offset());
  const std::vector<PoseMeasurement> stream = drive(20, true);
  StateEstimate after_tenth;
  for (std::size_t i = 0; i < stream.size(); ++i) {
    ekf.add(stream[i]);
    if (i == 9) {
      after_tenth = *ekf.latest();
    }
  }
  const StateEstimate newest = *ekf.latest();
  // Querying the past gives the state as it was then; querying the future predicts along the road.
  const auto past = ekf.estimate_at(after_tenth.time);
  EXPECT_EQ(past->state, after_tenth.state);
  const auto ahead = ekf.estimate_at(newest.time + kNsPerSecond);
  EXPECT_NEAR(ahead->state(kX) - newest.state(kX), kTruthSpeed * std::cos(kHeading), 0.2);
  EXPECT_GT(ahead->covariance(kX, kX), newest.covariance(kX, kX));
  EXPECT_EQ(ekf.latest()->state, newest.state);
  EXPECT_EQ(ekf.latest()->time, newest.time);
}

// Lock-out recovery needs a run of refused NDT poses with nothing accepted in between: fewer NDT outliers
// in a row, or outliers interleaved with accepted RSU fixes, never restart the filter.
TEST(VehicleEkf, ShortOrInterruptedNdtOutlierRunsDoNotRestart) {
  const VehicleEkfConfig config = config_with_offset();
  const int run = config.ndt_restart_after_rejections;
  ASSERT_GT(run, 1);
  for (const bool with_rsu : {false, true}) {
    VehicleEkf ekf(config);
    int k = 0;
    for (; k < 20; ++k) {
      ekf.add(ndt_at(kStart + k * 100 * kNsPerMs, static_cast<std::uint64_t>(k)));
    }
    // NDT jumps 3 m sideways and stays there: run - 1 poses alone, or any number between good RSU fixes.
    const int outliers = with_rsu ? 3 * run : run - 1;
    for (int i = 0; i < outliers; ++i, ++k) {
      const TimeNs t = kStart + k * 100 * kNsPerMs;
      PoseMeasurement bad = ndt_at(t, static_cast<std::uint64_t>(k));
      bad.pose.y += 3.0;
      EXPECT_EQ(ekf.add(bad), MeasurementOutcome::kRejectedGate) << "outlier " << i;
      if (with_rsu) {
        EXPECT_EQ(ekf.add(rsu_at(t + 50 * kNsPerMs, static_cast<std::uint64_t>(k))),
                  MeasurementOutcome::kAccepted);
      }
    }
    EXPECT_EQ(ekf.stats().ndt_restarts, 0U);
    EXPECT_LT(position_error(ekf, kStart + (k - 1) * 100 * kNsPerMs), 0.3);
  }
}

TEST(VehicleEkf, RestartsFromNdtAfterALongGap) {
  VehicleEkf ekf(config_with_offset());
  for (const auto& m : drive(10, false)) {
    ekf.add(m);
  }
  PoseMeasurement far_later = ndt_at(kStart + 60 * kNsPerSecond, 999);
  far_later.pose = {500.0, 400.0, 1.0};
  PoseMeasurement rsu_later = rsu_at(kStart + 30 * kNsPerSecond, 998);
  EXPECT_EQ(ekf.add(rsu_later), MeasurementOutcome::kRejectedNotInitialized);
  EXPECT_EQ(ekf.add(far_later), MeasurementOutcome::kInitialized);
  EXPECT_EQ(ekf.latest()->state(kX), 500.0);
  EXPECT_EQ(ekf.latest()->time, far_later.time);
  // Absurd timestamps neither hang nor crash.
  PoseMeasurement absurd = pose_fix(MeasurementSource::kNdt, 500.0, 400.0, 1.0, 0.01);
  absurd.time = std::numeric_limits<TimeNs>::max();
  EXPECT_EQ(ekf.add(absurd), MeasurementOutcome::kInitialized);
  absurd.time = std::numeric_limits<TimeNs>::min();
  EXPECT_EQ(ekf.add(absurd), MeasurementOutcome::kRejectedTooOld);
  EXPECT_TRUE(ekf.estimate_at(0)->state.allFinite());
}

}  // namespace
}  // namespace rsu::fusion
