// SPDX-License-Identifier: Apache-2.0
#include "core/prepared_fixes.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>

#include "core/rsu_core.h"
#include "lidar/point_eigen.h"
#include "tracking/association.h"

namespace rsu::core {

namespace {

// Bit for bit (doubles too: -0 and 0 differ, a NaN matches itself), so that equal inputs give equal fixes.
bool same_bits(const double* a, const double* b, std::size_t n) {
  return std::memcmp(a, b, n * sizeof(double)) == 0;
}

bool same_bits(double a, double b) {
  return same_bits(&a, &b, 1);
}

// Eigen's fixed-size vectors and matrices are their doubles, without padding.
template <class M>
bool same_bits(const Eigen::MatrixBase<M>& a, const Eigen::MatrixBase<M>& b) {
  static_assert(sizeof(typename M::PlainObject) == M::SizeAtCompileTime * sizeof(double));
  return same_bits(a.derived().data(), b.derived().data(), static_cast<std::size_t>(M::SizeAtCompileTime));
}

template <class M>
bool same_bits(const std::vector<M>& a, const std::vector<M>& b) {
  static_assert(sizeof(M) == M::SizeAtCompileTime * sizeof(double));
  return a.size() == b.size() &&
         (a.empty() || same_bits(a.front().data(), b.front().data(), a.size() * M::SizeAtCompileTime));
}

bool same_point(const lidar::LidarPoint& a, const lidar::LidarPoint& b) {
  const auto bits = [](float v) { return std::bit_cast<std::uint32_t>(v); };
  return bits(a.x) == bits(b.x) && bits(a.y) == bits(b.y) && bits(a.z) == bits(b.z) &&
         bits(a.intensity) == bits(b.intensity) && a.ring == b.ring && a.echo == b.echo &&
         bits(a.azimuth_rad) == bits(b.azimuth_rad) && a.time_ns == b.time_ns;
}

// What GatheredVehicleFixer::fix reads of a held vehicle.
bool same_held(const HeldVehicle& a, const HeldVehicle& b) {
  return a.vehicle_id == b.vehicle_id && same_bits(a.points, b.points) && a.first_time == b.first_time &&
         a.weighted_offset == b.weighted_offset && a.parts == b.parts &&
         a.assigned_begin == b.assigned_begin && a.assigned_size == b.assigned_size &&
         a.assigned_time == b.assigned_time && a.assigned_own == b.assigned_own &&
         a.gathered_own == b.gathered_own && a.after_assigned_release == b.after_assigned_release &&
         a.far == b.far;
  // Not release_at, ahead_of_open or assigned_distance_sq: when and why it is released, and how near its
  // prediction the assigned detection lay (which moves with the other detections of the release's batch:
  // the prediction is to their median time), not what it is fixed from.
}

bool same_announcement(const v2i::VehicleAnnouncement& a, const v2i::VehicleAnnouncement& b) {
  const auto same_optional = [](const std::optional<double>& x, const std::optional<double>& y) {
    return x.has_value() == y.has_value() && (!x || same_bits(*x, *y));
  };
  return a.protocol_version == b.protocol_version && a.vehicle_id == b.vehicle_id &&
         a.sequence == b.sequence && a.generation_time == b.generation_time &&
         same_bits(a.size.length_m, b.size.length_m) && same_bits(a.size.width_m, b.size.width_m) &&
         same_bits(a.size.height_m, b.size.height_m) && same_bits(a.reference_offset, b.reference_offset) &&
         same_bits(a.pose.x, b.pose.x) && same_bits(a.pose.y, b.pose.y) &&
         same_bits(a.pose.yaw, b.pose.yaw) && same_bits(a.pose_covariance, b.pose_covariance) &&
         same_optional(a.speed_mps, b.speed_mps) && same_optional(a.yaw_rate_rps, b.yaw_rate_rps) &&
         a.reply_to.address == b.reply_to.address && a.reply_to.port == b.reply_to.port;
}

}  // namespace

Prepared prepare(Preparation preparation) {
  Prepared out;
  out.fixer = std::move(preparation.fixer);
  out.step_time = preparation.step_time;
  for (FixInputs& in : preparation.vehicles) {
    PreparedFix prepared;
    prepared.fix =
        out.fixer->fix(in.held, in.announcement, in.lost_nearby, in.occluders, &prepared.occlusion_queries);
    prepared.inputs = std::move(in);
    out.fixes.push_back(std::move(prepared));
  }
  for (std::vector<lidar::LidarPoint>& points : preparation.clusters) {
    perception::Detection d = out.fixer->detect(points);
    out.fits.emplace_back(std::move(points), std::move(d));
  }
  return out;
}

std::array<Eigen::Vector2d, 4> grown_box_outline(const perception::CorrectedPose& fix, double length_m,
                                                 double width_m) {
  const double half_length = 0.5 * length_m;
  const double half_width = 0.5 * width_m;
  const double yaw_sigma = std::sqrt(std::max(0.0, fix.covariance(2, 2)));
  const double grow =
      3.0 * std::hypot(perception::position_sigma_m(fix), yaw_sigma * std::hypot(half_length, half_width));
  const Eigen::Vector2d along(std::cos(fix.pose.yaw), std::sin(fix.pose.yaw));
  const Eigen::Vector2d across(-along.y(), along.x());
  const Eigen::Vector2d centre(fix.pose.x, fix.pose.y);
  const Eigen::Vector2d l = (half_length + grow) * along;
  const Eigen::Vector2d w = (half_width + grow) * across;
  return {centre + l + w, centre + l - w, centre - l - w, centre - l + w};
}

void PreparedFixes::add_fit(std::vector<lidar::LidarPoint>&& points, perception::Detection detection) {
  if (fits_.size() == kKept)
    fits_.erase(fits_.begin());
  fits_.emplace_back(std::move(points), std::move(detection));
}

perception::Detection PreparedFixes::fit(std::span<const lidar::LidarPoint> points,
                                         const GatheredVehicleFixer& fixer) {
  const auto it = std::find_if(fits_.begin(), fits_.end(), [&](const auto& fit) {
    return std::equal(fit.first.begin(), fit.first.end(), points.begin(), points.end(), same_point);
  });
  if (it == fits_.end())
    return fixer.detect(points);
  perception::Detection d = std::move(it->second);
  fits_.erase(it);
  return d;
}

void PreparedFixes::add(PreparedFix&& fix) {
  if (fixes_.size() == kKept)
    fixes_.erase(fixes_.begin());
  fixes_.push_back(std::move(fix));
}

GatheredFix PreparedFixes::fix(const GatheredVehicleFixer& fixer, const HeldVehicle& held,
                               const v2i::VehicleAnnouncement& a, bool lost_nearby,
                               const std::vector<Eigen::Vector2d>& occluders, LidarStats& stats) {
  const auto it = std::find_if(fixes_.begin(), fixes_.end(), [&](const PreparedFix& e) {
    return e.inputs.lost_nearby == lost_nearby && same_held(e.inputs.held, held) &&
           same_announcement(e.inputs.announcement, a) &&
           (same_bits(e.inputs.occluders, occluders) || fixer.answers_alike(occluders, e.occlusion_queries));
  });
  if (it == fixes_.end())
    return fixer.fix(held, a, lost_nearby, occluders);
  ++stats.fixes_prepared_used;
  GatheredFix fix = std::move(it->fix);
  fixes_.erase(it);
  return fix;
}

// RsuCore's half of the preparation (file comment of prepared_fixes.h). What to prepare: each cluster
// every laser has swept past, to fit; each vehicle the gatherer holds (one beyond
// GatheringConfig::hold_beyond_m until the sweep has passed its footprint) whenever it gains a part, so
// that its release finds the fix ready unless it gains another; and the vehicles that the fits recorded
// since would release (record_prepared).
Preparation RsuCore::take_preparation() {
  Preparation p;
  p.fixer = fixer_;
  p.vehicles = std::move(chained_);
  chained_.clear();
  if (!prepare_due_)
    return p;
  const TimeNs now = *prepare_due_;
  prepare_due_.reset();
  p.step_time = now;
  std::vector<std::tuple<std::uint64_t, std::size_t, std::size_t>> held_now;
  for (const HeldVehicle& held : gatherer_.held()) {
    held_now.emplace_back(held.vehicle_id, held.parts, held.points.size());
    if (std::find(prepared_held_.begin(), prepared_held_.end(), held_now.back()) == prepared_held_.end())
      add_fix_inputs(held, now, p.vehicles);
  }
  prepared_held_ = std::move(held_now);
  for (perception::SweptCluster& cluster : clusterer_.swept_open()) {
    if (config_.release_fixed_open) {
      if (open_handed_.size() == kOpenKept)
        open_handed_.erase(open_handed_.begin());
      open_handed_.emplace_back(perception::OpenClusterName{cluster.id, cluster.points.size()},
                                lidar::position_of(cluster.points.front()));
    }
    p.clusters.push_back(std::move(cluster.points));
  }
  return p;
}

// A prepared fix that sends a correction, of a vehicle gathered with a cluster handed out open: that
// cluster may be released open once the sweep has passed the fix's grown box (grown_box_outline).
void RsuCore::note_fixed_open(const PreparedFix& prepared) {
  if (!config_.release_fixed_open || !prepared.fix.ok())
    return;
  const std::vector<Eigen::Vector3d>& points = prepared.inputs.held.points;
  const v2i::BoxSize& size = prepared.inputs.announcement.size;
  for (const auto& [name, first] : open_handed_) {
    if (std::find(points.begin(), points.end(), first) == points.end())
      continue;
    if (fixed_open_.size() == kOpenKept)
      fixed_open_.erase(fixed_open_.begin());
    fixed_open_.push_back({name, grown_box_outline(prepared.fix.fix.corrected, size.length_m, size.width_m)});
  }
}

// The open clusters whose fixed box the sweep has passed (note_fixed_open), to release with the closed.
std::vector<perception::OpenClusterName> RsuCore::fixed_open_swept() const {
  std::vector<perception::OpenClusterName> out;
  for (const FixedOpenCluster& f : fixed_open_) {
    if (sweep_.swept(f.outline))
      out.push_back(f.name);
  }
  return out;
}

// What was prepared, kept for the releases; each fitted cluster is also associated and gathered as its
// release would do it now (on a copy of the gatherer; counters untouched), and the vehicles it would
// release fixed next (chained_, handed out by take_preparation).
void RsuCore::record_prepared(Prepared&& prepared) {
  const TimeNs now = prepared.step_time;
  if (prepared.fixer != fixer_)
    return;  // a reload replaced the fixer since: these may differ from what it computes
  for (PreparedFix& fix : prepared.fixes) {
    note_fixed_open(fix);
    prepared_.add(std::move(fix));
    ++lidar_stats_.fixes_prepared;
  }
  std::vector<perception::Detection> detections;
  std::vector<Eigen::Vector3d> first_points;
  for (auto& [points, d] : prepared.fits) {
    if (d.fit.ok() && (d.fit.center - mount_.xy()).norm() <= config_.coverage_radius_m && !d.points.empty()) {
      first_points.push_back(d.points.front());
      detections.push_back(d);
    }
    prepared_.add_fit(std::move(points), std::move(d));
  }
  if (detections.empty())
    return;
  const std::uint64_t offered = lidar_stats_.vehicles_in_batches;
  const std::vector<tracking::VehicleHypothesis> vehicles = predict_announced(detections, now);
  lidar_stats_.vehicles_in_batches = offered;
  if (vehicles.empty())
    return;
  const tracking::AssociationResult pairs = tracking::associate(detections, vehicles, config_.association);
  VehicleGatherer gatherer = gatherer_;
  gatherer.gather(std::move(detections), vehicles, pairs, sweep_);
  for (const HeldVehicle& held : gatherer.release(true, sweep_)) {
    const bool prepared_here =
        std::any_of(first_points.begin(), first_points.end(), [&](const Eigen::Vector3d& p) {
          return std::find(held.points.begin(), held.points.end(), p) != held.points.end();
        });
    if (prepared_here)
      add_fix_inputs(held, now, chained_);
  }
}

void RsuCore::add_fix_inputs(const HeldVehicle& held, TimeNs now, std::vector<FixInputs>& out) {
  const v2i::RegisteredVehicle* vehicle = announcements_.registry().find(held.vehicle_id, now);
  if (vehicle == nullptr || held.points.empty())
    return;
  out.push_back({held, vehicle->announcement, lost_near(held), occluders_of(held)});
}

// A cluster released ahead of a nearer one still open in its line of sight: what of that one the sweep
// has passed may hide part of it (perception::SweepClusterer::overtaken_open_points).
std::vector<Eigen::Vector2d> RsuCore::occluders_of(const HeldVehicle& held) {
  if (!unfinished_current_) {
    occluders_.set_unfinished(clusterer_.overtaken_open_points());
    unfinished_current_ = true;
  }
  return occluders_.of(held);
}

bool RsuCore::lost_near(const HeldVehicle& held) const {
  return last_loss_ns_ >= held.first_time - sweep_.rotation_period_ns() / 8;
}

}  // namespace rsu::core
