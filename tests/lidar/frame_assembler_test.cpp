// SPDX-License-Identifier: Apache-2.0
// The assembler on simulated sensor streams: schedule -> encode -> decode -> assemble.
#include "lidar/frame_assembler.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>
#include <stdexcept>

#include "common/angles.h"
#include "lidar/velodyne_decoder.h"
#include "packet_stream.h"

namespace rsu::lidar {
namespace {

struct Segment {
  TimeNs t0 = 0;
  double start_deg = 0.0;
  TimeNs duration_ns = 0;
  double drop_fraction = 0.0;  // packets lost at random
  TimeNs lost_from_ns = 0;     // packets lost in [from, to) after t0
  TimeNs lost_to_ns = 0;
};

// Rotation number of a firing, from ground truth: the rotor angle at its time (600 rpm from the start
// angle) tells which turn the beam's wrapped azimuth belongs to.
std::int64_t rotation_of(const Segment& s, double cut_deg, TimeNs t, double azimuth_rad) {
  const double rotor = s.start_deg + 3600.0 * static_cast<double>(t - s.t0) * 1e-9;
  const double az = rad_to_deg(azimuth_rad);
  const double unwrapped = az + 360.0 * std::round((rotor - az) / 360.0);
  return static_cast<std::int64_t>(std::floor((unwrapped - cut_deg) / 360.0));
}

struct SegmentTruth {
  std::map<std::int64_t, std::size_t> points_per_rotation;  // points actually sent
  std::vector<std::int64_t> whole_rotations;                // swept from start cut to end cut
};

// Sends one segment's packets through the decoder into the assembler; returns what the test knows.
SegmentTruth send_segment(const SensorModel& model, const Segment& s, double cut_deg,
                          FrameAssembler& assembler, std::vector<LidarFrame>& frames, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const FiringSchedule schedule(model, s.t0, s.start_deg);
  VelodyneDecoder decoder(model);
  SegmentTruth truth;
  for (std::int64_t k = 0;; ++k) {
    const test::EncodedPacket packet = test::make_packet(schedule, k, rng, 0.0);
    const TimeNs start = packet.returns.blocks.first_firing_ns;
    if (start >= s.t0 + s.duration_ns) {
      break;
    }
    const bool lost =
        unit(rng) < s.drop_fraction || (start >= s.t0 + s.lost_from_ns && start < s.t0 + s.lost_to_ns);
    if (lost) {
      continue;
    }
    for (const Firing& f : packet.firings) {
      ++truth.points_per_rotation[rotation_of(s, cut_deg, f.time_ns, f.azimuth_rad)];
    }
    std::vector<LidarPoint> points;
    EXPECT_TRUE(decoder.decode(packet.bytes, start + kNsPerMs, points).is_data());
    for (LidarFrame& f : assembler.add(points)) {
      frames.push_back(std::move(f));
    }
  }
  // Whole rotations lie between the first cut after the start and the last cut before the end. The
  // scenarios keep every cut at least 20 deg from either end so that no margin decides the outcome.
  const double end_deg = s.start_deg + 3600.0 * static_cast<double>(s.duration_ns) * 1e-9;
  for (std::int64_t r = -2; r < 100; ++r) {
    const double from = cut_deg + 360.0 * static_cast<double>(r);
    const double to = from + 360.0;
    EXPECT_GT(std::abs(from - s.start_deg), 20.0) << "scenario too close to a cut";
    EXPECT_GT(std::abs(to - end_deg), 20.0) << "scenario too close to a cut";
    if (from > s.start_deg && to < end_deg) {
      truth.whole_rotations.push_back(r);
    }
  }
  return truth;
}

// Every frame holds exactly the points of one whole rotation that were sent, in order.
void expect_frames_match(const std::vector<LidarFrame>& frames, std::size_t first, const Segment& s,
                         double cut_deg, const SegmentTruth& truth) {
  ASSERT_GE(frames.size(), first + truth.whole_rotations.size());
  for (std::size_t i = 0; i < truth.whole_rotations.size(); ++i) {
    const std::int64_t r = truth.whole_rotations[i];
    const LidarFrame& frame = frames[first + i];
    EXPECT_EQ(frame.points.size(), truth.points_per_rotation.at(r)) << "rotation " << r;
    TimeNs lo = frame.points.front().time_ns;
    TimeNs hi = lo;
    for (const LidarPoint& p : frame.points) {
      ASSERT_EQ(rotation_of(s, cut_deg, p.time_ns, static_cast<double>(p.azimuth_rad)), r);
      lo = std::min(lo, p.time_ns);
      hi = std::max(hi, p.time_ns);
    }
    EXPECT_EQ(frame.start_ns, lo);
    EXPECT_EQ(frame.end_ns, hi);
  }
}

void check_full_rotations(const SensorModel& model, double cut_deg, double drop_fraction) {
  FrameAssemblerConfig config;
  config.cut_azimuth_deg = cut_deg;
  FrameAssembler assembler(config);
  std::vector<LidarFrame> frames;
  const Segment s{.t0 = 10 * kNsPerSecond + 777,
                  .start_deg = 90.0,
                  .duration_ns = 450 * kNsPerMs,
                  .drop_fraction = drop_fraction};
  const SegmentTruth truth = send_segment(model, s, cut_deg, assembler, frames, 11);
  for (LidarFrame& f : assembler.flush()) {
    frames.push_back(std::move(f));
  }
  ASSERT_EQ(frames.size(), truth.whole_rotations.size());
  expect_frames_match(frames, 0, s, cut_deg, truth);
  // A rotation is 0.1 s / 55.296 us = 1808.45 firing sequences of every laser.
  const double full = 0.1 / 55.296e-6 * static_cast<double>(model.laser_count());
  for (const LidarFrame& f : frames) {
    if (drop_fraction == 0.0) {
      EXPECT_NEAR(static_cast<double>(f.points.size()), full, 2.0 * static_cast<double>(model.laser_count()));
    } else {
      EXPECT_LT(static_cast<double>(f.points.size()), full - static_cast<double>(model.laser_count()));
      EXPECT_GT(static_cast<double>(f.points.size()), 0.85 * full);
    }
  }
  EXPECT_EQ(assembler.stats().frames_emitted, frames.size());
  EXPECT_EQ(assembler.stats().late_points, 0U);
  EXPECT_EQ(assembler.stats().restarts, 0U);
  EXPECT_EQ(assembler.stats().partial_frames_dropped, 2U);  // the first rotation and the unfinished last
}

TEST(LidarFrameAssembler, Vlp16FullRotations) {
  check_full_rotations(make_vlp16(), 0.0, 0.0);
}
TEST(LidarFrameAssembler, Vlp32cFullRotationsWithAzimuthOffsets) {
  check_full_rotations(make_vlp32c(), 0.0, 0.0);
}
TEST(LidarFrameAssembler, Vlp32cCutAt180) {
  check_full_rotations(make_vlp32c(), 180.0, 0.0);
}
TEST(LidarFrameAssembler, Vlp16LostPacketsKeepFrameCount) {
  check_full_rotations(make_vlp16(), 0.0, 0.05);
}
TEST(LidarFrameAssembler, Vlp32cLostPacketsKeepFrameCount) {
  check_full_rotations(make_vlp32c(), 0.0, 0.05);
}

TEST(LidarFrameAssembler, GapBelowTwoRotationsIsNotARestart) {
  // 150 ms (1.5 rotations) lost in the middle: the rotation count survives the gap.
  const SensorModel model = make_vlp16();
  FrameAssembler assembler;
  std::vector<LidarFrame> frames;
  const Segment s{.t0 = 0,
                  .start_deg = 90.0,
                  .duration_ns = 650 * kNsPerMs,
                  .lost_from_ns = 200 * kNsPerMs,
                  .lost_to_ns = 350 * kNsPerMs};
  const SegmentTruth truth = send_segment(model, s, 0.0, assembler, frames, 5);
  ASSERT_EQ(truth.whole_rotations.size(), 5U);
  ASSERT_EQ(frames.size(), 5U);
  expect_frames_match(frames, 0, s, 0.0, truth);
  EXPECT_EQ(assembler.stats().restarts, 0U);
}

void check_restart(TimeNs second_t0_after_first) {
  const SensorModel model = make_vlp16();
  FrameAssembler assembler;
  std::vector<LidarFrame> frames;
  const Segment first{.t0 = 100 * kNsPerSecond, .start_deg = 90.0, .duration_ns = 250 * kNsPerMs};
  const Segment second{
      .t0 = first.t0 + second_t0_after_first, .start_deg = 200.0, .duration_ns = 270 * kNsPerMs};
  const SegmentTruth truth1 = send_segment(model, first, 0.0, assembler, frames, 1);
  const std::size_t after_first = frames.size();
  const SegmentTruth truth2 = send_segment(model, second, 0.0, assembler, frames, 2);
  for (LidarFrame& f : assembler.flush()) {
    frames.push_back(std::move(f));
  }
  ASSERT_EQ(truth1.whole_rotations.size(), 1U);
  ASSERT_EQ(truth2.whole_rotations.size(), 2U);
  ASSERT_EQ(after_first, 1U);
  ASSERT_EQ(frames.size(), 3U);
  expect_frames_match(frames, 0, first, 0.0, truth1);
  expect_frames_match(frames, 1, second, 0.0, truth2);
  EXPECT_EQ(assembler.stats().restarts, 1U);
  // Partial: each segment's first rotation and its unfinished last one.
  EXPECT_EQ(assembler.stats().partial_frames_dropped, 4U);
}

TEST(LidarFrameAssembler, TimeGoingBackwardsRestarts) {
  check_restart(-50 * kNsPerSecond);
}
TEST(LidarFrameAssembler, GapAboveTwoRotationsRestarts) {
  check_restart(250 * kNsPerMs + 300 * kNsPerMs);
}

TEST(LidarFrameAssembler, EmitsPartialFramesWhenAsked) {
  FrameAssemblerConfig config;
  config.emit_partial_frames = true;
  FrameAssembler assembler(config);
  std::vector<LidarFrame> frames;
  const Segment s{.t0 = 0, .start_deg = 90.0, .duration_ns = 450 * kNsPerMs};
  const SegmentTruth truth = send_segment(make_vlp16(), s, 0.0, assembler, frames, 3);
  for (LidarFrame& f : assembler.flush()) {
    frames.push_back(std::move(f));
  }
  // The first rotation (from 90 deg) and the last (to 1710 deg) come too, with the points sent.
  ASSERT_EQ(frames.size(), truth.points_per_rotation.size());
  std::size_t i = 0;
  for (const auto& [rotation, count] : truth.points_per_rotation) {
    EXPECT_EQ(frames[i++].points.size(), count) << "rotation " << rotation;
  }
  EXPECT_EQ(assembler.stats().partial_frames_dropped, 0U);
}

TEST(LidarFrameAssembler, IgnoresPointsWithoutAzimuth) {
  FrameAssembler assembler;
  LidarPoint bad;
  bad.azimuth_rad = std::nanf("");
  const std::vector<LidarPoint> points(5, bad);
  EXPECT_TRUE(assembler.add(points).empty());
  EXPECT_TRUE(assembler.add({}).empty());
  EXPECT_TRUE(assembler.flush().empty());
  EXPECT_EQ(assembler.stats().invalid_points, 5U);
}

TEST(LidarFrameAssembler, RejectsBadConfig) {
  EXPECT_THROW(FrameAssembler(FrameAssemblerConfig{.rotation_hz = 0.0}), std::invalid_argument);
  EXPECT_THROW(FrameAssembler(FrameAssemblerConfig{.cut_azimuth_deg = std::nan("")}), std::invalid_argument);
  EXPECT_THROW(FrameAssembler(FrameAssemblerConfig{.max_gap_rotations = -1.0}), std::invalid_argument);
  EXPECT_THROW(FrameAssembler(FrameAssemblerConfig{.emit_margin_deg = 200.0}), std::invalid_argument);
}

}  // namespace
}  // namespace rsu::lidar
