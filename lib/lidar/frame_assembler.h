// SPDX-License-Identifier: Apache-2.0
// Cuts a stream of decoded points into rotations (docs/architecture.md).
//
// A frame holds the points whose beam azimuth lies in [cut, cut + 360 deg) of one rotation. Points
// arrive packet by packet in firing order. Beam azimuths are not monotonic within a packet (the
// VLP-32C's per-laser azimuth offsets span -4.2..+4.2 deg), so a frame stays open until the stream
// is `emit_margin_deg` past its end cut; only then can no later point belong to it.
//
// Each point's azimuth is unwrapped against the previous point's, advanced by the nominal rotation
// over the time between them, so lost packets (up to `max_gap_rotations`) do not confuse the
// rotation count: a frame then just has fewer points. Time going backwards, or a gap longer than
// `max_gap_rotations`, is a stream restart: the open frames are closed and counting starts over.
//
// A frame is whole when the stream was running before its start cut and went past its end cut.
// The first frame after a (re)start and frames closed by a restart or flush() are partial; by
// default they are dropped (and counted), as a partial rotation would, e.g., leave a hole in a
// background model.
#pragma once

#include <cstdint>
#include <deque>
#include <span>
#include <vector>

#include "common/time.h"
#include "lidar/point.h"

namespace rsu::lidar {

struct FrameAssemblerConfig {
  double cut_azimuth_deg = 0.0;      // Velodyne azimuth (clockwise from +x) where one frame ends
  double rotation_hz = 10.0;         // nominal spin rate (600 rpm), for unwrapping across gaps
  double max_gap_rotations = 2.0;    // a longer silence restarts the stream
  double emit_margin_deg = 10.0;     // must exceed the spread of per-laser azimuth offsets (8.4 deg)
  bool emit_partial_frames = false;  // also return partial frames (see file comment)
};

struct FrameAssemblerStats {
  std::uint64_t frames_emitted = 0;
  std::uint64_t partial_frames_dropped = 0;
  std::uint64_t restarts = 0;        // time went backwards or a gap > max_gap_rotations
  std::uint64_t late_points = 0;     // belonged to a frame already closed; dropped
  std::uint64_t invalid_points = 0;  // non-finite azimuth; dropped
};

class FrameAssembler {
 public:
  // Throws std::invalid_argument on a non-finite cut, non-positive rate or gap, or a margin outside
  // [0, 180) deg.
  explicit FrameAssembler(const FrameAssemblerConfig& config = {});

  // Feeds the next points (normally one packet's). Returns the frames completed by them, oldest first
  // (usually none or one).
  std::vector<LidarFrame> add(std::span<const LidarPoint> points);
  // End of stream: closes every open frame (partial) and forgets the stream.
  std::vector<LidarFrame> flush();
  // The spin rate as measured since (lidar_decoder.h: SweepGeometry::rotation_hz), for unwrapping
  // across gaps. Ignored unless finite and positive.
  void set_rotation_hz(double rotation_hz);

  const FrameAssemblerStats& stats() const { return stats_; }

 private:
  struct OpenFrame {
    std::int64_t index = 0;  // rotation number since the stream (re)started
    LidarFrame frame;
  };

  void start_stream(const LidarPoint& p);
  double unwrap(const LidarPoint& p) const;
  void append(std::int64_t index, const LidarPoint& p);
  void close_passed_frames(std::vector<LidarFrame>& done);
  void close_all(std::vector<LidarFrame>& done);
  void finish(OpenFrame&& open, bool whole, std::vector<LidarFrame>& done);

  FrameAssemblerConfig config_;
  std::size_t largest_emitted_ = 0;  // points of the largest frame emitted: a new frame's reserve
  double cut_rad_;
  double margin_rad_;
  TimeNs max_gap_ns_;
  FrameAssemblerStats stats_;

  bool running_ = false;
  double first_u_ = 0.0;  // unwrapped azimuth past the cut of the stream's first point, radians
  double last_u_ = 0.0;
  double max_u_ = 0.0;
  TimeNs last_time_ns_ = 0;
  std::int64_t first_open_index_ = 0;  // frames below this index are closed
  std::deque<OpenFrame> open_;         // ascending index
};

}  // namespace rsu::lidar
