// SPDX-License-Identifier: Apache-2.0
// The vehicle's fault detection and exclusion (IntegrityMonitor inside VehicleCore) on simulated drives
// whose truth, NDT noise and RSU faults the test makes itself: honest sources are (almost) never
// excluded, and the false-exclusion rate is measured; biased, rotated, overconfident and wrong-vehicle
// sources are excluded within a bounded number of fixes and never move the pose far; the own estimate
// is overruled only when its NDT says it failed or two RSUs agree against it.
#include "vehicle/integrity_monitor.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <vector>

#include "common/angles.h"
#include "common/random.h"
#include "vehicle/vehicle_core.h"

namespace rsu::vehicle {
namespace {

constexpr double kSpeed = 11.0;  // m/s, along +x (the corridor's drive)
constexpr TimeNs kDriveStart = 100 * kNsPerSecond;
constexpr TimeNs kStep = 100 * kNsPerMs;       // 10 Hz NDT and RSU
constexpr TimeNs kSweepAfter = 40 * kNsPerMs;  // each fix is swept 40 ms after an NDT pose

Eigen::Vector2d truth_at(TimeNs t) {
  return {kSpeed * to_seconds(t - kDriveStart), -1.75};
}

Eigen::Matrix3d diagonal(double sxy, double syaw) {
  return Eigen::Vector3d(sxy * sxy, sxy * sxy, syaw * syaw).asDiagonal();
}

// One simulated RSU: its fixes are the truth plus noise of `true_sigma_m` plus `error(t)`, and claim
// `claimed_sigma_m` (the corridor's RSU fixes claim a few cm).
struct RsuModel {
  std::uint64_t rsu_id = 1;
  double true_sigma_m = 0.05;
  double claimed_sigma_m = 0.05;
  double yaw_sigma_rad = 0.015;
  double claimed_yaw_sigma_rad = 0.015;
  std::function<Eigen::Vector2d(TimeNs)> error = [](TimeNs) { return Eigen::Vector2d::Zero(); };
  TimeNs from = kDriveStart;  // first sweep time in view
  TimeNs until = kDriveStart + 1000 * kNsPerSecond;
  std::uint64_t seed = 1;
};

// The vehicle's NDT: the truth plus white noise of `true_sigma_m` plus `drift(t)`, claiming 0.15 m
// (Autoware's fixed covariance), with a quality indicator that says degraded while `degraded(t)`.
struct NdtModel {
  double true_sigma_m = 0.15;
  double claimed_sigma_m = 0.15;
  std::function<Eigen::Vector2d(TimeNs)> drift = [](TimeNs) { return Eigen::Vector2d::Zero(); };
  std::function<bool(TimeNs)> degraded = [](TimeNs) { return false; };
  std::uint64_t seed = 1;
};

struct FixRecord {
  std::uint64_t rsu_id = 0;
  TimeNs time = 0;
  CorrectionStep step;
  double true_error_m = 0.0;  // of the fix itself
};

struct DriveResult {
  std::vector<FixRecord> fixes;
  double ndt_mae = 0.0;
  double fused_mae = 0.0;
  double fused_max = 0.0;
  double ndt_max = 0.0;
};

v2i::Correction make_fix(const RsuModel& rsu, TimeNs t, int k) {
  const NormalPair n = standard_normal_pair(rsu.seed, 100 + rsu.rsu_id, static_cast<std::uint64_t>(k));
  const NormalPair m = standard_normal_pair(rsu.seed, 200 + rsu.rsu_id, static_cast<std::uint64_t>(k));
  const Eigen::Vector2d p = truth_at(t) + rsu.error(t) + rsu.true_sigma_m * Eigen::Vector2d(n.a, n.b);
  v2i::Correction c;
  c.rsu_id = rsu.rsu_id;
  c.vehicle_id = 1;
  c.sequence = static_cast<std::uint32_t>(k);
  c.sweep_time = t;
  c.pose = {p.x(), p.y(), wrap_angle(rsu.yaw_sigma_rad * m.a + (k % 2 ? kPi : 0.0))};  // a box yaw
  c.pose_covariance = diagonal(rsu.claimed_sigma_m, rsu.claimed_yaw_sigma_rad);
  return c;
}

// Drives for `seconds`; errors are scored at the NDT poses' times (as the corridor report does), from
// `score_from` on.
DriveResult drive(double seconds, const NdtModel& ndt, const std::vector<RsuModel>& rsus,
                  const VehicleCoreConfig& config = {}, TimeNs score_from = kDriveStart) {
  VehicleCore core(config);
  DriveResult r;
  int scored = 0;
  const int steps = static_cast<int>(seconds * 10.0);
  for (int k = 0; k < steps; ++k) {
    const TimeNs t = kDriveStart + k * kStep;
    const NormalPair n = standard_normal_pair(ndt.seed, 7, static_cast<std::uint64_t>(k));
    const NormalPair m = standard_normal_pair(ndt.seed, 8, static_cast<std::uint64_t>(k));
    const Eigen::Vector2d p = truth_at(t) + ndt.drift(t) + ndt.true_sigma_m * Eigen::Vector2d(n.a, n.b);
    NdtPose pose{t, {p.x(), p.y(), 0.025 * m.a}, diagonal(ndt.claimed_sigma_m, 0.025), {}};
    pose.quality.converged = !ndt.degraded(t);
    const NdtStep step = core.on_ndt(pose);
    if (t >= score_from && step.fused) {
      const double e_ndt = (p - truth_at(t)).norm();
      const double e_fused =
          (Eigen::Vector2d(step.fused->state(fusion::kX), step.fused->state(fusion::kY)) - truth_at(t))
              .norm();
      r.ndt_mae += e_ndt;
      r.fused_mae += e_fused;
      r.ndt_max = std::max(r.ndt_max, e_ndt);
      r.fused_max = std::max(r.fused_max, e_fused);
      ++scored;
    }
    for (const RsuModel& rsu : rsus) {
      const TimeNs sweep = t + kSweepAfter;
      if (sweep < rsu.from || sweep > rsu.until) {
        continue;
      }
      const v2i::Correction fix = make_fix(rsu, sweep, k);
      r.fixes.push_back({rsu.rsu_id, sweep, core.on_correction(fix),
                         (Eigen::Vector2d(fix.pose.x, fix.pose.y) - truth_at(sweep)).norm()});
    }
  }
  r.ndt_mae /= std::max(scored, 1);
  r.fused_mae /= std::max(scored, 1);
  return r;
}

bool fused(const FixRecord& f) {
  return f.step.outcome == fusion::MeasurementOutcome::kAccepted;
}
bool excluded_now(const FixRecord& f) {
  return f.step.check && f.step.check->excluded_now;
}
// Fixes of `rsu_id` from its first until the one that excluded it (-1: never excluded).
int fixes_until_exclusion(const DriveResult& r, std::uint64_t rsu_id) {
  int n = 0;
  for (const FixRecord& f : r.fixes) {
    if (f.rsu_id != rsu_id)
      continue;
    ++n;
    if (excluded_now(f))
      return n;
  }
  return -1;
}

// Honest sources (fixes and NDT exactly as noisy as they claim) over 2000 s of driving for each of three
// seeds, 60,000 fixes: the false-exclusion rate is measured and bounded. The own estimate's error is
// correlated from fix to fix (it is a filter), so the CUSUM trips more often than for independent
// innovations (about 1e-5 per fix with these settings); this test measures what it really is.
TEST(IntegrityMonitor, HonestSourcesAreAlmostNeverExcluded) {
  constexpr double kSeconds = 2000.0;
  std::uint64_t fixes = 0, exclusions = 0, refused_gate = 0;
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    NdtModel ndt;
    ndt.seed = seed;
    std::vector<RsuModel> rsus(2);
    rsus[1].rsu_id = 2;
    for (RsuModel& rsu : rsus) {
      rsu.seed = seed;
    }
    const DriveResult r = drive(kSeconds, ndt, rsus);
    fixes += r.fixes.size();
    for (const FixRecord& f : r.fixes) {
      exclusions += excluded_now(f) ? 1 : 0;
      refused_gate += f.step.check && f.step.check->verdict == FixVerdict::kInconsistent ? 1 : 0;
    }
    // Admitted once its first five fixes were consistent together.
    std::size_t first_fused = 0;
    while (first_fused < r.fixes.size() && !fused(r.fixes[first_fused])) {
      ++first_fused;
    }
    EXPECT_LE(first_fused, 2 * 6U) << "seed " << seed;  // two RSUs' fixes interleave
    EXPECT_LT(r.fused_mae, 0.6 * r.ndt_mae) << "seed " << seed;
  }
  const double rate = static_cast<double>(exclusions) / static_cast<double>(fixes);
  const double gate_rate = static_cast<double>(refused_gate) / static_cast<double>(fixes);
  RecordProperty("fixes", std::to_string(fixes));
  RecordProperty("false_exclusions", std::to_string(exclusions));
  RecordProperty("refused_by_fix_gate", std::to_string(refused_gate));
  std::printf(
      "honest sources: %llu fixes, %llu false exclusions (%.1e per fix), %llu refused by the per-fix "
      "gate (%.1e)\n",
      static_cast<unsigned long long>(fixes), static_cast<unsigned long long>(exclusions), rate,
      static_cast<unsigned long long>(refused_gate), gate_rate);
  EXPECT_LE(rate, 3e-4);
  EXPECT_LE(gate_rate, 2e-3);  // the 99.9 % gate, with both covariances honest
}

// A constant position bias claimed at 5 cm, in every direction, against an honest NDT claiming 0.15 m:
// how many fixes the monitor needs, over 200 seeded trials each. Along the road the vehicle's own
// estimate is least sure (its speed is estimated from the same poses: 0.09 m there, 0.06 m across), so
// a 0.3 m bias along the road is the hardest case; the tail is stated, not hidden.
TEST(IntegrityMonitor, BiasedSourcesAreExcludedWithinOneSecond) {
  for (const double bias : {0.3, 1.0, 3.0}) {
    std::vector<int> delays;
    int fused_total = 0, trials = 0;
    for (std::uint64_t seed = 1; seed <= 200; ++seed, ++trials) {
      NdtModel ndt;
      ndt.seed = seed;
      RsuModel rsu;
      rsu.seed = seed;
      const double angle = 0.7 * static_cast<double>(seed);  // every direction
      rsu.error = [=](TimeNs) { return Eigen::Vector2d(bias * std::cos(angle), bias * std::sin(angle)); };
      rsu.from = kDriveStart + 3 * kNsPerSecond;  // in view once the own filter has settled
      const DriveResult r = drive(8.0, ndt, {rsu});
      delays.push_back(fixes_until_exclusion(r, rsu.rsu_id));
      for (const FixRecord& f : r.fixes) {
        fused_total += fused(f) ? 1 : 0;
      }
    }
    std::sort(delays.begin(), delays.end());
    const int p95 = delays[static_cast<std::size_t>(0.95 * trials)];
    std::printf(
        "bias %.1f m claimed at 5 cm: excluded after %d fixes (median), %d (p95), %d (max) of %d trials; "
        "%.2f fixes fused per trial before\n",
        bias, delays[static_cast<std::size_t>(trials / 2)], p95, delays.back(), trials,
        static_cast<double>(fused_total) / trials);
    EXPECT_GT(delays.front(), 0) << bias << " m: every trial excluded it";
    EXPECT_LE(p95, 10) << bias << " m: within 1 s at 10 Hz";
    EXPECT_LE(delays.back(), 25) << bias;
    EXPECT_LE(fused_total, trials / 2) << bias;  // almost always caught in probation
    if (bias >= 1.0) {
      EXPECT_LE(delays.back(), 2) << bias;  // two gross fixes exclude
      EXPECT_EQ(fused_total, 0) << bias;    // and none is ever fused
    }
  }
}

// Fixes that claim a fifth of their real spread (covariance x0.04: 1 cm for 5 cm). The vehicle credits
// no fix with less than 3 cm (VehicleCoreConfig::min_rsu_sigma_m), and against an own estimate of
// 0.06-0.09 m the remaining understatement shows only partly, so accurate but overconfident fixes are
// excluded in some drives, not all; either way the fused pose is better than NDT's. Overconfident fixes
// that are also wrong (a 0.3 m bias along the road, the hardest direction) are excluded in every drive.
TEST(IntegrityMonitor, OverconfidentFixesAreHarmlessWhenRightAndExcludedWhenWrong) {
  int excluded_right = 0, excluded_wrong = 0, worst = 0;
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    NdtModel ndt;
    ndt.seed = seed;
    RsuModel rsu;
    rsu.seed = seed;
    rsu.claimed_sigma_m = 0.2 * rsu.true_sigma_m;
    rsu.claimed_yaw_sigma_rad = 0.2 * rsu.yaw_sigma_rad;
    const DriveResult right = drive(30.0, ndt, {rsu});
    excluded_right += fixes_until_exclusion(right, 1) > 0 ? 1 : 0;
    EXPECT_LT(right.fused_mae, right.ndt_mae) << "seed " << seed;
    rsu.error = [](TimeNs) { return Eigen::Vector2d(0.3, 0.0); };
    const DriveResult wrong = drive(30.0, ndt, {rsu});
    const int n = fixes_until_exclusion(wrong, 1);
    EXPECT_GT(n, 0) << "seed " << seed;
    worst = std::max(worst, n);
    excluded_wrong += n > 0 ? 1 : 0;
    EXPECT_LT(wrong.fused_mae, 1.1 * wrong.ndt_mae) << "seed " << seed;
  }
  std::printf(
      "overconfident fixes (covariance x0.04): excluded in %d of 20 drives when right; when 0.3 m off "
      "in %d of 20, after at most %d fixes\n",
      excluded_right, excluded_wrong, worst);
  EXPECT_LE(worst, 20);          // along the road, as in BiasedSourcesAreExcludedWithinOneSecond's tail
  EXPECT_GE(excluded_right, 5);  // overconfidence alone is seen in some drives
}

