// The RSU's whole decision logic, pure (no sockets, threads, clocks or files; DESIGN.md §4): the daemon
// hands it datagrams and LiDAR data with the time they arrived and sends what it returns. Tests drive
// it with hand-stepped time (as Vanetza's router is driven), so everything the daemon decides is
// tested here in microseconds.
//
//   announcements -> decode -> validate -> registry (expiry, capacity, per-source rate)
//   LiDAR packets -> decode (sensor frame) -> mount pose -> map frame
//       while learning: whole rotations train the background model (or load_background())
//       then: per point background removal -> SweepClusterer releases each cluster as soon as the
//       sweep has passed it -> rectangle fit -> association of the released batch with the registered
//       vehicles (gating + one global assignment) -> every cluster inside a vehicle's predicted
//       footprint is gathered for it, across the batches of one rotation, until the sweep has passed
//       that footprint -> rectangle fit on the union -> size correction with the vehicle's announced
//       size and predicted yaw as prior (rejected when the known-size box contradicts the points)
//       -> Correction datagram to the vehicle's reply_to address.
//
// Why gather. A vehicle far away and seen head-on breaks into fragments more than the clustering
// tolerance apart (bumper and front face low, cabin high, the hood between two rings), and the
// VLP-32C's per-laser azimuth offsets (+-4.2 deg, DESIGN.md §2) close them in different batches. A
// fragment fitted as the whole vehicle is metres off, so a vehicle's fix waits until the sweep has
// passed its whole predicted footprint (grown by its uncertainty) and the clusters that closed there.
// Near the LiDAR that footprint is passed about when its cluster closes: the wait is a few degrees.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include "common/time.h"
#include "lidar/frame_assembler.h"
#include "lidar/lidar_decoder.h"
#include "lidar/packet_order.h"
#include "lidar/point.h"
#include "lidar/sensor_clock.h"
#include "perception/background_model.h"
#include "perception/vehicle_fix.h"
#include "rsu/datagram_outcome.h"
#include "rsu/rsu_core_config.h"
#include "rsu/sweep_clusterer.h"
#include "v2i/announcement_validation.h"
#include "v2i/enum_counter.h"
#include "v2i/message_authenticator.h"
#include "v2i/message_signer.h"
#include "v2i/messages.h"
#include "v2i/source_rate_limiter.h"
#include "v2i/vehicle_registry.h"

