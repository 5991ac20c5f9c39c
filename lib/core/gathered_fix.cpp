// SPDX-License-Identifier: Apache-2.0
#include "core/gathered_fix.h"

#include <algorithm>
#include <cmath>

#include "common/angles.h"
#include "lidar/lidar_decoder.h"
#include "tracking/association.h"
#include "tracking/vehicle_hypothesis.h"

namespace rsu::core {

void count(const GatheredFix& f, LidarStats& stats) {
  stats.fragments_merged += f.fragments_merged;
  stats.clusters_unmatched += f.fragments_unmatched;
  if (f.outcome == GatheredFixOutcome::doubtful_cluster)
    ++stats.clusters_unmatched;
  else if (f.outcome == GatheredFixOutcome::out_of_coverage)
    ++stats.clusters_out_of_coverage;
  else if (f.outcome == GatheredFixOutcome::inconsistent)
    ++stats.corrections_inconsistent;
  else if (f.outcome == GatheredFixOutcome::no_assigned_cluster)
    ++stats.corrections_unassigned;
  else if (f.outcome == GatheredFixOutcome::track_conflict)
    return;  // counted by the footprint track (lidar.track_conflicts)
  else if (!f.ok())
    ++stats.corrections_failed;  // no assigned cluster, no rectangle, or the correction refused it
}

namespace {

// What the fix needs to know of the LiDAR: where it stands, the road's height, and its lasers'
// elevations and azimuth step from the tables its points are decoded with (an Ouster's from its metadata:
// before, an OS1-128 at 2048x10 was fixed as if 0.2 deg apart and every direction observed; a model without
// tables leaves every direction counted as observed: fewer, not wrong, bounds).
perception::LidarGeometry lidar_geometry(const RsuCoreConfig& config, const LidarMount& mount) {
  perception::LidarGeometry lidar;
  lidar.position = mount.position();
  lidar.ground_z = config.perception.ground.ground_z;
  if (const auto model = lidar::decoded_sensor_model(config.sensor_model, config.sensor_options)) {
    for (const double e : model->elevation_deg)
      lidar.elevations_rad.push_back(deg_to_rad(e));
    lidar.azimuth_step_rad = deg_to_rad(model->azimuth_step_deg());
  }
  return lidar;
}

}  // namespace

GatheredVehicleFixer::GatheredVehicleFixer(const RsuCoreConfig& config, const LidarMount& mount)
    : fix_config_(config.perception.fix),
      hypothesis_(config.hypothesis),
      association_(config.association),
      lidar_(lidar_geometry(config, mount)),
      lidar_xy_(mount.xy()),
      coverage_radius_m_(config.coverage_radius_m) {}

perception::Detection GatheredVehicleFixer::detect(std::span<const lidar::LidarPoint> points) const {
  return perception::detect(points, lidar_xy_, fix_config_.fit, {&lidar_, fix_config_.thin_above_points});
}

perception::VehicleFix GatheredVehicleFixer::fix_announced(std::span<const Eigen::Vector3d> points,
                                                           const perception::AzimuthThinning* thinning,
                                                           const v2i::VehicleAnnouncement& a,
                                                           TimeNs sweep_time,
                                                           const perception::LidarGeometry& lidar) const {
  // The yaw prior: the announced yaw carried to the sweep time with the announced motion (the
  // hypothesis model), with its grown uncertainty.
  const tracking::VehicleHypothesis at_sweep = tracking::predict_hypothesis(a, sweep_time, hypothesis_);
  const double yaw_var = at_sweep.covariance(2, 2);
  perception::AnnouncedVehicle vehicle;
  vehicle.size = {a.size.length_m, a.size.width_m, a.size.height_m};
  if (std::isfinite(at_sweep.yaw) && std::isfinite(yaw_var) && yaw_var >= 0.0) {
    vehicle.yaw_prior = perception::YawPrior{at_sweep.yaw, std::max(std::sqrt(yaw_var), 1e-3)};
  }
  // The detection's thinning was made with lidar_, whose position, lasers and azimuth step `lidar` shares.
  return thinning != nullptr ? perception::fix_vehicle(points, *thinning, vehicle, lidar, fix_config_)
                             : perception::fix_vehicle(points, vehicle, lidar, fix_config_);
}

bool GatheredVehicleFixer::fits_vehicle(const perception::RectangleFit& fit,
                                        const v2i::VehicleAnnouncement& a, TimeNs sweep_time) const {
  return tracking::check_pair(fit, tracking::predict_hypothesis(a, sweep_time, hypothesis_), association_)
             .verdict == tracking::PairGate::kPass;
}

GatheredFix GatheredVehicleFixer::fix(const HeldVehicle& held, const v2i::VehicleAnnouncement& a,
                                      bool lost_nearby, std::vector<Eigen::Vector2d> occluders,
                                      std::vector<perception::OcclusionQuery>* occlusion_queries) const {
  GatheredFix out;
  out.sweep_time = held.sweep_time();  // also for no fix: a notice names the rotation (withheld_notices.h)
  perception::LidarGeometry lidar = lidar_;
  lidar.complete_sweep = !lost_nearby;
  lidar.occluders = std::move(occluders);
  lidar.occlusion_log = occlusion_queries;
  // A near vehicle was held because its assigned detection lay outside its footprint (the gatherer);
  // if none of its own came while the sweep passed it, that one is more likely a neighbour's (its own
  // hidden, or its packets lost): no fix rather than someone else's.
  if (!held.far && held.assigned_size > 0 && !held.assigned_own) {
    out.outcome = GatheredFixOutcome::doubtful_cluster;
    return out;
  }
  // Every part was only gathered (it lay mostly inside the footprint grown by up to 2 m), none given to
  // this vehicle by the association's gate: unless each lay in its lane (the footprint grown across
  // it by the minimum margin and one sigma only), none is known to be this vehicle's rather than a
  // neighbour's, one part or several. Seen from 6 m up, an unconnected car 1.6 m beside a connected one
  // showed its top mostly inside the grown footprint, after the connected car's own cluster had been
  // assigned, fixed and refused earlier in the sweep: its place, 3.5 m off, went out as the connected car's
  // (README, "An elevated RSU"); at 4 m, so did the unconnected car queueing ahead of a connected one, in its
  // lane. So neither a part outside its lane nor one after its assigned detection was judged in this
  // rotation, nor when packets were lost near it (a loaded rsud at 2 m lost the connected car's own
  // packets and sent the car queueing ahead of it in its lane, 5.6 m off). A vehicle whose clock is
  // 0.8 s behind is predicted 2.4 m ahead, beyond the gate, while its own cluster still lies in its
  // lane: it is fixed from it.
  if (held.assigned_size == 0 && (!held.gathered_own || held.after_assigned_release || lost_nearby)) {
    out.fragments_unmatched = held.parts;
    out.outcome = GatheredFixOutcome::no_assigned_cluster;
    return out;
  }
  out.fix = fix_announced(held.points, held.thinning ? &*held.thinning : nullptr, a, out.sweep_time, lidar);
  if (held.parts > 1 && fits_vehicle(out.fix.fit, a, out.sweep_time)) {
    out.fragments_merged = held.parts - 1;
  } else if (held.parts > 1 && held.assigned_size == 0) {
    out.fragments_unmatched = held.parts;  // several parts, none assigned, not one vehicle
    out.outcome = GatheredFixOutcome::no_assigned_cluster;
    return out;
  } else if (held.parts > 1) {
    // The union is not one vehicle of this size (something else was inside the footprint): the
    // detection the assignment chose, alone; the correction's consistency check guards it.
    out.fragments_unmatched = held.parts - 1;
    out.sweep_time = held.assigned_time;
    out.fix = fix_announced(held.assigned_points(), nullptr, a, out.sweep_time, lidar);
  }
  if (!out.fix.fit.ok())
    out.outcome = GatheredFixOutcome::fit_failed;
  else if ((out.fix.fit.center - lidar_.xy()).norm() > coverage_radius_m_)
    out.outcome = GatheredFixOutcome::out_of_coverage;
  else if (out.fix.status() == perception::CorrectionStatus::inconsistent_box)
    out.outcome = GatheredFixOutcome::inconsistent;
  else
    out.outcome = out.fix.ok() ? GatheredFixOutcome::fixed : GatheredFixOutcome::correction_failed;
  return out;
}

}  // namespace rsu::core
