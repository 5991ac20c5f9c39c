// SPDX-License-Identifier: Apache-2.0
// The RSU's whole decision logic, pure (no sockets, threads, clocks or files: docs/architecture.md):
// the daemon hands it datagrams and LiDAR data with the time they arrived and sends what it returns.
// Tests drive it with hand-stepped time, so everything the daemon decides is tested here in
// microseconds. It orchestrates; each step is its own part:
//
//   announcements -> AnnouncementIntake (rate limit, authentication, decoding, validation, registry)
//   LiDAR packets -> PacketIntake (decoder, reorder, shedding) -> LidarMount (map frame)
//       while learning: whole rotations train the background model (or load_background())
//       then, batch by batch as the sweep passes (RsuCore::process, the map of the daemon):
//       foreground -> clusters (perception::SweepClusterer) -> fit (perception::detect) -> predict the
//       announced vehicles -> associate (tracking::associate) -> gather (VehicleGatherer) -> fix
//       (GatheredVehicleFixer: perception::fix_vehicle) -> correction (CorrectionBuilder)
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "calibration/mount_monitor.h"
#include "common/time.h"
#include "core/announcement_intake.h"
#include "core/correction_builder.h"
#include "core/datagram_outcome.h"
#include "core/footprint_track.h"
#include "core/gathered_fix.h"
#include "core/lidar_mount.h"
#include "core/lidar_stats.h"
#include "core/packet_intake.h"
#include "core/prepared_fixes.h"
#include "core/refusal_notices.h"
#include "core/rsu_core_config.h"
#include "core/sweep_occluders.h"
#include "core/sweep_position.h"
#include "core/vehicle_gatherer.h"
#include "core/withheld_notices.h"
#include "lidar/frame_assembler.h"
#include "lidar/lidar_decoder.h"
#include "lidar/packet_order.h"
#include "lidar/point.h"
#include "perception/background_model.h"
#include "perception/detection.h"
#include "perception/sweep_clusterer.h"
#include "tracking/vehicle_hypothesis.h"

namespace rsu::core {

struct LidarStepResult {
  std::vector<OutgoingCorrection> corrections;
  // Vehicles swept but not corrected, told why (core/withheld_notices.h): sent like the corrections.
  std::vector<OutgoingNotice> withheld_notices;
  bool background_became_ready = false;  // learning finished during this step (log it)
  // on_lidar_packet: what the decoder made of the payload (refused ones: the reason, to log).
  lidar::PacketOutcome packet;
};

struct ReloadSummary {
  bool background_kept = false;  // false: the LiDAR or background setup changed, learning restarts
  std::size_t vehicles_before = 0;
  std::size_t vehicles_after = 0;
};

// Rotations of the static scene (sensor frame, a sample of its points) for the mount check, with the
// reference they are checked against, or what to build it from (the first rotations after learning).
struct MountRotations {
  std::shared_ptr<const calibration::MountReference> reference;
  std::optional<calibration::MountReferenceSource> source;  // when reference is null
  std::vector<lidar::LidarFrame> rotations;
};

// The mount check of `taken` (its reference built first when it came with a source): the reference, and
// each rotation's estimate in order, for RsuCore::record_mount_checks. Pure, and touching nothing of the
// core: rsud runs it on a thread of its own.
struct MountChecks {
  MountRotations checked;
  std::vector<calibration::MountDrift> drifts;
};
MountChecks check_mount_rotations(MountRotations taken);

class RsuCore {
 public:
  // Throws std::invalid_argument for an unusable configuration (unknown sensor model, a model without
  // a packet format, non-finite mount, signed mode without a signing key, ...), with a message naming
  // what is wrong.
  explicit RsuCore(const RsuCoreConfig& config);

  // One datagram from the announcement port, received at `now`. Never throws on content. In signed mode
  // it is authenticated first (v2i/message_authenticator.h): dropped and counted unless a trusted
  // vehicle key signed it for that vehicle id, fresh and not replayed.
  // A refused announcement that passed authentication may get a refusal notice for its source
  // (DatagramOutcome::refusal_notice; core/refusal_notices.h). `checked`: its signature checked ahead
  // (v2i::check_signature_ahead, on the daemon's receiver thread), taken instead of verifying it here.
  // `received`: when it came off the wire (the kernel's timestamp), if known: how far ahead of our clock
  // it was generated is judged then, not after it waited behind other work (v2i::validate_announcement).
  DatagramOutcome on_datagram(std::span<const std::uint8_t> bytes, const SourceEndpoint& source, TimeNs now,
                              const v2i::SignatureCheck* checked = nullptr,
                              std::optional<TimeNs> received = std::nullopt);
  // An announcement another RSU accepted from a vehicle and shared on the data bus, received at `now`.
  // It takes the datagram path (authentication: the vehicle's own signature over its original bytes,
  // fresh, not replayed; decode, validation, reply_to against the vehicle as that RSU saw it, registry),
  // is rate-limited per origin RSU, and is skipped when the registry already holds that announcement
  // or a newer one (the vehicle also announced here, or another peer shared it first). The caller must
  // not share it again: only what on_datagram() accepted is shared, so nothing loops. Never throws.
  DatagramOutcome on_peer_announcement(std::span<const std::uint8_t> datagram, const PeerProvenance& from,
                                       TimeNs now) {
    return announcements_.on_peer_announcement(datagram, from, now);
  }

