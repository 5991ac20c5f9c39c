// SPDX-License-Identifier: Apache-2.0
#include "core/lidar_stats.h"

#include "common/angles.h"

namespace rsu::core {

void report(const lidar::PacketOrderStats& o, const perception::SweepClustererStats& s, const LidarStats& l,
            CounterList& out) {
  out.add("packet", "released", o.released);  // into perception, in time order
  out.add("packet", "lost", o.lost);
  out.add("packet", "reordered", o.reordered);
  out.add("packet", "late_dropped", o.late);
  out.add("packet", "duplicate", o.duplicate);
  out.add("packet", "stream_gaps", o.stream_gaps);
  out.add("packet", "too_late", l.packets_too_late);
  out.add("packet", "clock_offset", l.packets_clock_offset);
  out.add("sweep", "foreground_points", s.foreground_points);
  out.add("sweep", "clusters_released", s.clusters_released);
  out.add("sweep", "clusters_released_open", s.clusters_released_open);
  out.add("sweep", "clusters_dropped_small", s.clusters_dropped_small);
  out.add("sweep", "clusters_dropped_large", s.clusters_dropped_large);
  out.add("sweep", "clusters_dropped_cut_at_start", s.clusters_dropped_cut_at_start);
  out.add("sweep", "points_dropped_stale", s.points_dropped_stale);
  out.add("sweep", "points_dropped_overflow", s.points_dropped_overflow);
  out.add("sweep", "points_dropped_restart", s.points_dropped_restart);
  out.add("sweep", "invalid_points", s.invalid_points);
  out.add("sweep", "restarts", s.restarts);
  out.add("lidar", "background_frames", l.background_frames);
  out.add("lidar", "fits_failed", l.fits_failed);
  out.add("lidar", "clusters_out_of_coverage", l.clusters_out_of_coverage);
  out.add("lidar", "clusters_unmatched", l.clusters_unmatched);
  out.add("lidar", "fragments_merged", l.fragments_merged);
  out.add("lidar", "corrections_failed", l.corrections_failed);
  out.add("lidar", "corrections_inconsistent", l.corrections_inconsistent);
  out.add("lidar", "corrections_unassigned", l.corrections_unassigned);
  out.add("lidar", "corrections_encode_failed", l.corrections_encode_failed);
  out.add("lidar", "corrections", l.corrections);
  out.add("lidar", "corrections_withheld_mount", l.corrections_withheld_mount);
  out.add("lidar", "fixes_bounded_by_track", l.track_bounded);
  out.add("lidar", "fixes_tightened_by_track", l.track_tightened);
  out.add("lidar", "track_conflicts", l.track_conflicts);
  out.add("lidar", "track_resets", l.track_resets);
  out.add("lidar", "fixes_prepared", l.fixes_prepared);
  out.add("lidar", "fixes_prepared_used", l.fixes_prepared_used);
}

void report_mount(const calibration::MountMonitor* monitor, std::uint64_t rotations_gappy, CounterList& out) {
  const calibration::MountMonitorStats none;
  const calibration::MountMonitorStats& m = monitor != nullptr ? monitor->stats() : none;
  out.add("mount", "rotations_checked", m.rotations_checked);
  out.add("mount", "rotations_beyond_tolerance", m.rotations_beyond_tolerance);
  out.add("mount", "rotations_unobservable", m.rotations_unobservable);
  out.add("mount", "rotations_gappy", rotations_gappy);
  out.add("mount", "rotations_mismatched", m.rotations_mismatched);
  out.add("mount", "rotations_unverifiable", m.rotations_unverifiable);
  out.add("mount", "stops", m.stops);
  out.add("mount", "stops_unconfirmed", m.stops_unconfirmed);
  out.add("mount", "resumes", m.resumes);
  out.add_level("mount", "fixes_stopped", monitor != nullptr && !monitor->serving() ? 1 : 0);
  if (monitor == nullptr || m.rotations_checked == 0)
    return;
  const calibration::MountDrift& d = monitor->last();
  out.add_measured("mount", "error_at_radius_m", d.error_at_radius_m);
  out.add_measured("mount", "error_sigma_m", d.error_sigma_m);
  out.add_measured("mount", "motion_x_m", d.motion.x);
  out.add_measured("mount", "motion_y_m", d.motion.y);
  out.add_measured("mount", "motion_z_m", d.motion.z);
  out.add_measured("mount", "motion_roll_deg", rad_to_deg(d.motion.roll));
  out.add_measured("mount", "motion_pitch_deg", rad_to_deg(d.motion.pitch));
  out.add_measured("mount", "motion_yaw_deg", rad_to_deg(d.motion.yaw));
  out.add_measured("mount", "matched_points", static_cast<double>(d.matches));
}

}  // namespace rsu::core