// Bursts of another vehicle's fixes (the car in the next lane, 3.5 m across and 6 m ahead), 0.5 s every
// 20 s, from an otherwise good RSU: each burst excludes the RSU after two fixes, none of its fixes is
// fused, and the RSU is readmitted after the burst once it has been consistent again, for longer after
// each exclusion (1, 2, 4, 8 s and 10, 20, 40, 80 fixes); the fifth exclusion bars it for the trip.
TEST(IntegrityMonitor, WrongVehicleBurstsAreExcludedAndTheRsuReadmittedAfterwards) {
  NdtModel ndt;
  RsuModel rsu;
  const auto in_burst = [](TimeNs t) {
    const double s = std::fmod(to_seconds(t - kDriveStart), 20.0);
    return s >= 4.0 && s < 4.5;
  };
  rsu.error = [=](TimeNs t) { return in_burst(t) ? Eigen::Vector2d(6.0, 3.5) : Eigen::Vector2d::Zero(); };
  const DriveResult r = drive(110.0, ndt, {rsu});
  int bursts = 0, burst_fixes_fused = 0, burst_fix = 0, fused_after_bar = 0;
  std::vector<TimeNs> excluded_at, readmitted_at;
  for (const FixRecord& f : r.fixes) {
    if (in_burst(f.time)) {
      burst_fix = in_burst(f.time - kStep) ? burst_fix + 1 : 1;
      bursts += burst_fix == 1 ? 1 : 0;
      burst_fixes_fused += fused(f) ? 1 : 0;
      if (excluded_now(f)) {
        EXPECT_EQ(burst_fix, 2) << "burst " << bursts;  // 0.1 s after the burst's first fix
        excluded_at.push_back(f.time);
      }
    } else {
      EXPECT_FALSE(excluded_now(f)) << "at " << to_seconds(f.time - kDriveStart) << " s";
    }
    if (f.step.check && f.step.check->admitted_now && !excluded_at.empty()) {
      readmitted_at.push_back(f.time);
    }
    if (excluded_at.size() == 5) {
      fused_after_bar += fused(f) ? 1 : 0;
      EXPECT_EQ(f.step.check->verdict, FixVerdict::kBarred);
    }
  }
  EXPECT_EQ(bursts, 6);
  EXPECT_EQ(burst_fixes_fused, 0);
  ASSERT_EQ(excluded_at.size(), 5U);
  ASSERT_EQ(readmitted_at.size(), 4U);
  for (std::size_t i = 0; i < readmitted_at.size(); ++i) {
    // Not before the hold, nor before the run of consistent fixes after the burst's last one (0.3 s after
    // the exclusion); and not much later than both: the CUSUM the burst drove up must first decay.
    const double waited = to_seconds(readmitted_at[i] - excluded_at[i]);
    const double hold = static_cast<double>(1 << i);
    const double run = 0.3 + 0.1 * std::min(80, 10 << i);
    EXPECT_GE(waited, hold) << "exclusion " << i + 1;
    EXPECT_GE(waited, run - 1e-6) << "exclusion " << i + 1;
    EXPECT_LE(waited, std::max(hold, run) + 1.0) << "exclusion " << i + 1;
  }
  EXPECT_EQ(fused_after_bar, 0);
  EXPECT_LT(r.fused_max, 0.5);
}