  // One UDP payload of the LiDAR (lidar/lidar_decoder.h: the configured sensor's decoder). `now` is its
  // receive time: it resolves what the packet's own time leaves ambiguous. Data packets pass a reorder
  // stage first (RsuCoreConfig::packet_order): held ones are processed later.
  LidarStepResult on_lidar_packet(std::span<const std::uint8_t> payload, TimeNs now);
  // Points in the SENSOR frame, in firing order, from a streaming source (a part of a rotation).
  LidarStepResult on_lidar_points(std::span<const lidar::LidarPoint> points_in_sensor_frame, TimeNs now);
  // One whole rotation (PCD replay, simulator frame): its clusters are released at its end.
  LidarStepResult on_lidar_frame(std::span<const lidar::LidarPoint> points_in_sensor_frame, TimeNs now);
  // Releases every pending cluster (drain at shutdown).
  LidarStepResult flush(TimeNs now);

  // Background frames recorded elsewhere (PCD files, or what an earlier run learned and the daemon
  // persisted; sensor frame): the model is ready afterwards. saved_by_earlier_run: no fix is sent before
  // the mount monitor has checked a rotation against them within its tolerance (mount_unverified_).
  void load_background(const std::vector<std::vector<lidar::LidarPoint>>& frames_in_sensor_frame,
                       bool saved_by_earlier_run = false);
  bool background_ready() const { return background_ready_; }
  // The rotations the background was learned or loaded from, in the SENSOR frame (independent of the
  // mount): what the daemon persists so that a restart serves at once.
  const std::vector<std::vector<lidar::LidarPoint>>& background_frames() const { return *background_frames_; }

  // Forgets silent vehicles (call about once a second); returns how many.
  std::size_t expire(TimeNs now);

  // Applies a new configuration, keeping the registered vehicles, the signers' replay state, the
  // signing sequence and, when the LiDAR and background setup are unchanged, the learned background.
  // The new trust list and key take effect (SIGHUP). Throws std::invalid_argument (and changes
  // nothing) if `next` is unusable.
  ReloadSummary reload(const RsuCoreConfig& next, TimeNs now);

  // The encoded RsuAdvertisement, signed in signed mode, generated at `now` (empty if encoding failed):
  // it says whether the fixes are withheld (the mount monitor) and why.
  std::vector<std::uint8_t> advertisement(TimeNs now);
  // Why fixes are withheld now (kNone while serving).
  v2i::FixesWithheld fixes_withheld() const;

  // Everything counted and measured, zeros included, in a stable order, each with its kind: for the
  // stats file, the metrics and logs.
  void report(CounterList& out) const;
  // The counts and levels of report() as ("area.reason", value).
  std::vector<std::pair<std::string, std::uint64_t>> counters() const;

