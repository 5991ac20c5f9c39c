// SPDX-License-Identifier: Apache-2.0
#include "core/prepared_fixes.h"

#include <algorithm>
#include <bit>
#include <cstdint>
#include <cstring>

#include "core/rsu_core.h"
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

bool same_held(const HeldVehicle& a, const HeldVehicle& b) {
  return a.vehicle_id == b.vehicle_id && same_bits(a.points, b.points) && a.first_time == b.first_time &&
         a.weighted_offset == b.weighted_offset && a.parts == b.parts &&
         a.assigned_begin == b.assigned_begin && a.assigned_size == b.assigned_size &&
         a.assigned_time == b.assigned_time && same_bits(a.assigned_distance_sq, b.assigned_distance_sq) &&
         a.assigned_own == b.assigned_own && a.gathered_own == b.gathered_own &&
         a.after_assigned_release == b.after_assigned_release && a.far == b.far;
  // Not release_at: when it is released, not what; the fix does not read it.
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

void PreparedFixes::add_fit(std::vector<lidar::LidarPoint>&& points, perception::Detection detection) {
  if (fits_.size() == kKept)
    fits_.erase(fits_.begin());
  fits_.emplace_back(std::move(points), std::move(detection));
}

perception::Detection PreparedFixes::fit(std::span<const lidar::LidarPoint> points,
                                         const Eigen::Vector2d& lidar_xy,
                                         const perception::LShapeFitConfig& config,
                                         const perception::FitThinning& thinning) {
  const auto it = std::find_if(fits_.begin(), fits_.end(), [&](const auto& fit) {
    return std::equal(fit.first.begin(), fit.first.end(), points.begin(), points.end(), same_point);
  });
  if (it == fits_.end())
    return perception::detect(points, lidar_xy, config, thinning);
  perception::Detection d = std::move(it->second);
  fits_.erase(it);
  return d;
}

void PreparedFixes::add(const HeldVehicle& held, const v2i::VehicleAnnouncement& a, bool lost_nearby,
                        const std::vector<Eigen::Vector2d>& occluders, const GatheredFix& fix) {
  if (fixes_.size() == kKept)
    fixes_.erase(fixes_.begin());
  fixes_.push_back({held, a, lost_nearby, occluders, fix});
}

GatheredFix PreparedFixes::fix(const GatheredVehicleFixer& fixer, const HeldVehicle& held,
                               const v2i::VehicleAnnouncement& a, bool lost_nearby,
                               const std::vector<Eigen::Vector2d>& occluders, LidarStats& stats) {
  const auto it = std::find_if(fixes_.begin(), fixes_.end(), [&](const Entry& e) {
    return e.lost_nearby == lost_nearby && same_held(e.held, held) && same_announcement(e.announcement, a) &&
           same_bits(e.occluders, occluders);
  });
  if (it == fixes_.end())
    return fixer.fix(held, a, lost_nearby, occluders);
  ++stats.fixes_prepared_used;
  GatheredFix fix = std::move(it->fix);
  fixes_.erase(it);
  return fix;
}

// RsuCore's step that prepares them (file comment of prepared_fixes.h): each cluster every laser has swept
// past, fitted, and fixed as its release would do it now (association and gathering on a copy of the
// gatherer; counters untouched but fixes_prepared); and each vehicle the gatherer holds (one beyond
// GatheringConfig::hold_beyond_m until the sweep has passed its footprint) whenever it gains a part, so
// that its release finds the fix ready unless it gains another.
void RsuCore::prepare_fixes(TimeNs now) {
  std::vector<std::tuple<std::uint64_t, std::size_t, std::size_t>> held_now;
  for (const HeldVehicle& held : gatherer_.held()) {
    held_now.emplace_back(held.vehicle_id, held.parts, held.points.size());
    if (std::find(prepared_held_.begin(), prepared_held_.end(), held_now.back()) == prepared_held_.end())
      prepare_fix(held, now);
  }
  prepared_held_ = std::move(held_now);
  std::vector<perception::SweptCluster> swept = clusterer_.swept_open();
  if (swept.empty())
    return;
  std::vector<perception::Detection> detections;
  std::vector<Eigen::Vector3d> first_points;
  for (perception::SweptCluster& cluster : swept) {
    perception::Detection d =
        perception::detect(cluster.points, mount_.xy(), config_.perception.fix.fit, fixer_.fit_thinning());
    if (d.fit.ok() && (d.fit.center - mount_.xy()).norm() <= config_.coverage_radius_m && !d.points.empty()) {
      first_points.push_back(d.points.front());
      detections.push_back(d);
    }
    prepared_.add_fit(std::move(cluster.points), std::move(d));
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
      prepare_fix(held, now);
  }
}

void RsuCore::prepare_fix(const HeldVehicle& held, TimeNs now) {
  const v2i::RegisteredVehicle* vehicle = announcements_.registry().find(held.vehicle_id, now);
  if (vehicle == nullptr || held.points.empty())
    return;
  const bool lost_nearby = lost_near(held);
  const std::vector<Eigen::Vector2d> occluders = occluders_of(held);
  prepared_.add(held, vehicle->announcement, lost_nearby, occluders,
                fixer_.fix(held, vehicle->announcement, lost_nearby, occluders));
  ++lidar_stats_.fixes_prepared;
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