// Two RSUs in view, one 1 m off: it is excluded after two fixes, the good one is never excluded, their
// fixes are compared with each other (and disagree), and the fused pose is as good as with the good RSU
// alone.
TEST(IntegrityMonitor, AFaultyRsuBesideAGoodOneIsExcludedAndTheGoodOneKept) {
  NdtModel ndt;
  RsuModel good;
  RsuModel faulty;
  faulty.rsu_id = 2;
  faulty.seed = 5;
  faulty.error = [](TimeNs) { return Eigen::Vector2d(0.0, 1.0); };
  VehicleCore core;
  const DriveResult both = drive(20.0, ndt, {good, faulty}, {}, kDriveStart + 2 * kNsPerSecond);
  const DriveResult alone = drive(20.0, ndt, {good}, {}, kDriveStart + 2 * kNsPerSecond);
  EXPECT_EQ(fixes_until_exclusion(both, 2), 2);
  EXPECT_EQ(fixes_until_exclusion(both, 1), -1);
  int faulty_fused = 0;
  for (const FixRecord& f : both.fixes) {
    faulty_fused += f.rsu_id == 2 && fused(f) ? 1 : 0;
  }
  EXPECT_EQ(faulty_fused, 0);
  EXPECT_NEAR(both.fused_mae, alone.fused_mae, 0.1 * alone.fused_mae);
}

