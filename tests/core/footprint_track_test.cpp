// SPDX-License-Identifier: Apache-2.0
// The footprint tracked over rotations (core/footprint_track.h): a car driving along a straight road at
// 10 m/s, swept every 0.1 s. Each rotation's fix is built here around the car's true centre the way the
// improved correction states it (the centre in the middle of the interval containment leaves, or on a
// seen end), so the test knows where the car truly is and what each rotation could honestly claim.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <random>

#include <Eigen/Core>

#include "core/footprint_track.h"

namespace rsu::core {
namespace {

constexpr TimeNs kRotation = 100 * kNsPerMs;
constexpr double kSpeed = 10.0;
constexpr double kHeading = 0.3;  // rad
constexpr double kNoise = 0.03;   // the fixes' other along-axis terms (m)
constexpr double kAcross = 0.05;  // their across-axis sigma (m)
constexpr double kChi2TwoDof3Sigma = 11.829;

Eigen::Vector2d heading() {
  return {std::cos(kHeading), std::sin(kHeading)};
}

Eigen::Vector2d truth_at(TimeNs t) {
  return Eigen::Vector2d(5.0, -3.0) + kSpeed * to_seconds(t) * heading();
}

// The car's announcement made at `t` (its own pose 0.3 m off: only its motion is used).
v2i::VehicleAnnouncement announced(TimeNs t = 0) {
  v2i::VehicleAnnouncement a;
  a.vehicle_id = 7;
  a.generation_time = t;
  a.size = {4.5, 1.8, 1.5};
  const Eigen::Vector2d p = truth_at(t) + Eigen::Vector2d(0.3, -0.3);
  a.pose = {p.x(), p.y(), kHeading};
  a.speed_mps = kSpeed;
  a.yaw_rate_rps = 0.0;
  return a;
}

// Rotation `t`'s fix: its centre `offset` m ahead of the true one along the length axis, in the middle of
// an interval `width` m wide (the true centre inside it), stated as a uniform error over it; withheld as
// unbounded (sigma > 0.5 m) as the improved correction does.
GatheredFix interval_fix(TimeNs t, double offset, double width, double yaw = kHeading) {
  GatheredFix f;
  f.sweep_time = t;
  perception::CorrectedPose& c = f.fix.corrected;
  const Eigen::Vector2d u(std::cos(yaw), std::sin(yaw));
  const Eigen::Vector2d v(-u.y(), u.x());
  const Eigen::Vector2d centre = truth_at(t) + offset * u;
  c.pose = {centre.x(), centre.y(), yaw};
  c.length_axis = {perception::AxisAnchor::interval, 0, -1.0, width};
  c.covariance = Eigen::Matrix3d::Zero();
  c.covariance.topLeftCorner<2, 2>() =
      (width * width / 12.0 + kNoise * kNoise) * u * u.transpose() + kAcross * kAcross * v * v.transpose();
  c.covariance(2, 2) = std::pow(deg_to_rad(1.0), 2);
  const bool unbounded = perception::position_sigma_m(c) > 0.5;
  c.status = unbounded ? perception::CorrectionStatus::position_unbounded : perception::CorrectionStatus::ok;
  f.outcome = unbounded ? GatheredFixOutcome::correction_failed : GatheredFixOutcome::fixed;
  return f;
}

double nees(const GatheredFix& f, TimeNs t) {
  const Eigen::Vector2d e = Eigen::Vector2d(f.fix.corrected.pose.x, f.fix.corrected.pose.y) - truth_at(t);
  return e.dot(f.fix.corrected.covariance.topLeftCorner<2, 2>().ldlt().solve(e));
}

struct Drive {
  FootprintTracks tracks;
  LidarStats stats;
  v2i::VehicleAnnouncement a = announced();

