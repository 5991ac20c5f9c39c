// SPDX-License-Identifier: Apache-2.0
// Everything RsuCore needs to know, as plain structs holding the defaults (KISS-ICP style). The daemon
// fills it from its YAML file (daemon/config.h); tests fill it by hand.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

#include "calibration/mount_monitor.h"
#include "common/angles.h"
#include "common/pose.h"
#include "common/time.h"
#include "lidar/lidar_decoder.h"
#include "lidar/packet_order.h"
#include "lidar/sensor_model.h"
#include "perception/pipeline.h"
#include "perception/sweep_clusterer.h"
#include "tracking/association.h"
#include "tracking/vehicle_hypothesis.h"
#include "v2i/announcement_validation.h"
#include "v2i/message_authenticator.h"
#include "v2i/security/ed25519.h"
#include "v2i/security/trust_list.h"
#include "v2i/source_rate_limiter.h"
#include "v2i/vehicle_registry.h"

namespace rsu::core {

// How background learning ends (docs/design.md §1: the static scene is removed before clustering).
struct BackgroundLearningConfig {
  // Whole rotations recorded at start-up, while no vehicle is expected in view, that train the model.
  // Ignored when the caller loads a background (e.g. PCD files) with RsuCore::load_background().
  int learning_frames = 10;
};

// How a matched vehicle's clusters are gathered before its fix (RsuCore, file comment of rsu_core.h).
// A vehicle far from the LiDAR and seen head-on breaks into fragments (bumper, cabin) more than the
// clustering tolerance apart, and the VLP-32C's per-laser azimuth offsets release them in different
// batches of the sweep; a fix from one fragment is metres off while it looks like a whole vehicle.
struct GatheringConfig {
  // The vehicle's predicted footprint (announced size, pose predicted to the sweep) is grown by this
  // many standard deviations of its predicted centre (largest axis) and of its yaw (at the corners).
  double footprint_sigmas = 2.5;
  // ... and by at least this much (the fit's own noise, shape departures), at most this much (a
  // vehicle with a lost estimate must not swallow its neighbours).
  double min_margin_m = 0.4;
  double max_margin_m = 2.0;
  // A cluster belongs to a vehicle when at least this fraction of its points lies in the grown footprint.
  double min_inside_fraction = 0.5;
  // Vehicles predicted farther than this are held until the sweep has passed their footprint, so that
  // fragments released in later batches join them (a head-on car splits where the hood falls between
  // rings, seen from 26 m on in the corridor); nearer ones are fixed at once.
  double hold_beyond_m = 25.0;
};

// Announcements other RSUs accepted from vehicles and shared on the data bus (RsuCore::
// on_peer_announcement; README, "Several RSUs on one bus").
struct PeerConfig {
  // Checked per origin RSU before decoding, as `datagram_flood` is per host: one RSU shares every
  // vehicle it hears at about 10 Hz each, so this carries ~100 vehicles per peer with a burst of one
  // second's worth, and a runaway peer costs one table lookup per sample.
  v2i::RateLimitConfig flood{.bucket = {.rate_per_s = 1000.0, .burst = 1000.0}, .max_sources = 256};
};

// Which clock the LiDAR's points are stamped on (README, "Sensor time").
enum class TimeSource {
  kSensor,       // the packets' own time: a real RSU synchronises its LiDAR to GNSS (PPS) or PTP
  kHostReceive,  // arrival on the host clock minus the packet's known duration (an unsynchronised sensor)
};

// What reply_to must be (docs/v2i.md): the datagram's source address and port (the default), its
// address only (vehicles that receive on another port than they send from), or ignored with the
// corrections sent to the datagram's source address and port (vehicles behind NAT, whose own idea of
// their address is not what the RSU sees).
enum class ReplyToPolicy : std::uint8_t { kMatchAddressAndPort, kMatchAddress, kUseSource };

// Notices that tell a vehicle why the RSU sends it nothing (core/refusal_notices.h: an announcement
// refused; core/withheld_notices.h: a fix withheld): at most one per vehicle per interval, and
// rate_per_s in all.
struct NoticeConfig {
  bool enabled = true;
  double per_vehicle_interval_s = 1.0;
  double rate_per_s = 50.0;