// The vehicle's NDT drifts 1.5 m across the road while its quality indicator says all is well (a map
// that differs from the street), and two good RSUs see the vehicle. They agree with each other and
// both disagree with the own estimate: the own estimate is the one that failed, the fused filter is
// re-anchored at their fixes and follows them. With one RSU alone nothing proves that: the vehicle
// trusts its own NDT and excludes the RSU (the price of never being led astray by a single source).
TEST(IntegrityMonitor, TwoAgreeingRsusOverruleADriftedNdtOneDoesNot) {
  NdtModel ndt;
  ndt.drift = [](TimeNs t) {
    const double s = to_seconds(t - kDriveStart);
    return Eigen::Vector2d(0.0, 1.5 * std::clamp(s - 3.0, 0.0, 1.0));
  };
  RsuModel a;
  a.from = kDriveStart + 5 * kNsPerSecond;
  RsuModel b = a;
  b.rsu_id = 2;
  b.seed = 9;
  const TimeNs score_from = kDriveStart + 7 * kNsPerSecond;
  const DriveResult two = drive(15.0, ndt, {a, b}, {}, score_from);
  const DriveResult one = drive(15.0, ndt, {a}, {}, score_from);
  std::printf(
      "NDT 1.5 m off (healthy-looking): fused MAE %.3f m with two agreeing RSUs, %.3f m with one (NDT "
      "%.3f m)\n",
      two.fused_mae, one.fused_mae, two.ndt_mae);
  EXPECT_LT(two.fused_mae, 0.15);
  EXPECT_GT(one.fused_mae, 1.2);
  EXPECT_GT(fixes_until_exclusion(one, 1), 0);
  int reanchored = 0;
  for (const FixRecord& f : two.fixes) {
    reanchored += f.step.reanchored ? 1 : 0;
  }
  EXPECT_GE(reanchored, 1);
}