namespace rsu::core {

// Who sent a datagram. `address` is the numeric IP literal; the rate limits are per address (host),
// so a sender cannot earn fresh tokens by changing ports.
struct SourceEndpoint {
  std::string address;
  std::uint16_t port = 0;
};

// Where an announcement shared by another RSU came from (README, "Several RSUs on one bus"). The
// announcement itself travels as the vehicle's original datagram, so that every RSU decodes and checks
// it itself (and, once announcements are signed, verifies the vehicle's own signature).
struct PeerProvenance {
  std::uint64_t origin_rsu_id = 0;  // the RSU that received it from the vehicle
  SourceEndpoint sender;            // the vehicle, as that RSU saw it (reply_to is checked against it)
};

struct OutgoingCorrection {
  v2i::UdpEndpoint destination;     // the vehicle's announced reply_to
  std::vector<std::uint8_t> bytes;  // the encoded datagram, signed in signed mode
  v2i::Correction correction;       // what the bytes say (vehicle id, sweep time, pose, quality)
};

struct LidarStepResult {
  std::vector<OutgoingCorrection> corrections;
  bool background_became_ready = false;  // learning finished during this step (log it)
  // on_lidar_packet: what the decoder made of the payload (refused ones: the reason, to log).
  PacketOutcome packet;
};

struct LidarStats {
  std::uint64_t background_frames = 0;
  std::uint64_t clusters_fitted = 0;
  std::uint64_t fits_failed = 0;
  std::uint64_t clusters_out_of_coverage = 0;
  std::uint64_t clusters_unmatched = 0;   // no registered vehicle within the gates: unregistered
  std::uint64_t fragments_merged = 0;     // extra clusters of one vehicle fitted with its main one
  std::uint64_t vehicles_in_batches = 0;  // registered vehicles offered to association
  std::uint64_t corrections_failed = 0;   // size correction refused the matched cluster
  // the known-size box contradicts the points, or the points do not decide where it sits: no fix
  std::uint64_t corrections_inconsistent = 0;
  std::uint64_t corrections_encode_failed = 0;
  std::uint64_t corrections = 0;
  std::uint64_t packets_too_late = 0;      // older than RsuCoreConfig::max_packet_age when processed
  std::uint64_t packets_clock_offset = 0;  // time_source sensor: the sensor's clock beyond the tolerance
};

// The LiDAR's clock against the host's (lidar/sensor_clock.h), as the stats and the log report it.
struct SensorClockReport {
  bool known = false;    // a data packet has arrived
  TimeNs offset_ns = 0;  // host - sensor (transit included): positive when the sensor is behind
  bool beyond_tolerance = false;
};

struct ReloadSummary {
  bool background_kept = false;  // false: the LiDAR or background setup changed, learning restarts
  std::size_t vehicles_before = 0;
  std::size_t vehicles_after = 0;
};

class RsuCore {
 public:
  // Throws std::invalid_argument for an unusable configuration (unknown sensor model, a model without
  // a packet format, non-finite mount, signed mode without a signing key, ...), with a message naming
  // what is wrong.
  explicit RsuCore(const RsuCoreConfig& config);

  // One datagram from the announcement port, received at `now`. Never throws on content. In signed mode
  // it is authenticated first (v2i/message_authenticator.h): dropped and counted unless a trusted
  // vehicle key signed it for that vehicle id, fresh and not replayed.
  DatagramOutcome on_datagram(std::span<const std::uint8_t> bytes, const SourceEndpoint& source, TimeNs now);

  // An announcement another RSU accepted from a vehicle and shared on the data bus, received at `now`.
  // It takes the datagram path (authentication: the vehicle's own signature over its original bytes,
  // fresh, not replayed; decode, validation, reply_to against the vehicle's address, registry),
  // is rate-limited per origin RSU, and is skipped when the registry already holds that announcement
  // or a newer one (the vehicle also announced here, or another peer shared it first). The caller must
  // not share it again: only what on_datagram() accepted is shared, so nothing loops. Never throws.
  DatagramOutcome on_peer_announcement(std::span<const std::uint8_t> datagram, const PeerProvenance& from,
                                       TimeNs now);

  // One UDP payload of the LiDAR (lidar/lidar_decoder.h: the configured sensor's decoder). `now` is its
  // receive time: it resolves what the packet's own time leaves ambiguous. Data packets pass a reorder
  // stage first (RsuCoreConfig::packet_order): held ones are processed later.
  LidarStepResult on_lidar_packet(std::span<const std::uint8_t> payload, TimeNs now);
  // Points in the SENSOR frame, in firing order, from a streaming source (a part of a rotation).
  LidarStepResult on_lidar_points(std::span<const LidarPoint> points_in_sensor_frame, TimeNs now);
  // One whole rotation (PCD replay, simulator frame): its clusters are released at its end.
  LidarStepResult on_lidar_frame(std::span<const LidarPoint> points_in_sensor_frame, TimeNs now);
  // Releases every pending cluster (drain at shutdown).
  LidarStepResult flush(TimeNs now);

  // Background frames recorded elsewhere (PCD files, sensor frame): the model is ready afterwards.
  void load_background(const std::vector<std::vector<LidarPoint>>& frames_in_sensor_frame);
  bool background_ready() const { return background_ready_; }

  // Forgets silent vehicles (call about once a second); returns how many.
  std::size_t expire(TimeNs now);