  const RsuCoreConfig& config() const { return config_; }
  const v2i::VehicleRegistry& registry() const { return announcements_.registry(); }
  const EnumCounter<DatagramStage>& datagram_stages() const { return announcements_.datagram_stages(); }
  const EnumCounter<DatagramStage>& peer_stages() const { return announcements_.peer_stages(); }
  const EnumCounter<v2i::DecodeStatus>& decode_counts() const { return announcements_.decode_counts(); }
  const EnumCounter<v2i::AnnouncementReason>& validation_counts() const {
    return announcements_.validator().counts();
  }
  const v2i::MessageAuthenticator& authenticator() const { return announcements_.authenticator(); }
  // The configured sensor's packet decoder (its counters, geometry and notices).
  const lidar::LidarDecoder& lidar_decoder() const { return packets_.decoder(); }
  // Notices for the operator (log them once each, as warnings): the decoder's, and the sensor clock
  // crossing the tolerance (and what RsuCore then does).
  // The mount monitor's too: fixes stopped or resumed, and why.
  std::vector<std::string> take_lidar_notices();
  SensorClockReport sensor_clock() const { return packets_.sensor_clock(); }
  const lidar::PacketOrderStats& packet_order_stats() const { return packets_.order_stats(); }
  const perception::SweepClustererStats& sweep_stats() const { return clusterer_.stats(); }
  const LidarStats& lidar_stats() const { return lidar_stats_; }
  const Eigen::Vector2d& lidar_xy() const { return mount_.xy(); }
  // Whether fixes are sent: the background is ready, the LiDAR has not moved beyond the tolerance and,
  // with a reference saved by an earlier run, a rotation has been checked within it (mount_unverified_).
  bool mount_serving() const { return !mount_unverified_ && (!monitor_ || monitor_->serving()); }
  // Why fixes are stopped (empty while serving), for the advertisement and the stats.
  std::string mount_reason() const { return monitor_ ? monitor_->reason() : std::string(); }
  // The mount monitor (nullopt before the background is ready or when disabled).
  const std::optional<calibration::MountMonitor>& mount_monitor() const { return monitor_; }
  // The mount check (calibration::MountMonitor, 1-3 ms of CPU per rotation) of the rotations the LiDAR
  // steps completed since the last call. A step leaves it pending, so that the corrections it returns
  // do not wait for it (issue 16: correction latency); a caller that sends them first calls this after.
  // A step first checks what is still pending, so nothing is skipped when a caller never calls it.
  // Returns how many rotations were checked.
  std::size_t check_mount_pending();
  // The fits and fixes prepared ahead of a release (prepared_fixes.h) for what the last step left swept
  // but not released. A step leaves them pending, so that the corrections it returns do not wait for
  // another vehicle's preparation (issue 16: a dense sensor's near car takes 2-4 ms); a caller that sends
  // them first calls this after. A step first prepares what is still pending.
  void prepare_pending();
  // The same in two halves, for a caller that prepares on a thread of its own (rsud: the preparation
  // held its loop, and the packets behind it, for 2-4 ms): what to prepare (the last step's clusters and
  // vehicles, and the vehicles that the fits recorded since would release), and core::prepare's results
  // back. Results of a fixer that a reload has replaced are dropped. Until the caller takes it, a step
  // first prepares what is pending itself.
  Preparation take_preparation();
  void record_prepared(Prepared&& prepared);
  // The same check in two halves, for a caller that registers the rotations on a thread of its own (rsud:
  // a dense LiDAR's check held its loop for 2-3 ms a rotation, and the packets behind it): the pending
  // rotations with the reference they are checked against (MountReference is immutable) or, the first
  // time, what to build it from; nothing at all (no reference, no source) while no rotation is pending,
  // so that a caller submits work only when there is some; their checks back, in the order taken.
  // Checks against a reference (or a background) that a reload has replaced since are dropped.
  MountRotations take_mount_rotations();
  void record_mount_checks(const MountChecks& checks);

 private:
  enum class Release { passed, everything };

  // One batch of the sweep, the paper's steps in order (the .cpp quotes it in docs/architecture.md).
  LidarStepResult process(std::span<const lidar::LidarPoint> map_points, Release release, TimeNs now);
  std::vector<perception::Detection> detect(std::vector<perception::SweptCluster>&& clusters);
  std::vector<tracking::VehicleHypothesis> predict_announced(
      std::span<const perception::Detection> detections, TimeNs now);
  void correct(const HeldVehicle& held, TimeNs now, LidarStepResult& result);
  // The vehicle's notice that `fix` is not sent, and why, when it is owed one and the limits allow it.
  void tell_withheld(const GatheredFix& fix, const v2i::VehicleAnnouncement& a, bool lost_nearby, TimeNs now,
                     LidarStepResult& result);
  // Released open (prepared_fixes.h): a prepared fix's cluster noted with its box, and those the sweep
  // has passed.
  void note_fixed_open(const PreparedFix& prepared);
  std::vector<perception::OpenClusterName> fixed_open_swept() const;
  // The inputs of `held`'s fix, appended to `out` when its vehicle is registered (prepared_fixes.h).
  void add_fix_inputs(const HeldVehicle& held, TimeNs now, std::vector<FixInputs>& out);
  // Whether LiDAR packets were lost while the sweep crossed `held` (or just before its first points).
  bool lost_near(const HeldVehicle& held) const;
  // occluders_.of(held), with the points of the open clusters this batch's releases went ahead of
  // (fetched once a batch, when a fix needs them: copying a dense sensor's open car costs per packet).
  std::vector<Eigen::Vector2d> occluders_of(const HeldVehicle& held);
  bool unfinished_current_ = false;
  std::optional<TimeNs> prepare_due_;  // the last step's time, its preparation pending (prepare_pending)