// The unit-level degraded corridor: NDT's error along the road as measured in the degraded corridor
// (scenarios/corridor_degraded.yaml, the experiment's seed): small, then a step of 0.44 m at 5.6 s, 0.3-
// 0.44 m for 1.5 s, back, 0.2 m the other way at 8.6 s; little noise besides. Its quality indicator says
// it is degraded (there: its degeneracy, above 7 nearly throughout), from the start or from the step. A
// good RSU in view: the fused error stays at least 80 % below NDT's. Said only 0.5 s into the step, the
// RSU has meanwhile been excluded against the (then healthy-looking) own estimate; the flag annuls that
// exclusion, but the RSU must prove itself again against the degraded estimate, which still follows NDT's
// step: better than NDT, not 80 % (measured and printed).
double degraded_corridor_ndt_error(TimeNs t) {
  static const std::pair<double, double> kMeasured[] = {{0.0, 0.0},   {5.1, -0.04}, {5.6, -0.44},
                                                        {6.1, -0.35}, {7.1, -0.30}, {7.6, 0.01},
                                                        {8.6, 0.20},  {9.6, 0.05},  {20.0, 0.0}};
  const double s = to_seconds(t - kDriveStart);
  for (std::size_t i = 1; i < std::size(kMeasured); ++i) {
    const auto [t0, e0] = kMeasured[i - 1];
    const auto [t1, e1] = kMeasured[i];
    if (s <= t1) {
      return e0 + (e1 - e0) * std::clamp((s - t0) / (t1 - t0), 0.0, 1.0);
    }
  }
  return 0.0;
}

TEST(IntegrityMonitor, ADegradedNdtIsStillHelpedByAGoodRsu) {
  for (const double flagged_from_s : {0.0, 5.1, 6.1}) {
    const bool in_time = flagged_from_s <= 5.1;
    NdtModel ndt;
    ndt.true_sigma_m = 0.02;
    ndt.drift = [](TimeNs t) { return Eigen::Vector2d(degraded_corridor_ndt_error(t), 0.0); };
    ndt.degraded = [=](TimeNs t) { return to_seconds(t - kDriveStart) >= flagged_from_s; };
    RsuModel rsu;
    rsu.true_sigma_m = 0.03;  // the degraded corridor's RSU fixes (MAE 0.02-0.03 m)
    const DriveResult r = drive(12.0, ndt, {rsu}, {}, kDriveStart + 4 * kNsPerSecond);
    std::printf("degraded NDT (flagged from %.1f s): NDT MAE %.3f m, fused %.3f m (%.0f %% lower)\n",
                flagged_from_s, r.ndt_mae, r.fused_mae, 100.0 * (1.0 - r.fused_mae / r.ndt_mae));
    EXPECT_LE(r.fused_mae, (in_time ? 0.2 : 1.0) * r.ndt_mae) << "flagged from " << flagged_from_s << " s";
  }
}

// An NDT that states its own, match-dependent covariance (3 cm where the match is curved, as the
// corridor's Laplace covariance does) and fails along the road while its curvature still claims 3 cm,
// flagged degraded at two poses in three (between them it looks healthy, as in the degraded corridor).
// With a good RSU, its degraded poses count with at least 0.45 m (and the healthy-looking ones in
// between likewise), so the RSU wins; with only a faulty RSU (1 m off, excluded) there is nobody to take
// over, and the fused pose follows NDT as it is instead of lagging its wander.
TEST(IntegrityMonitor, AnNdtClaimingCentimetresWhileDegradedIsWeakenedOnlyWhenAnRsuCanTakeOver) {
  NdtModel ndt;
  ndt.true_sigma_m = 0.02;
  ndt.claimed_sigma_m = 0.03;
  ndt.drift = [](TimeNs t) { return Eigen::Vector2d(degraded_corridor_ndt_error(t), 0.0); };
  ndt.degraded = [](TimeNs t) { return (t - kDriveStart) / kStep % 3 != 0; };
  RsuModel good;
  good.true_sigma_m = 0.03;
  const TimeNs score_from = kDriveStart + 4 * kNsPerSecond;
  const DriveResult helped = drive(12.0, ndt, {good}, {}, score_from);
  RsuModel biased = good;
  biased.error = [](TimeNs) { return Eigen::Vector2d(1.0, 0.0); };
  const DriveResult alone = drive(12.0, ndt, {biased}, {}, score_from);
  VehicleCoreConfig always;
  always.weaken_degraded_ndt_only_with_rsu = false;
  const DriveResult lagging = drive(12.0, ndt, {biased}, always, score_from);
  std::printf(
      "NDT claiming 3 cm, degraded: NDT MAE %.3f m; good RSU: fused %.3f m; 1 m biased RSU: fused %.3f m "
      "(weakened regardless: %.3f m)\n",
      helped.ndt_mae, helped.fused_mae, alone.fused_mae, lagging.fused_mae);
  EXPECT_LE(helped.fused_mae, 0.2 * helped.ndt_mae);
  EXPECT_GT(fixes_until_exclusion(alone, 1), 0);
  EXPECT_LE(alone.fused_mae, 1.1 * alone.ndt_mae);
  EXPECT_GT(lagging.fused_mae, alone.fused_mae);
}