  // Applies a new configuration, keeping the registered vehicles, the signers' replay state, the
  // signing sequence and, when the LiDAR and background setup are unchanged, the learned background.
  // The new trust list and key take effect (SIGHUP). Throws std::invalid_argument (and changes
  // nothing) if `next` is unusable.
  ReloadSummary reload(const RsuCoreConfig& next, TimeNs now);

  // The encoded RsuAdvertisement, signed in signed mode, generated at `now` (empty if encoding failed).
  std::vector<std::uint8_t> advertisement(TimeNs now);

  // Every counter as ("area.reason", value), zeros included, in a stable order: for logs and stats.
  std::vector<std::pair<std::string, std::uint64_t>> counters() const;

  const RsuCoreConfig& config() const { return config_; }
  const v2i::VehicleRegistry& registry() const { return registry_; }
  const v2i::EnumCounter<DatagramStage>& datagram_stages() const { return datagram_stages_; }
  const v2i::EnumCounter<DatagramStage>& peer_stages() const { return peer_stages_; }
  const v2i::EnumCounter<v2i::DecodeStatus>& decode_counts() const { return decode_counts_; }
  const v2i::EnumCounter<v2i::AnnouncementReason>& validation_counts() const { return validator_.counts(); }
  const v2i::MessageAuthenticator& authenticator() const { return authenticator_; }
  // The configured sensor's packet decoder (its counters, geometry and notices).
  const LidarDecoder& lidar_decoder() const { return *decoder_; }
  // Notices for the operator (log them once each, as warnings): the decoder's, and the sensor clock
  // crossing the tolerance (and what RsuCore then does).
  std::vector<std::string> take_lidar_notices();
  SensorClockReport sensor_clock() const;
  // Measured values (not counts) as ("area.name", value), in a stable order: the sensor clock's offset
  // in ms (NaN before any packet) and the measured rotation rate.
  std::vector<std::pair<std::string, double>> gauges() const;
  const PacketOrderStats& packet_order_stats() const { return packet_order_.stats(); }
  const SweepClustererStats& sweep_stats() const { return clusterer_.stats(); }
  const LidarStats& lidar_stats() const { return lidar_stats_; }
  const Eigen::Vector2d& lidar_xy() const { return lidar_xy_; }

 private:
  struct VehicleChannel {
    std::uint32_t next_sequence = 0;
    TimeNs last_matched_sweep = 0;
    bool matched = false;
  };

  void to_map_frame(std::span<const LidarPoint> in, std::vector<LidarPoint>& out) const;
  // Passes a changed rotation rate or packet period measured by the decoder on to the stages.
  void follow_geometry();
  // Measures the clock on a data packet and says whether its points may be used (time_source sensor,
  // clock beyond the tolerance: no), queueing a notice when the clock crosses the tolerance.
  bool check_clock(const PacketOutcome& packet, TimeNs now);
  TimeNs rotation_period_ns() const { return static_cast<TimeNs>(1e9 / rotation_hz_); }
  LidarStepResult learn(std::span<const LidarPoint> map_points, bool whole_frame);
  void add_background_frame(std::span<const LidarPoint> map_points);
  // The clusters gathered for one matched vehicle in this rotation, waiting for the sweep to pass the
  // vehicle's predicted footprint (file comment).
  struct HeldVehicle {
    std::uint64_t vehicle_id = 0;
    std::vector<Eigen::Vector2d> footprint;  // union of the gathered clusters' points, map frame
    std::vector<float> heights;              // their z, map frame
    TimeNs first_time = 0;                   // sweep time of the first gathered cluster
    TimeNs weighted_offset = 0;              // sum over points of (point's cluster time - first_time)
    std::size_t parts = 0;                   // clusters gathered
    // The cluster the global assignment gave this vehicle (the nearest in Mahalanobis distance if it
    // was given one in several batches), its range in `footprint`: what it is fixed from when the
    // gathered union is not one vehicle. The other parts may be a neighbour's (a car beside it, a van
    // behind it) lying inside the grown footprint: the largest of them is no better a guess.
    std::size_t assigned_part_begin = 0;
    std::size_t assigned_part_size = 0;  // 0: no cluster was assigned, only gathered
    TimeNs assigned_part_time = 0;
    double assigned_distance_sq = 0.0;
    bool assigned_own = false;  // it lay in the footprint grown by the minimum margin + 1 sigma
    bool far = false;           // beyond GatheringConfig::hold_beyond_m (held for its fragments)
    TimeNs release_at = 0;      // firing time when the sweep has passed the footprint and its clusters
  };