  // sensor_points: this batch in the sensor frame (the rotations are kept so); map_scratch_ holds them
  // in the map frame.
  LidarStepResult learn(std::span<const lidar::LidarPoint> sensor_points, bool whole_frame);
  void add_background_frame(std::vector<lidar::LidarPoint>&& sensor_points);
  // The mount monitor from the background's rotations (once the background is ready).
  void start_mount_monitor();
  calibration::MountReferenceSource mount_reference_source() const;
  // A sample of the sweep's static points (sensor frame; map_scratch_ holds them in the map frame) for
  // the mount monitor, which checks each whole rotation.
  void watch_mount(std::span<const lidar::LidarPoint> sensor_points, bool whole_frame);
  // Passes a changed rotation rate or packet period measured by the decoder on to the stages.
  void follow_geometry();

  RsuCoreConfig config_;
  LidarMount mount_;
  PacketIntake packets_;
  lidar::FrameAssembler assembler_;  // whole rotations for background learning
  perception::BackgroundModel background_;
  perception::SweepClusterer clusterer_;
  SweepPosition sweep_;
  bool background_ready_ = false;
  // Sensor frame; shared with the mount check's reference build (not changed once learned).
  std::shared_ptr<std::vector<std::vector<lidar::LidarPoint>>> background_frames_ =
      std::make_shared<std::vector<std::vector<lidar::LidarPoint>>>();
  AnnouncementIntake announcements_;
  VehicleGatherer gatherer_;
  SweepOccluders occluders_;  // the sweep's other objects, which may hide part of a vehicle
  std::shared_ptr<const GatheredVehicleFixer> fixer_;  // shared with the preparation (prepared_fixes.h)
  PreparedFixes prepared_;          // fits and fixes prepared ahead of the release (take_preparation)
  std::vector<FixInputs> chained_;  // vehicles the recorded fits would release, to fix next
  FootprintTracks tracks_;          // each vehicle's footprint bounded over rotations
  // The held vehicles fixed ahead, as (vehicle id, parts gathered, points).
  std::vector<std::tuple<std::uint64_t, std::size_t, std::size_t>> prepared_held_;
  // Released open (prepared_fixes.h): the clusters handed out open to fit, by name and first point (map
  // frame), and those whose vehicle's fix is prepared, with the box the sweep must pass; the newest of each.
  static constexpr std::size_t kOpenKept = 8;
  std::vector<std::pair<perception::OpenClusterName, Eigen::Vector3d>> open_handed_;
  std::vector<FixedOpenCluster> fixed_open_;
  CorrectionBuilder corrections_;
  RefusalNotices refusals_;
  WithheldNotices withheld_;
  LidarStats lidar_stats_;

  std::vector<lidar::LidarPoint> ordered_scratch_;  // a packet released by the reorder stage
  // Lost packets: how many so far, and the firing time after the latest gap. A vehicle swept around a
  // gap may miss a part, so its fix counts none of its sides as seen (GatheredVehicleFixer).
  std::uint64_t packets_lost_ = 0;
  TimeNs last_loss_ns_ = std::numeric_limits<TimeNs>::min();
  std::vector<lidar::LidarPoint> map_scratch_;
  std::optional<calibration::MountMonitor> monitor_;
  bool monitor_due_ = false;       // learned: monitor_ is built before the first rotation it checks
  bool monitor_building_ = false;  // its reference's source taken (take_mount_rotations), not back yet
  lidar::FrameAssembler monitor_assembler_;  // rotations of a sample of the points, for monitor_
  std::vector<lidar::LidarPoint> monitor_scratch_;
  std::vector<lidar::LidarFrame> mount_rotations_pending_;  // for check_mount_pending()
  // Packets the stream lacked (lost on the way or by the kernel, shed as too late) when the monitor's
  // last rotation was completed: a rotation that lacked more than max_missing_fraction of its packets
  // is not checked (watch_mount).
  std::uint64_t missing_at_last_rotation_ = 0;
  std::uint64_t mount_rotations_gappy_ = 0;  // mount.rotations_gappy
  std::size_t monitor_skip_ = 0;             // points since the last one sampled
  std::vector<std::string> mount_notices_;
  // A reference saved by an earlier run (load_background): the LiDAR may have moved while rsud was
  // down, by any amount. Its fixes are withheld until a rotation checked against it has read within the
  // tolerance (check_mount_pending). Why: before its first check (a rotation or two after the stream
  // starts: only whole rotations are checked) a restarted rsud sent the fixes of a LiDAR leaned 0.36 deg
  // (6x the tolerance) since the background was saved, one 0.097 m off at a stated sigma of 0.032 m
  // (3.1 sigma; rsud_faults.py mount_lean under load).
  bool mount_unverified_ = false;
};

}  // namespace rsu::core