  bool operator==(const NoticeConfig&) const = default;
};

// How each vehicle's footprint is tracked over rotations (core/footprint_track.h).
struct FootprintTrackConfig {
  bool enabled = true;
  // The chain breaks when the vehicle's previous bound is older than this many rotations.
  double max_gap_rotations = 1.5;
  // Bounds on the error of the vehicle's motion between two sweeps (the announced speed's error, an
  // acceleration since the announcement, its heading's error), and a floor for the sweep's own smear
  // (the points' mean firing time stands for the whole vehicle).
  double speed_error_mps = 0.5;
  double speed_error_fraction = 0.05;
  double max_accel_mps2 = 4.0;
  double heading_error_rad = deg_to_rad(10.0);
  double motion_floor_m = 0.05;
  // A fix placed otherwise than in an interval bounds its centre within this many sigmas of its
  // length-axis variance, and never tighter than min_bound_half_m.
  double bound_sigmas = 3.0;
  double min_bound_half_m = 0.3;
  // The yaw may change between rotations by the announced yaw rate, plus this many combined sigmas of
  // the two fixes' yaw (at least min_yaw_jump_rad); more breaks the chain.
  double yaw_jump_sigmas = 3.0;
  double min_yaw_jump_rad = deg_to_rad(3.0);
};

struct RsuCoreConfig {
  std::uint64_t rsu_id = 1;

  // The LiDAR: its model, what else its decoder needs (calibration, metadata, returns used, rotation
  // start: lidar/lidar_decoder.h) and its surveyed pose in the map frame (sensor -> map).
  std::string sensor_model = "vlp16";
  lidar::LidarDecoderOptions sensor_options;
  Pose3 mount;

  BackgroundLearningConfig background;
  // Velodyne packets put back in time order (lidar/packet_order.h); lost and reordered ones counted.
  lidar::PacketOrderConfig packet_order;
  // A packet whose first firing is older than this when it is processed is dropped and counted
  // (packet.too_late): the RSU has fallen behind (overload, a stall) and sheds load to catch up. Fixes
  // that late are of little use, and worse, they would be associated with the vehicles' announcements
  // made since, predicted back over the lag: in a queue that picks the car behind (issue 7). 0: never.
  TimeNs max_packet_age = 150 * kNsPerMs;
  // The LiDAR's points: on its own clock or stamped by arrival (TimeSource). Either way the offset
  // between its clock and the host's is measured on every packet (lidar/sensor_clock.h).
  TimeSource time_source = TimeSource::kSensor;
  // With time_source kSensor, packets of a sensor whose clock is further than this from the host's
  // are refused and counted (packet.clock_offset): stamped on a clock that far off, their points
  // would be associated with the vehicles' announcements of another moment. The measured offset
  // includes the packets' transit (a millisecond on a direct link).
  TimeNs clock_tolerance = 100 * kNsPerMs;
  perception::SweepConfig sweep;  // when a cluster is released (perception/sweep_clusterer.h)
  // Fit and fix a cluster once every laser has swept past it, while the sweep still covers the angle
  // that decides it is closed, and use the result on its release when its inputs are the same bit for
  // bit (rsu_core.h, prepare_fixes): the corrections are the same, sent sooner. false: the baseline.
  bool prepare_fixes = true;
  // With prepare_fixes: a cluster not yet closed is released once its vehicle's prepared fix is ready and
  // every laser has swept past the fix's whole box grown by 3 sigma (prepared_fixes.h, "Released open"):
  // no return of that vehicle can still come, so a point that would still join the cluster within the
  // clustering tolerance is another object's, which the closed cluster would have mixed into the fix.
  // false: every cluster waits until it is closed.
  bool release_fixed_open = true;
  GatheringConfig gathering;
  // Each connected vehicle's footprint tracked over rotations: what earlier rotations bounded along its
  // length, carried by its own motion and intersected with the current one (core/footprint_track.h).
  FootprintTrackConfig footprint_track;
  // Background, clustering and the per-vehicle fix (perception::fix_vehicle): the library's defaults,
  // the same the pilot experiment measures, unless the configuration file changes them.
  perception::PerceptionConfig perception;

