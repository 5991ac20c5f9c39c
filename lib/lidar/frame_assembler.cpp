// SPDX-License-Identifier: Apache-2.0
// Rotation assembly (see frame_assembler.h).
#include "lidar/frame_assembler.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "common/angles.h"

namespace rsu::lidar {
namespace {

constexpr double kTurn = 2.0 * kPi;

}  // namespace

FrameAssembler::FrameAssembler(const FrameAssemblerConfig& config) : config_(config) {
  if (!std::isfinite(config.cut_azimuth_deg)) {
    throw std::invalid_argument("FrameAssembler: cut azimuth must be finite");
  }
  if (!(config.rotation_hz > 0.0) || !std::isfinite(config.rotation_hz)) {
    throw std::invalid_argument("FrameAssembler: rotation_hz must be positive");
  }
  if (!(config.max_gap_rotations > 0.0) || !std::isfinite(config.max_gap_rotations)) {
    throw std::invalid_argument("FrameAssembler: max_gap_rotations must be positive");
  }
  if (!(config.emit_margin_deg >= 0.0 && config.emit_margin_deg < 180.0)) {
    throw std::invalid_argument("FrameAssembler: emit_margin_deg must be in [0, 180)");
  }
  cut_rad_ = deg_to_rad(config.cut_azimuth_deg);
  margin_rad_ = deg_to_rad(config.emit_margin_deg);
  max_gap_ns_ = from_seconds(std::min(config.max_gap_rotations / config.rotation_hz, 1e9));
}

void FrameAssembler::start_stream(const LidarPoint& p) {
  running_ = true;
  first_u_ = wrap_angle_positive(static_cast<double>(p.azimuth_rad) - cut_rad_);
  last_u_ = first_u_;
  max_u_ = first_u_;
  last_time_ns_ = p.time_ns;
  first_open_index_ = std::numeric_limits<std::int64_t>::min();
}

double FrameAssembler::unwrap(const LidarPoint& p) const {
  // Predict where the rotor is now, then take the azimuth nearest that prediction.
  const double predicted = last_u_ + kTurn * config_.rotation_hz * to_seconds(p.time_ns - last_time_ns_);
  return predicted + wrap_angle(static_cast<double>(p.azimuth_rad) - cut_rad_ - predicted);
}

void FrameAssembler::append(std::int64_t index, const LidarPoint& p) {
  auto it = open_.end();
  while (it != open_.begin() && std::prev(it)->index >= index) {
    --it;
  }
  if (it == open_.end() || it->index != index) {
    OpenFrame fresh;
    fresh.index = index;
    fresh.frame.start_ns = p.time_ns;
    fresh.frame.end_ns = p.time_ns;
    // Room for a rotation like the last one, taken at once: grown by doubling, a 128 x 2048 rotation's
    // last step copied 4 MB into memory touched for the first time, tens of milliseconds in one packet.
    fresh.frame.points.reserve(largest_emitted_);
    it = open_.insert(it, std::move(fresh));
  }
  LidarFrame& f = it->frame;
  f.start_ns = std::min(f.start_ns, p.time_ns);
  f.end_ns = std::max(f.end_ns, p.time_ns);
  f.points.push_back(p);
}

void FrameAssembler::finish(OpenFrame&& open, bool whole, std::vector<LidarFrame>& done) {
  first_open_index_ = std::max(first_open_index_, open.index + 1);
  if (whole || config_.emit_partial_frames) {
    ++stats_.frames_emitted;
    largest_emitted_ = std::max(largest_emitted_, open.frame.points.size());
    done.push_back(std::move(open.frame));
  } else {
    ++stats_.partial_frames_dropped;
  }
}

void FrameAssembler::close_passed_frames(std::vector<LidarFrame>& done) {
  while (!open_.empty()) {
    const auto index = static_cast<double>(open_.front().index);
    if ((index + 1.0) * kTurn + margin_rad_ > max_u_) {
      break;  // a later point may still fall before this frame's end cut
    }
    // Whole only if the stream began far enough before the start cut that every laser, whatever its
    // azimuth offset, had already swept past it.
    const bool whole = index * kTurn >= first_u_ + margin_rad_;
    OpenFrame open = std::move(open_.front());
    open_.pop_front();
    finish(std::move(open), whole, done);
  }
}

void FrameAssembler::close_all(std::vector<LidarFrame>& done) {
  while (!open_.empty()) {
    OpenFrame open = std::move(open_.front());
    open_.pop_front();
    finish(std::move(open), false, done);
  }
  running_ = false;
}

std::vector<LidarFrame> FrameAssembler::add(std::span<const LidarPoint> points) {
  std::vector<LidarFrame> done;
  for (const LidarPoint& p : points) {
    if (!std::isfinite(p.azimuth_rad)) {
      ++stats_.invalid_points;
      continue;
    }
    // Unsigned difference: no overflow whatever the (possibly garbage) times.
    if (running_ && (p.time_ns < last_time_ns_ ||
                     static_cast<std::uint64_t>(p.time_ns) - static_cast<std::uint64_t>(last_time_ns_) >
                         static_cast<std::uint64_t>(max_gap_ns_))) {
      ++stats_.restarts;
      close_all(done);
    }
    if (!running_) {
      start_stream(p);
    }
    const double u = unwrap(p);
    last_u_ = u;
    max_u_ = std::max(max_u_, u);
    last_time_ns_ = p.time_ns;
    const auto index = static_cast<std::int64_t>(std::floor(u / kTurn));
    if (index < first_open_index_) {
      ++stats_.late_points;
      continue;
    }
    append(index, p);
  }
  close_passed_frames(done);
  return done;
}

void FrameAssembler::set_rotation_hz(double rotation_hz) {
  if (!(rotation_hz > 0.0) || !std::isfinite(rotation_hz)) {
    return;
  }
  config_.rotation_hz = rotation_hz;
  max_gap_ns_ = from_seconds(std::min(config_.max_gap_rotations / rotation_hz, 1e9));
}

std::vector<LidarFrame> FrameAssembler::flush() {
  std::vector<LidarFrame> done;
  close_passed_frames(done);
  close_all(done);
  return done;
}

}  // namespace rsu::lidar