// The degraded corridor's seed 2 (README, issue 13) in miniature: an NDT flagged degraded throughout and
// claiming 0.15 m (Autoware's fixed covariance), within a few cm of the truth for 4.5 s, then sliding
// 0.6-0.65 m back along the road for about 1.5 s and returning. An honest RSU that agreed with it
// before is not excluded for the slide: against a degraded own estimate consecutive fixes count as the
// one error of it they hold (IntegrityConfig::degraded_own_correlation_time). Counted fix by fix (the
// correlation time 0), the same drive excludes it, and the fused pose falls back to the slide.
double ndt_excursion(TimeNs t, double along_m) {
  static const std::pair<double, double> kShape[] = {{0.0, 0.0}, {4.5, 0.0},  {5.3, 0.92}, {6.3, 1.0},
                                                     {7.0, 0.7}, {7.6, 0.15}, {8.5, 0.0},  {20.0, 0.0}};
  const double s = to_seconds(t - kDriveStart);
  for (std::size_t i = 1; i < std::size(kShape); ++i) {
    const auto [t0, e0] = kShape[i - 1];
    const auto [t1, e1] = kShape[i];
    if (s <= t1) {
      return along_m * (e0 + (e1 - e0) * std::clamp((s - t0) / (t1 - t0), 0.0, 1.0));
    }
  }
  return 0.0;
}

TEST(IntegrityMonitor, AnNdtSlidingAlongTheRoadDoesNotExcludeAnHonestRsuThatAgreedBefore) {
  NdtModel ndt;
  ndt.true_sigma_m = 0.03;
  ndt.drift = [](TimeNs t) { return Eigen::Vector2d(ndt_excursion(t, -0.65), 0.0); };
  ndt.degraded = [](TimeNs) { return true; };
  RsuModel rsu;
  rsu.true_sigma_m = 0.03;
  const TimeNs score_from = kDriveStart + 4 * kNsPerSecond;
  const DriveResult r = drive(12.0, ndt, {rsu}, {}, score_from);
  VehicleCoreConfig fix_by_fix;
  fix_by_fix.integrity.degraded_own_correlation_time = 0;
  const DriveResult before = drive(12.0, ndt, {rsu}, fix_by_fix, score_from);
  std::printf(
      "NDT sliding 0.65 m along the road: NDT MAE %.3f m; honest RSU: fused %.3f m, excluded after %d fixes "
      "(counted fix by fix: %.3f m, excluded after %d)\n",
      r.ndt_mae, r.fused_mae, fixes_until_exclusion(r, 1), before.fused_mae,
      fixes_until_exclusion(before, 1));
  EXPECT_EQ(fixes_until_exclusion(r, 1), -1);
  EXPECT_LE(r.fused_mae, 0.2 * r.ndt_mae);
  EXPECT_GT(fixes_until_exclusion(before, 1), 0);  // the situation the test reproduces
}

// The other side of it: an RSU 1 m off along the road, the way the NDT slides 0.65 m. In view from the
// start it is excluded (its fixes beyond the gate count in full) and never fused; the fused pose stays
// within the issue-18 targets (MAE within 1.1x NDT's, maximum within NDT's + 0.1 m). Coming into view
// during the slide, where it agrees with the NDT, it is admitted and fused until the NDT returns
// (README, Known shortfalls: a single degraded NDT cannot tell); it has no record of agreeing with the
// own estimate over several correlation times, so it is judged fix by fix exactly as before.
TEST(IntegrityMonitor, AnRsuBiasedTheWayTheNdtSlidesIsStillExcluded) {
  NdtModel ndt;
  ndt.true_sigma_m = 0.03;
  ndt.drift = [](TimeNs t) { return Eigen::Vector2d(ndt_excursion(t, 0.65), 0.0); };
  ndt.degraded = [](TimeNs) { return true; };
  VehicleCoreConfig fix_by_fix;
  fix_by_fix.integrity.degraded_own_correlation_time = 0;
  for (const double seen_from_s : {0.0, 5.5}) {
    RsuModel biased;
    biased.true_sigma_m = 0.03;
    biased.error = [](TimeNs) { return Eigen::Vector2d(1.0, 0.0); };
    biased.from = kDriveStart + static_cast<TimeNs>(seen_from_s * 1e9);
    const DriveResult r = drive(12.0, ndt, {biased}, {}, kDriveStart + 4 * kNsPerSecond);
    const DriveResult before = drive(12.0, ndt, {biased}, fix_by_fix, kDriveStart + 4 * kNsPerSecond);
    const auto fused_fixes = std::count_if(r.fixes.begin(), r.fixes.end(), fused);
    std::printf(
        "1 m biased RSU from %.1f s, NDT sliding 0.65 m the same way: excluded after %d fixes, %d fused; NDT "
        "MAE %.3f max %.3f m, fused %.3f max %.3f m (fix by fix: %.3f max %.3f m)\n",
        seen_from_s, fixes_until_exclusion(r, 1), static_cast<int>(fused_fixes), r.ndt_mae, r.ndt_max,
        r.fused_mae, r.fused_max, before.fused_mae, before.fused_max);
    EXPECT_GT(fixes_until_exclusion(r, 1), 0) << seen_from_s;
    EXPECT_EQ(fixes_until_exclusion(r, 1), fixes_until_exclusion(before, 1)) << seen_from_s;
    EXPECT_LE(r.fused_max, before.fused_max + 1e-9) << seen_from_s;
    if (seen_from_s == 0.0) {
      EXPECT_EQ(fused_fixes, 0);
      EXPECT_LE(r.fused_mae, 1.1 * r.ndt_mae);
      EXPECT_LE(r.fused_max, r.ndt_max + 0.1);
    }
  }
}