  // Is the LiDAR still where `mount` says? Each rotation registered against the background learned
  // under the mount; beyond the tolerance no fixes are sent until it is back (calibration/mount_monitor.h).
  calibration::MountMonitorConfig mount_monitor;

  // Clusters whose fitted centre is farther than this from the LiDAR get no correction: beyond it the
  // fit is too sparse to beat the vehicle's own estimate (paper Table 2: VLP-16 beyond 36 m).
  double coverage_radius_m = 50.0;
  // Verify on demand (v2i::VerificationRadius): an announcement claiming a place farther than the
  // coverage radius plus this from the LiDAR is neither verified nor registered. Its vehicle is in radio
  // range but out of sight, and there it costs no Ed25519 check (~50 us: 1000 vehicles at 10 Hz had taken
  // half a core). The margin covers a vehicle driving in (registered 1.6 s before it reaches coverage at
  // 30 m/s), a vehicle's own pose error far beyond the association gate's, and, on a bus of RSUs
  // (README, "Several RSUs on one bus"), a neighbour up to 50 m away: only announcements this RSU verified
  // are shared. None: verify every announcement.
  std::optional<double> verify_beyond_coverage_m = 50.0;

  // V2I: validation limits, registry (expiry, capacity, per-source rate), association gates.
  v2i::AnnouncementLimits announcement_limits;
  v2i::VehicleRegistryConfig registry;
  tracking::AssociationConfig association;
  tracking::HypothesisConfig hypothesis;
  // A cheap per-source-host limit applied to every datagram BEFORE decoding, so a flood of garbage
  // costs one table lookup per datagram. Looser than the registry's per-source announcement limit.
  v2i::RateLimitConfig datagram_flood{.bucket = {.rate_per_s = 200.0, .burst = 100.0}, .max_sources = 4096};
  // Where corrections go. By default only to the address and port the announcement came from:
  // otherwise anyone could aim the RSU's corrections at a third party (a reflection attack), or a
  // vehicle announcing from one port would miss corrections sent to another.
  ReplyToPolicy reply_to = ReplyToPolicy::kMatchAddressAndPort;
  // Telling a vehicle why its announcement was refused (core/refusal_notices.h).
  NoticeConfig refusal_notices;
  // Telling a vehicle the LiDAR swept why it gets no correction (core/withheld_notices.h). Each goes to
  // a registered vehicle at its checked reply_to (no one can aim them elsewhere), so the cap only bounds
  // what a crowded scene costs the RSU in signatures and sends: higher than the refusals', as every
  // vehicle in view may be owed one each second.
  NoticeConfig withheld_notices{.rate_per_s = 200.0};
  PeerConfig peers;

  // Message security (proto/v2i.proto): signed mode verifies every announcement against the trust list
  // (vehicle keys bound to their vehicle ids) and signs corrections and advertisements with the RSU's
  // key; insecure mode (local development only) neither signs nor verifies. The daemon reads the key
  // and the trust list from files (daemon/config.h).
  v2i::SecurityConfig security;
  std::optional<v2i::security::SigningKey> signing_key;  // required in signed mode
  v2i::security::TrustList trust_list;

  // For the RSU advertisement (v2i::RsuAdvertisement).
  std::uint16_t announcement_port = 0;
  std::uint16_t correction_port = 0;
};

}  // namespace rsu::core