  void combine(GatheredFix& f) {
    tracks.combine(f, a, true, kRotation, 0.5, tracking::HypothesisConfig{}, stats);
  }
  // The first rotation: the car's front seen, not its back (the centre 0.2 m behind to 1.8 m ahead of
  // the fix's), withheld; then `next`, combined with it.
  GatheredFix after_the_front(GatheredFix next) {
    GatheredFix first = interval_fix(0, -0.8, 2.0);
    combine(first);
    EXPECT_FALSE(first.ok());  // nothing to combine with yet
    combine(next);
    return next;
  }
};

// Approaching from far away the first rotation sees the car's front end at bonnet height, nothing of
// its back: its centre lies anywhere from 0.2 m behind to 1.8 m ahead of where the fix puts it (2 m wide,
// withheld). The next sees its back, not its front: anywhere from 1.8 m behind to 0.2 m ahead. Each
// alone is unbounded; carried by the car's 1 m of motion, together they leave about 0.8 m, and the second
// rotation's fix goes out, bounded by the track, its stated covariance covering its error.
TEST(FootprintTrack, EndsSeenInDifferentRotationsBoundTheFix) {
  ASSERT_FALSE(interval_fix(kRotation, 0.8, 2.0).ok());  // unbounded on its own
  Drive run;
  const GatheredFix second = run.after_the_front(interval_fix(kRotation, 0.8, 2.0));
  const double own_error = 0.8;
  ASSERT_TRUE(second.ok());
  EXPECT_EQ(second.fix.status(), perception::CorrectionStatus::ok);
  EXPECT_LE(perception::position_sigma_m(second.fix.corrected), 0.5);
  const Eigen::Vector2d sent(second.fix.corrected.pose.x, second.fix.corrected.pose.y);
  EXPECT_LT((sent - truth_at(kRotation)).norm(), own_error);  // nearer than the rotation's own middle
  EXPECT_LT(nees(second, kRotation), kChi2TwoDof3Sigma);
  EXPECT_EQ(run.stats.track_bounded, 1U);
  EXPECT_EQ(run.stats.track_conflicts, 0U);
}

// A rotation missed (the car hidden, its fix refused) breaks the chain: the next interval is not cut by
// what is now 0.3 s old, and the fix stays withheld.
TEST(FootprintTrack, AGapOfRotationsResetsTheTrack) {
  Drive run;
  const GatheredFix late = run.after_the_front(interval_fix(3 * kRotation, 0.8, 2.0));
  EXPECT_FALSE(late.ok());
  EXPECT_EQ(late.fix.status(), perception::CorrectionStatus::position_unbounded);
  EXPECT_EQ(run.stats.track_resets, 1U);
  EXPECT_EQ(run.stats.track_bounded, 0U);
}

// A yaw the announced yaw rate (none) does not explain, or a fix refused for another reason, or a new
// announced size, each break the chain too.
TEST(FootprintTrack, AnUnexplainedTurnANewSizeOrARefusedFixResetsTheTrack) {
  {
    Drive run;
    const GatheredFix turned =
        run.after_the_front(interval_fix(kRotation, 0.8, 2.0, kHeading + deg_to_rad(15.0)));
    EXPECT_FALSE(turned.ok());
    EXPECT_EQ(run.stats.track_resets, 1U);
  }
  {
    Drive run;
    GatheredFix resized = interval_fix(kRotation, 0.8, 2.0);
    GatheredFix first = interval_fix(0, -0.8, 2.0);
    run.combine(first);
    run.a.size.length_m = 4.8;
    run.combine(resized);
    EXPECT_FALSE(resized.ok());
    EXPECT_EQ(run.stats.track_resets, 1U);
  }
  {
    Drive run;
    GatheredFix refused = interval_fix(kRotation, 0.0, 2.0);
    refused.outcome = GatheredFixOutcome::inconsistent;
    run.after_the_front(refused);
    GatheredFix third = interval_fix(2 * kRotation, 0.8, 2.0);
    run.combine(third);
    EXPECT_FALSE(third.ok());
    EXPECT_EQ(run.stats.track_resets, 1U);
  }
}

// A rotation whose interval lies wholly beyond where the track carries the car (here 3 m ahead: one of
// the two bounds is wrong) is withheld and counted, and the track forgotten: the next rotation starts
// afresh.
TEST(FootprintTrack, AnEmptyIntersectionWithholdsAndResets) {
  Drive run;
  GatheredFix first = interval_fix(0, -0.8, 2.0);
  run.combine(first);
  GatheredFix wrong = interval_fix(kRotation, 3.0 + 1.1, 2.0);    // its interval starts 3 m ahead of the car
  wrong.fix.corrected.status = perception::CorrectionStatus::ok;  // even one the rotation would send
  wrong.outcome = GatheredFixOutcome::fixed;
  run.combine(wrong);
  EXPECT_EQ(wrong.outcome, GatheredFixOutcome::track_conflict);
  EXPECT_FALSE(wrong.ok());
  EXPECT_EQ(run.stats.track_conflicts, 1U);
  EXPECT_EQ(run.tracks.size(), 0U);
  GatheredFix next = interval_fix(2 * kRotation, 0.8, 2.0);
  run.combine(next);
  EXPECT_FALSE(next.ok());  // nothing left to cut it
  EXPECT_EQ(run.stats.track_bounded, 0U);
}

// Over a longer drive the track keeps bounding the roof-only rotations once an end was seen, and never
// states less than its error: each rotation sees alternately the front and the back (as the first test),
// or only the roof (the centre anywhere in 2.6 m about the truth, at a varying place inside it).
TEST(FootprintTrack, ALongDriveStaysBoundedAndHonest) {
  Drive run;
  int sent = 0;
  for (int k = 0; k < 40; ++k) {
    const TimeNs t = k * kRotation;
    run.a = announced(t - 50 * kNsPerMs);    // it announces every rotation, half a rotation before the sweep
    const double place = std::sin(0.7 * k);  // where inside its interval the truth lies, -1..1
    GatheredFix f =
        k % 3 == 0 ? interval_fix(t, k % 2 == 0 ? -0.8 : 0.8, 2.0) : interval_fix(t, 1.2 * place, 2.6);
    run.combine(f);
    if (!f.ok())
      continue;
    ++sent;
    EXPECT_LT(nees(f, t), kChi2TwoDof3Sigma) << k;
  }
  EXPECT_GT(sent, 30);
  EXPECT_EQ(run.stats.track_conflicts, 0U);
  EXPECT_EQ(run.stats.track_resets, 0U);
}

// The carried bound's reach along a direction, against the region written out: the segment [lo, hi] along
// its axis, widened by the along error, times the band across it, widened by the across error, moved by
// the motion; its projection's ends are those of its four corners.
TEST(FootprintTrack, CarriedIntervalIsTheCarriedRegionsProjection) {
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 500; ++trial) {
    FootprintBound b;
    b.centre = {20.0 * u(rng), 20.0 * u(rng)};
    const double yaw = 3.2 * u(rng);
    b.axis = {std::cos(yaw), std::sin(yaw)};
    b.lo = -0.1 - 2.0 * std::abs(u(rng));
    b.hi = 0.1 + 2.0 * std::abs(u(rng));
    b.across_half_m = 0.5 * std::abs(u(rng));
    const Eigen::Vector2d motion(2.0 * u(rng), 2.0 * u(rng));
    const double along_error = 0.5 * std::abs(u(rng)), across_error = 0.3 * std::abs(u(rng));
    const Eigen::Vector2d origin(20.0 * u(rng), 20.0 * u(rng));
    const double turn = 3.2 * u(rng);
    const Eigen::Vector2d direction(std::cos(turn), std::sin(turn));
    const Eigen::Vector2d across(-b.axis.y(), b.axis.x());
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (const double s : {b.lo - along_error, b.hi + along_error}) {
      for (const double t : {-(b.across_half_m + across_error), b.across_half_m + across_error}) {
        const double v = (b.centre + motion + s * b.axis + t * across - origin).dot(direction);
        lo = std::min(lo, v);
        hi = std::max(hi, v);
      }
    }
    const auto [got_lo, got_hi] = carried_interval(b, motion, along_error, across_error, origin, direction);
    EXPECT_NEAR(got_lo, lo, 1e-9) << "trial " << trial;
    EXPECT_NEAR(got_hi, hi, 1e-9) << "trial " << trial;
  }
}

// What one rotation's fix bounds: an interval-placed centre its hard interval plus 3 sigma of the other
// terms of its variance; any other the larger of 3 sigma and min_bound_half_m. Across, 3 sigma.
TEST(FootprintTrack, BoundOfAFixFromItsCovariance) {
  const FootprintTrackConfig config;
  perception::CorrectedPose fix;
  fix.pose = {4.0, -2.0, std::numbers::pi / 6.0};
  const Eigen::Vector2d axis(std::cos(fix.pose.yaw), std::sin(fix.pose.yaw));
  const Eigen::Vector2d across(-axis.y(), axis.x());
  // Along 0.2 m sigma, across 0.05 m, uncorrelated in the box frame.
  const Eigen::Matrix2d local = Eigen::Vector2d(0.04, 0.0025).asDiagonal();
  Eigen::Matrix2d frame;
  frame << axis, across;
  fix.covariance = Eigen::Matrix3d::Identity() * 1e-4;
  fix.covariance.topLeftCorner<2, 2>() = frame * local * frame.transpose();

  fix.length_axis.anchor = perception::AxisAnchor::face;
  FootprintBound b = bound_of(fix, config);
  EXPECT_NEAR(b.hi, 3.0 * 0.2, 1e-12);
  EXPECT_NEAR(b.lo, -3.0 * 0.2, 1e-12);
  EXPECT_NEAR(b.across_half_m, 3.0 * 0.05, 1e-12);
  EXPECT_NEAR((b.centre - Eigen::Vector2d(4.0, -2.0)).norm(), 0.0, 1e-15);
  EXPECT_NEAR(b.axis.dot(axis), 1.0, 1e-15);

  fix.covariance.topLeftCorner<2, 2>() = frame * Eigen::Vector2d(1e-4, 1e-4).asDiagonal() * frame.transpose();
  EXPECT_NEAR(bound_of(fix, config).hi, config.min_bound_half_m, 1e-12);  // 3 sigma = 0.03 m: the floor

  // An interval 0.8 m wide holding the centre, its variance the uniform's (0.8^2 / 12) plus 0.05^2 of noise.
  fix.length_axis.anchor = perception::AxisAnchor::interval;
  fix.length_axis.interval_m = 0.8;
  const double variance = 0.8 * 0.8 / 12.0 + 0.05 * 0.05;
  fix.covariance.topLeftCorner<2, 2>() =
      frame * Eigen::Vector2d(variance, 0.0025).asDiagonal() * frame.transpose();
  b = bound_of(fix, config);
  EXPECT_NEAR(b.hi, 0.4 + 3.0 * 0.05, 1e-9);
  EXPECT_NEAR(b.lo, -(0.4 + 3.0 * 0.05), 1e-9);
}

}  // namespace
}  // namespace rsu::core