// The limit: an NDT that runs away (0.5 m/s, 6 m in 12 s) far beyond what its degraded covariance
// (x4, at least 0.45 m) allows. The vehicle's own estimate follows it, a single RSU cannot prove it wrong,
// and it is excluded: the fused pose stays with NDT. (Dead reckoning on odometry or an IMU would bound such a
// run; the paper's vehicle has neither.) Measured here so that the README states it.
TEST(IntegrityMonitor, ARunawayNdtIsNotOverruledByOneRsu) {
  NdtModel ndt;
  ndt.drift = [](TimeNs t) {
    return Eigen::Vector2d(0.5 * std::max(0.0, to_seconds(t - kDriveStart) - 3.0), 0.0);
  };
  ndt.degraded = [](TimeNs t) { return to_seconds(t - kDriveStart) >= 3.0; };
  RsuModel rsu;
  const DriveResult r = drive(15.0, ndt, {rsu}, {}, kDriveStart + 3 * kNsPerSecond);
  std::printf("runaway NDT (0.5 m/s, flagged degraded): NDT MAE %.3f m, fused %.3f m\n", r.ndt_mae,
              r.fused_mae);
  EXPECT_GT(fixes_until_exclusion(r, 1), 0);
  EXPECT_GT(r.fused_mae, 0.5 * r.ndt_mae);
}

// While NDT is degraded its (inflated) estimate is still a reference for gross errors: an RSU 10 m off
// is excluded, and never fused.
TEST(IntegrityMonitor, ADegradedOwnEstimateStillCatchesGrossFaults) {
  NdtModel ndt;
  ndt.degraded = [](TimeNs t) { return t >= kDriveStart + 2 * kNsPerSecond; };
  RsuModel rsu;
  rsu.from = kDriveStart + 3 * kNsPerSecond;
  rsu.error = [](TimeNs) { return Eigen::Vector2d(10.0, 0.0); };
  const DriveResult r = drive(10.0, ndt, {rsu});
  EXPECT_EQ(fixes_until_exclusion(r, 1), 2);
  for (const FixRecord& f : r.fixes) {
    EXPECT_FALSE(fused(f));
  }
}

// The handover region: RSU 2 comes into view while RSU 1 is admitted. Alone, RSU 2 would have to show
// five fixes consistent with the own estimate; RSU 1 vouches for it: three fixes in a row that agree
// with RSU 1 (and disagree with no admitted RSU) admit it.
TEST(IntegrityMonitor, AnAdmittedRsuVouchesForANewOne) {
  NdtModel ndt;
  RsuModel first;
  RsuModel second;
  second.rsu_id = 2;
  second.seed = 3;
  second.from = kDriveStart + 4 * kNsPerSecond;
  const auto admitted_at = [](const DriveResult& r) {
    int fixes = 0;
    for (const FixRecord& f : r.fixes) {
      if (f.rsu_id == 2 && (++fixes, f.step.check->admitted_now))
        return fixes;
    }
    return -1;
  };
  const DriveResult both = drive(8.0, ndt, {first, second});
  const DriveResult alone = drive(8.0, ndt, {second});
  EXPECT_EQ(fixes_until_exclusion(both, 1), -1);
  EXPECT_EQ(admitted_at(both), 3);
  EXPECT_EQ(admitted_at(alone), 5);
  EXPECT_GT(both.fixes.size(), 0U);
}