  void correct_clusters(std::vector<SweptCluster>&& clusters, TimeNs now, LidarStepResult& result);
  void gather(std::vector<SweptCluster>&& clusters, TimeNs now);
  // Fixes the held vehicles whose footprint the sweep has passed (all of them if `everything`).
  void release_held(bool everything, TimeNs now, LidarStepResult& result);
  void correct_held(const HeldVehicle& held, TimeNs now, LidarStepResult& result);
  // The vehicle's fix from its points swept at `sweep_time`, with its announced size and heading.
  perception::VehicleFix fix_announced(std::span<const Eigen::Vector3d> points,
                                       const v2i::VehicleAnnouncement& a, TimeNs sweep_time) const;
  // The firing time at which the sweep has passed every point of `outline` (map frame) far enough
  // that no cluster near them can still grow (the SweepClusterer's closing rule).
  TimeNs passed_time(const std::vector<Eigen::Vector2d>& outline) const;
  // Authentication (signature, signer's rights, time and sequence windows), decoding, validation and
  // the reply_to check, whatever carried the datagram: the announcement, or empty with `out` saying which
  // stage refused it.
  std::optional<v2i::VehicleAnnouncement> screen(std::span<const std::uint8_t> bytes,
                                                 const std::string& sender_address, TimeNs now,
                                                 DatagramOutcome& out);
  DatagramOutcome finish(DatagramOutcome outcome);
  DatagramOutcome finish_peer(DatagramOutcome outcome);

  RsuCoreConfig config_;
  std::unique_ptr<LidarDecoder> decoder_;
  Eigen::Isometry3d sensor_to_map_;
  Eigen::Vector2d lidar_xy_;
  double rotation_hz_;  // as last applied to the stages below (follow_geometry)

  SensorClock sensor_clock_;
  bool clock_beyond_ = false;
  std::vector<std::string> notices_;
  PacketOrder packet_order_;
  FrameAssembler assembler_;  // whole rotations for background learning
  perception::BackgroundModel background_;
  SweepClusterer clusterer_;
  bool background_ready_ = false;

  v2i::SourceRateLimiter flood_limiter_;
  v2i::SourceRateLimiter peer_flood_limiter_;  // keyed by origin RSU
  v2i::MessageAuthenticator authenticator_;
  v2i::MessageSigner signer_;
  v2i::AnnouncementValidator validator_;
  v2i::VehicleRegistry registry_;
  std::unordered_map<std::uint64_t, VehicleChannel> channels_;
  std::vector<HeldVehicle> held_;
  bool shedding_ = false;  // the last packet was shed as too late (RsuCoreConfig::max_packet_age)
  bool sweep_known_ = false;
  LidarPoint sweep_point_;  // the latest point of the stream: where the rotation is, and when

  v2i::EnumCounter<DatagramStage> datagram_stages_;
  v2i::EnumCounter<DatagramStage> peer_stages_;
  v2i::EnumCounter<v2i::DecodeStatus> decode_counts_;
  LidarStats lidar_stats_;

  std::vector<LidarPoint> sensor_scratch_;   // reused packet after packet
  std::vector<LidarPoint> ordered_scratch_;  // a packet released by packet_order_
  std::vector<LidarPoint> map_scratch_;
};

}  // namespace rsu::core