// Two gross fixes in a row exclude a source even where both covariances are wide: the LiDAR at 5 m (the
// fault table) sent fixes 1.5 m and 3.6 m off along the road, 0.2 s apart, claiming 0.34 m there while
// the own estimate was degraded (0.32 m along, 0.26 m across). The test computes each fix's NIS itself
// (3 dof, diagonal: the residual over both variances): the first stays within the per-fix gate, the
// second is far beyond it. One gross fix alone, or after a fix only mildly off, still costs the RSU
// nothing.
TEST(IntegrityMonitor, TwoGrossFixesInARowExcludeEvenWithWideCovariances) {
  const IntegrityConfig config;
  const double own_along = 0.32, own_across = 0.26, own_yaw = 0.02;
  const double fix_along = 0.34, fix_across = 0.15, fix_yaw = 0.02;
  const auto expected_nis = [&](double along_m) {
    return along_m * along_m / (own_along * own_along + fix_along * fix_along);
  };
  const auto run = [&](const std::vector<double>& offsets_along_m) {
    IntegrityMonitor monitor(config);
    std::vector<FixCheck> checks;
    for (std::size_t k = 0; k < offsets_along_m.size(); ++k) {
      const TimeNs t = kDriveStart + static_cast<TimeNs>(k) * 2 * kStep;  // 0.2 s apart, as measured
      fusion::StateEstimate own;
      own.time = t;
      own.state(fusion::kX) = truth_at(t).x();
      own.state(fusion::kY) = truth_at(t).y();
      own.covariance.topLeftCorner<3, 3>() =
          Eigen::Vector3d(own_along * own_along, own_across * own_across, own_yaw * own_yaw).asDiagonal();
      v2i::Correction fix;
      fix.rsu_id = 1;
      fix.sweep_time = t;
      fix.pose = {truth_at(t).x() + offsets_along_m[k], truth_at(t).y(), 0.0};
      fix.pose_covariance =
          Eigen::Vector3d(fix_along * fix_along, fix_across * fix_across, fix_yaw * fix_yaw).asDiagonal();
      checks.push_back(monitor.check(fix, own, OwnEstimate::kDegraded, Eigen::Vector2d::Zero()));
      EXPECT_NEAR(checks.back().nis, expected_nis(offsets_along_m[k]), 1e-9) << k;
    }
    return checks;
  };
  const auto excluded_at = [](const std::vector<FixCheck>& checks) {
    for (std::size_t k = 0; k < checks.size(); ++k) {
      if (checks[k].excluded_now)
        return static_cast<int>(k);
    }
    return -1;
  };
  const std::vector<double> honest(6, 0.0);  // admitted after five consistent fixes
  auto sequence = [&](std::vector<double> tail) {
    std::vector<double> all = honest;
    all.insert(all.end(), tail.begin(), tail.end());
    all.insert(all.end(), 4, 0.0);
    return all;
  };
  // The measured pair: its first fix within the per-fix gate, so the fused filter's own gate (not the
  // monitor) refused it; the second far beyond; with each counted at most cusum_cap, short of the
  // threshold.
  ASSERT_LT(expected_nis(1.5), config.fix_gate_chi2);
  ASSERT_GT(expected_nis(1.5), config.suspicious_fix_chi2);
  ASSERT_GT(expected_nis(3.6), config.fix_gate_chi2);
  ASSERT_LT(expected_nis(1.5) - config.cusum_drift + config.cusum_cap - config.cusum_drift,
            config.cusum_threshold);
  const auto pair = run(sequence({1.5, 3.6}));
  EXPECT_EQ(excluded_at(pair), 7);  // at the second of the two
  EXPECT_EQ(pair[6].verdict, FixVerdict::kUseOwnFailed);
  EXPECT_EQ(pair[7].verdict, FixVerdict::kExcluded);
  // One gross fix alone (an L-shape failure), or after one only mildly off (0.9 m: NIS below the
  // 97.5 % quantile), is refused without excluding the RSU.
  ASSERT_LT(expected_nis(0.9), config.suspicious_fix_chi2);
  EXPECT_EQ(excluded_at(run(sequence({3.6}))), -1);
  EXPECT_EQ(excluded_at(run(sequence({0.9, 3.6}))), -1);
  // Two fixes both 1.5 m off are suspicious, not gross: not excluded by this pair.
  EXPECT_EQ(excluded_at(run(sequence({1.5, 1.5}))), -1);
}

// A flood of RSU ids (each a new source) keeps at most max_sources records.
TEST(IntegrityMonitor, RemembersAtMostMaxSources) {
  IntegrityConfig config;
  config.max_sources = 8;
  IntegrityMonitor monitor(config);
  fusion::StateEstimate own;
  own.covariance = fusion::StateMatrix::Identity() * 0.01;
  for (std::uint64_t id = 1; id <= 100; ++id) {
    v2i::Correction fix;
    fix.rsu_id = id;
    fix.sweep_time = kDriveStart + static_cast<TimeNs>(id) * kStep;
    fix.pose_covariance = diagonal(0.05, 0.015);
    monitor.check(fix, own, OwnEstimate::kHealthy, Eigen::Vector2d::Zero());
    EXPECT_LE(monitor.sources().size(), 8U);
  }
  EXPECT_EQ(monitor.sources().count(100), 1U);  // the newest is kept, the least recently heard go
  EXPECT_EQ(monitor.sources().count(1), 0U);
  EXPECT_EQ(monitor.totals().verdicts.count(FixVerdict::kProbation), 100U);
}

}  // namespace
}  // namespace rsu::vehicle
