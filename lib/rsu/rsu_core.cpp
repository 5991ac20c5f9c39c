#include "rsu/rsu_core.h"

#include <arpa/inet.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <variant>

#include "common/angles.h"
#include "lidar/firing_schedule.h"
#include "perception/l_shape_fitting.h"
#include "rsu/correction_builder.h"
#include "v2i/association.h"
#include "v2i/vehicle_hypothesis.h"
#include "v2i/wire_codec.h"

namespace rsu::core {

namespace {

// The configured sensor's decoder, after checking the rest of the configuration it depends on.
std::unique_ptr<LidarDecoder> make_decoder(const RsuCoreConfig& config) {
  const Pose3& m = config.mount;
  for (const double v : {m.x, m.y, m.z, m.roll, m.pitch, m.yaw}) {
    if (!std::isfinite(v))
      throw std::invalid_argument("LiDAR mount pose must be finite");
  }
  if (!(config.coverage_radius_m > 0.0))
    throw std::invalid_argument("coverage radius must be > 0");
  if (config.background.learning_frames < 0)
    throw std::invalid_argument("learning frames must be >= 0");
  if (config.security.mode == v2i::SecurityMode::kSigned && !config.signing_key)
    throw std::invalid_argument("signed mode needs the RSU's signing key (security.key_file)");
  return make_lidar_decoder(config.sensor_model, config.sensor_options);
}

double azimuth_spread_rad(const SweepGeometry& geometry) {
  const std::vector<double>& offsets = geometry.ring_azimuth_offset_rad;
  if (offsets.empty())
    return 0.0;
  const auto [lo, hi] = std::minmax_element(offsets.begin(), offsets.end());
  return *hi - *lo;
}

// The release rule's margin grows by how far beams may lead the rotor at their firing (the VLP-32C's
// precision azimuth: sensor_model.h), so that the exact rule stays exact.
SweepConfig sweep_config(const RsuCoreConfig& config, const SweepGeometry& geometry) {
  SweepConfig c = config.sweep;
  c.release_margin_deg += rad_to_deg(geometry.azimuth_lead_rad);
  return c;
}

FrameAssemblerConfig assembler_config(const SweepGeometry& geometry) {
  FrameAssemblerConfig c;
  c.rotation_hz = geometry.rotation_hz;
  c.cut_azimuth_deg = rad_to_deg(geometry.rotation_start_azimuth_rad);
  return c;
}

// The 16 address bytes of an IPv4 (as IPv4-mapped IPv6) or IPv6 literal; false if neither.
bool address_bytes(const std::string& text, std::array<unsigned char, 16>& out) {
  out.fill(0);
  if (text.empty() || text.size() > 64 || text.find('\0') != std::string::npos)
    return false;
  std::array<unsigned char, 4> v4{};
  if (inet_pton(AF_INET, text.c_str(), v4.data()) == 1) {
    out[10] = 0xff;
    out[11] = 0xff;
    std::memcpy(out.data() + 12, v4.data(), 4);
    return true;
  }
  return inet_pton(AF_INET6, text.c_str(), out.data()) == 1;
}

// Same host, whatever the spelling ("127.0.0.1" and the dual-stack "::ffff:127.0.0.1" are one).
bool same_address(const std::string& a, const std::string& b) {
  std::array<unsigned char, 16> x{};
  std::array<unsigned char, 16> y{};
  return address_bytes(a, x) && address_bytes(b, y) && x == y;
}

bool same_pose(const Pose3& a, const Pose3& b) {
  return a.x == b.x && a.y == b.y && a.z == b.z && a.roll == b.roll && a.pitch == b.pitch && a.yaw == b.yaw;
}

// Whether a learned background stays valid under `b`: it depends on the sensor, its pose and the
// background model's parameters only.
// Whether the sensor is decoded the same way under both (the decoder, its counters and its measured
// rate carry over a reload then).
bool same_sensor_setup(const RsuCoreConfig& a, const RsuCoreConfig& b) {
  const LidarDecoderOptions& x = a.sensor_options;
  const LidarDecoderOptions& y = b.sensor_options;
  const bool same_tables =
      x.calibrated_model.has_value() == y.calibrated_model.has_value() &&
      (!x.calibrated_model ||
       (x.calibrated_model->elevation_deg == y.calibrated_model->elevation_deg &&
        x.calibrated_model->azimuth_offset_deg == y.calibrated_model->azimuth_offset_deg &&
        x.calibrated_model->distance_unit_m == y.calibrated_model->distance_unit_m));
  return a.sensor_model == b.sensor_model && same_tables && x.metadata_text == y.metadata_text &&
         x.returns == y.returns && x.rotation_start_azimuth_deg == y.rotation_start_azimuth_deg;
}

bool same_background_setup(const RsuCoreConfig& a, const RsuCoreConfig& b) {
  const auto& p = a.perception;
  const auto& q = b.perception;
  return same_sensor_setup(a, b) && same_pose(a.mount, b.mount) && p.background == q.background &&
         p.ground_prefilter == q.ground_prefilter && p.ground.ground_z == q.ground.ground_z &&
         p.ground.min_height == q.ground.min_height &&
         p.reference_frame.match_radius_m == q.reference_frame.match_radius_m &&
         p.range_image.azimuth_bins == q.range_image.azimuth_bins &&
         p.range_image.neighbour_bins == q.range_image.neighbour_bins &&
         p.range_image.near_percentile == q.range_image.near_percentile &&
         p.range_image.margin_m == q.range_image.margin_m &&
         p.range_image.margin_per_m == q.range_image.margin_per_m &&
         p.range_image.max_rings == q.range_image.max_rings;
}

bool same_registry_setup(const v2i::VehicleRegistryConfig& a, const v2i::VehicleRegistryConfig& b) {
  return a.silence_timeout == b.silence_timeout && a.capacity == b.capacity &&
         a.rate_limit.bucket.rate_per_s == b.rate_limit.bucket.rate_per_s &&
         a.rate_limit.bucket.burst == b.rate_limit.bucket.burst &&
         a.rate_limit.max_sources == b.rate_limit.max_sources &&
         a.size_change_tolerance_m == b.size_change_tolerance_m;
}

// The packet stream's order rule: the sensor's packet period, and a silence as long as the sweep
// clusterer's restart rule (SweepConfig::max_gap_rotations) is a restart of the stream.
PacketOrder packet_order_for(const RsuCoreConfig& config, const SweepGeometry& geometry) {
  const auto max_gap = static_cast<TimeNs>(config.sweep.max_gap_rotations / geometry.rotation_hz * 1e9);
  return PacketOrder(config.packet_order, geometry.packet_period_ns, std::max<TimeNs>(1, max_gap));
}

void append(LidarStepResult& into, LidarStepResult&& step) {
  for (OutgoingCorrection& c : step.corrections)
    into.corrections.push_back(std::move(c));
  into.background_became_ready = into.background_became_ready || step.background_became_ready;
}

// "52.312 s behind" / "0.8 ms ahead of": how the sensor's clock stands to the host's (offset = host -
// sensor).
std::string describe_clock_offset(TimeNs offset_ns) {
  const double magnitude = std::abs(static_cast<double>(offset_ns));
  char amount[48];
  if (magnitude >= 1e9)
    std::snprintf(amount, sizeof amount, "%.3f s", magnitude * 1e-9);
  else
    std::snprintf(amount, sizeof amount, "%.1f ms", magnitude * 1e-6);
  return std::string(amount) + (offset_ns >= 0 ? " behind" : " ahead of");
}

TimeNs mean_time(const std::vector<LidarPoint>& points) {
  const TimeNs t0 = points.front().time_ns;
  TimeNs offset_sum = 0;  // relative to t0: a cluster spans well under a second, so no overflow
  for (const LidarPoint& p : points)
    offset_sum += p.time_ns - t0;
  return t0 + offset_sum / static_cast<TimeNs>(points.size());
}

}  // namespace

RsuCore::RsuCore(const RsuCoreConfig& config)
    : config_(config),
      decoder_(make_decoder(config)),
      sensor_to_map_(config.mount.to_isometry()),
      lidar_xy_(config.mount.x, config.mount.y),
      rotation_hz_(decoder_->geometry().rotation_hz),
      packet_order_(packet_order_for(config, decoder_->geometry())),
      assembler_(assembler_config(decoder_->geometry())),
      background_(perception::background_model_config(config.perception), lidar_xy_),
      clusterer_(sweep_config(config, decoder_->geometry()), config.perception.clustering, lidar_xy_,
                 decoder_->geometry().rotation_hz, decoder_->geometry().ring_azimuth_offset_rad),
      background_ready_(config.background.learning_frames == 0),
      flood_limiter_(config.datagram_flood),
      peer_flood_limiter_(config.peers.flood),
      authenticator_(config.security, config.trust_list),
      signer_(config.security.mode == v2i::SecurityMode::kSigned ? config.signing_key : std::nullopt),
      validator_(config.announcement_limits),
      registry_(config.registry) {}

DatagramOutcome RsuCore::finish(DatagramOutcome outcome) {
  datagram_stages_.add(outcome.stage);
  return outcome;
}

DatagramOutcome RsuCore::finish_peer(DatagramOutcome outcome) {
  peer_stages_.add(outcome.stage);
  return outcome;
}

std::optional<v2i::VehicleAnnouncement> RsuCore::screen(std::span<const std::uint8_t> bytes,
                                                        const std::string& sender_address, TimeNs now,
                                                        DatagramOutcome& out) {
  v2i::AuthenticatedMessage authenticated = authenticator_.authenticate(bytes, now);
  out.auth = authenticated.verdict;
  if (authenticated.verdict == v2i::AuthVerdict::kMalformed) {
    decode_counts_.add(authenticated.message.status);
    out.stage = DatagramStage::kDecode;
    out.decode = authenticated.message.status;
    return std::nullopt;
  }
  if (!authenticated.accepted()) {
    out.stage = DatagramStage::kAuthentication;
    return std::nullopt;
  }
  auto* announcement = std::get_if<v2i::VehicleAnnouncement>(&authenticated.message.body);
  if (announcement == nullptr) {
    out.stage = DatagramStage::kNotAnnouncement;
    return std::nullopt;
  }
  out.vehicle_id = announcement->vehicle_id;
  out.validation = validator_.check(*announcement, now);
  if (out.validation != v2i::AnnouncementReason::kValid) {
    out.stage = DatagramStage::kValidation;
    return std::nullopt;
  }
  if (config_.require_reply_to_source_address &&
      !same_address(announcement->reply_to.address, sender_address)) {
    out.stage = DatagramStage::kReplyToMismatch;
    return std::nullopt;
  }
  return std::move(*announcement);
}

DatagramOutcome RsuCore::on_datagram(std::span<const std::uint8_t> bytes, const SourceEndpoint& source,
                                     TimeNs now) {
  DatagramOutcome out;
  if (flood_limiter_.admit(source.address, now) != v2i::RateDecision::kAllowed) {
    out.stage = DatagramStage::kFloodLimited;
    return finish(out);
  }
  const auto announcement = screen(bytes, source.address, now, out);
  if (!announcement)
    return finish(out);
  out.upsert = registry_.upsert(*announcement, source.address, now);
  out.stage = v2i::is_accepted(out.upsert) ? DatagramStage::kAccepted : DatagramStage::kRegistry;
  return finish(out);
}

DatagramOutcome RsuCore::on_peer_announcement(std::span<const std::uint8_t> datagram,
                                              const PeerProvenance& from, TimeNs now) {
  DatagramOutcome out;
  if (from.origin_rsu_id == config_.rsu_id) {
    out.stage = DatagramStage::kFromSelf;  // the bus delivers an RSU's own samples back to it
    return finish_peer(out);
  }
  if (peer_flood_limiter_.admit("rsu:" + std::to_string(from.origin_rsu_id), now) !=
      v2i::RateDecision::kAllowed) {
    out.stage = DatagramStage::kFloodLimited;
    return finish_peer(out);
  }
  const auto announcement = screen(datagram, from.sender.address, now, out);
  if (out.stage == DatagramStage::kAuthentication && out.auth == v2i::AuthVerdict::kDuplicate) {
    // A signed datagram this RSU verified already: the vehicle announced here too, or another peer
    // shared it first. Not news, not an attack (the bytes are the vehicle's own, signature and all).
    out.stage = DatagramStage::kNotFresher;
    return finish_peer(out);
  }
  if (!announcement)
    return finish_peer(out);
  // Checked before the registry so that a vehicle announcing to several RSUs, each sharing it, is not
  // charged twice by the registry's per-source rate limit for one announcement.
  const v2i::RegisteredVehicle* known = registry_.find(announcement->vehicle_id, now);
  if (known != nullptr && !v2i::sequence_newer(announcement->sequence, known->announcement.sequence)) {
    out.stage = DatagramStage::kNotFresher;
    return finish_peer(out);
  }
  // The registry's source is the vehicle's address, as for its own datagrams: its rate limit and
  // source-change count follow the vehicle, whichever RSU heard it.
  out.upsert = registry_.upsert(*announcement, from.sender.address, now);
  out.stage = v2i::is_accepted(out.upsert) ? DatagramStage::kAccepted : DatagramStage::kRegistry;
  return finish_peer(out);
}

void RsuCore::to_map_frame(std::span<const LidarPoint> in, std::vector<LidarPoint>& out) const {
  const Eigen::Matrix3f r = sensor_to_map_.linear().cast<float>();
  const Eigen::Vector3f t = sensor_to_map_.translation().cast<float>();
  out.resize(in.size());
  for (std::size_t i = 0; i < in.size(); ++i) {
    const Eigen::Vector3f q = r * Eigen::Vector3f(in[i].x, in[i].y, in[i].z) + t;
    out[i] = in[i];  // ring, azimuth (the sensor's beam azimuth) and time are kept
    out[i].x = q.x();
    out[i].y = q.y();
    out[i].z = q.z();
  }
}

void RsuCore::add_background_frame(std::span<const LidarPoint> map_points) {
  background_.add_background_frame(map_points);
  ++lidar_stats_.background_frames;
}

LidarStepResult RsuCore::learn(std::span<const LidarPoint> map_points, bool whole_frame) {
  LidarStepResult result;
  if (whole_frame) {
    add_background_frame(map_points);
  } else {
    for (const LidarFrame& frame : assembler_.add(map_points))
      add_background_frame(frame.points);
  }
  if (static_cast<int>(lidar_stats_.background_frames) >= config_.background.learning_frames) {
    background_ready_ = true;
    result.background_became_ready = true;
  }
  return result;
}

bool RsuCore::check_clock(const PacketOutcome& packet, TimeNs now) {
  sensor_clock_.observe(packet.next_ns, now);
  const TimeNs offset = *sensor_clock_.offset_ns();
  const bool beyond = std::abs(static_cast<double>(offset)) > static_cast<double>(config_.clock_tolerance);
  const bool sensor_time = config_.time_source == TimeSource::kSensor;
  if (beyond != clock_beyond_) {
    clock_beyond_ = beyond;
    const std::string where = "the LiDAR's clock is " + describe_clock_offset(offset) + " the host's";
    const std::string tolerance = std::to_string(config_.clock_tolerance / kNsPerMs) + " ms";
    if (beyond && sensor_time) {
      notices_.push_back(where + " (beyond lidar.clock_tolerance_ms, " + tolerance +
                         "): its packets are REFUSED (packet.clock_offset) while this lasts. Synchronise the "
                         "LiDAR to the RSU's clock (PTP or GNSS PPS), or set lidar.time_source: host_receive "
                         "to stamp its points by arrival");
    } else if (beyond) {
      notices_.push_back(
          where + " (beyond " + tolerance +
          "): lidar.time_source host_receive stamps its points by arrival, the offset removed");
    } else {
      notices_.push_back(where + ": within lidar.clock_tolerance_ms (" + tolerance + ") again" +
                         (sensor_time ? ", its packets are used" : ""));
    }
  }
  return !(beyond && sensor_time);
}

std::vector<std::string> RsuCore::take_lidar_notices() {
  std::vector<std::string> out = decoder_->take_notices();
  for (std::string& n : notices_)
    out.push_back(std::move(n));
  notices_.clear();
  return out;
}

SensorClockReport RsuCore::sensor_clock() const {
  SensorClockReport r;
  if (const auto offset = sensor_clock_.offset_ns()) {
    r.known = true;
    r.offset_ns = *offset;
    r.beyond_tolerance = clock_beyond_;
  }
  return r;
}

std::vector<std::pair<std::string, double>> RsuCore::gauges() const {
  const auto offset = sensor_clock_.offset_ns();
  return {{"clock.offset_ms", offset ? static_cast<double>(*offset) * 1e-6 : std::nan("")},
          {"clock.steps", static_cast<double>(sensor_clock_.steps())},
          {"lidar.rotation_hz", decoder_->geometry().rotation_hz}};
}

void RsuCore::follow_geometry() {
  const SweepGeometry& g = decoder_->geometry();
  packet_order_.set_packet_period(g.packet_period_ns);
  // A rotation rate measured anew (the decoder smooths it packet by packet): passed on when it moved
  // by more than 0.1 %, which is what unwrapping across gaps and the rotation period need.
  if (std::abs(g.rotation_hz - rotation_hz_) <= 1e-3 * rotation_hz_)
    return;
  rotation_hz_ = g.rotation_hz;
  assembler_.set_rotation_hz(rotation_hz_);
  clusterer_.set_rotation_hz(rotation_hz_);
}

LidarStepResult RsuCore::on_lidar_packet(std::span<const std::uint8_t> payload, TimeNs now) {
  sensor_scratch_.clear();
  LidarStepResult result;
  result.packet = decoder_->decode(payload, now, sensor_scratch_);
  if (!result.packet.is_data()) {
    return result;  // counted by the decoder, by kind and reason
  }
  follow_geometry();
  if (!check_clock(result.packet, now)) {
    ++lidar_stats_.packets_clock_offset;
    return result;
  }
  if (config_.time_source == TimeSource::kHostReceive) {
    // On the host clock: the packet's sensor times moved by the measured offset (its arrival minus its
    // known duration, the smallest delay seen: sensor_clock.h); relative times stay the sensor's.
    const TimeNs shift = *sensor_clock_.offset_ns();
    for (LidarPoint& p : sensor_scratch_)
      p.time_ns += shift;
    result.packet.first_ns += shift;
    result.packet.next_ns += shift;
  }
  if (config_.max_packet_age > 0 && now - result.packet.first_ns > config_.max_packet_age) {
    ++lidar_stats_.packets_too_late;  // behind: shed (RsuCoreConfig::max_packet_age)
    if (!shedding_)
      clusterer_.restart();  // what is open now lacks the shed points: never fitted as whole
    shedding_ = true;
    return result;
  }
  shedding_ = false;
  // A late one is counted.
  packet_order_.push(result.packet.first_ns, sensor_scratch_, result.packet.next_ns);
  while (packet_order_.pop(ordered_scratch_))
    append(result, on_lidar_points(ordered_scratch_, now));
  return result;
}

LidarStepResult RsuCore::on_lidar_points(std::span<const LidarPoint> points, TimeNs now) {
  to_map_frame(points, map_scratch_);
  if (!background_ready_) {
    return learn(map_scratch_, false);
  }
  for (const LidarPoint& p : map_scratch_) {
    clusterer_.add(p, background_.classify(p) == perception::PointClass::foreground);
  }
  if (!map_scratch_.empty() && std::isfinite(map_scratch_.back().azimuth_rad)) {
    sweep_point_ = map_scratch_.back();
    sweep_known_ = true;
  }
  LidarStepResult result;
  correct_clusters(clusterer_.release_closed(), now, result);
  return result;
}

LidarStepResult RsuCore::on_lidar_frame(std::span<const LidarPoint> points, TimeNs now) {
  to_map_frame(points, map_scratch_);
  if (!background_ready_) {
    return learn(map_scratch_, true);
  }
  for (const LidarPoint& p : map_scratch_) {
    clusterer_.add(p, background_.classify(p) == perception::PointClass::foreground);
  }
  LidarStepResult result;
  gather(clusterer_.release_all(), now);
  release_held(true, now, result);  // a whole rotation: every vehicle in it has been swept
  return result;
}

LidarStepResult RsuCore::flush(TimeNs now) {
  LidarStepResult result;
  while (packet_order_.pop(ordered_scratch_, true))
    append(result, on_lidar_points(ordered_scratch_, now));
  if (background_ready_) {
    gather(clusterer_.release_all(), now);
    release_held(true, now, result);
  }
  return result;
}

void RsuCore::load_background(const std::vector<std::vector<LidarPoint>>& frames) {
  for (const auto& frame : frames) {
    to_map_frame(frame, map_scratch_);
    add_background_frame(map_scratch_);
  }
  background_ready_ = true;
}

void RsuCore::correct_clusters(std::vector<SweptCluster>&& clusters, TimeNs now, LidarStepResult& result) {
  gather(std::move(clusters), now);
  release_held(false, now, result);
}

TimeNs RsuCore::passed_time(const std::vector<Eigen::Vector2d>& outline) const {
  if (!sweep_known_ || outline.empty())
    return 0;
  // Beam azimuths clockwise from the sensor's +x (LidarPoint::azimuth_rad), relative to the first
  // outline point so that an outline across the 0/360 deg cut needs no unwrapping.
  const Eigen::Isometry3d map_to_sensor = sensor_to_map_.inverse();
  const auto azimuth_of = [&](const Eigen::Vector2d& q) {
    const Eigen::Vector3d s = map_to_sensor * Eigen::Vector3d(q.x(), q.y(), config_.mount.z);
    return -std::atan2(s.y(), s.x());
  };
  const double reference = azimuth_of(outline.front());
  double ahead = 0.0;
  double nearest = std::numeric_limits<double>::infinity();
  for (const Eigen::Vector2d& q : outline) {
    ahead = std::max(ahead, wrap_angle(azimuth_of(q) - reference));
    nearest = std::min(nearest, (q - lidar_xy_).norm());
  }
  // The clusterer's rule: a point at range r is closed once the earliest future firing is asin(d / r)
  // past it, and future firings lag the sweep by the offset spread plus the margin.
  const double d = config_.perception.clustering.tolerance_m;
  const double closing = nearest > d ? std::asin(d / nearest) : std::numbers::pi / 2.0;
  const SweepGeometry& geometry = decoder_->geometry();
  const double lag =
      azimuth_spread_rad(geometry) + geometry.azimuth_lead_rad + deg_to_rad(config_.sweep.release_margin_deg);
  const double target = reference + ahead + closing + lag;
  const double forward = wrap_angle_positive(target - static_cast<double>(sweep_point_.azimuth_rad));
  if (forward > std::numbers::pi)
    return sweep_point_.time_ns;  // already behind the sweep
  const double radians_per_ns = 2.0 * std::numbers::pi / static_cast<double>(rotation_period_ns());
  return sweep_point_.time_ns + static_cast<TimeNs>(forward / radians_per_ns);
}

void RsuCore::gather(std::vector<SweptCluster>&& clusters, TimeNs now) {
  if (clusters.empty())
    return;

  struct Candidate {
    std::vector<Eigen::Vector2d> footprint;
    std::vector<float> heights;  // z of the footprint's points
    perception::RectangleFit fit;
    TimeNs sweep_time = 0;
    bool fitted = false;  // fit ok and inside the coverage radius: offered to association
  };
  std::vector<Candidate> candidates;
  std::vector<v2i::FittedCluster> fitted;
  std::vector<std::size_t> fitted_candidate;  // fitted[i] is candidates[fitted_candidate[i]]
  for (const SweptCluster& cluster : clusters) {
    if (cluster.points.empty())
      continue;
    Candidate c;
    c.footprint.reserve(cluster.points.size());
    c.heights.reserve(cluster.points.size());
    for (const LidarPoint& p : cluster.points) {
      c.footprint.emplace_back(static_cast<double>(p.x), static_cast<double>(p.y));
      c.heights.push_back(p.z);
    }
    c.sweep_time = mean_time(cluster.points);
    c.fit = perception::fit_rectangle(c.footprint, lidar_xy_, config_.perception.fix.fit);
    ++lidar_stats_.clusters_fitted;
    if (!c.fit.ok()) {
      // Too small or thin to fit alone, but it may still be a fragment of a vehicle (gathered below).
      ++lidar_stats_.fits_failed;
    } else if ((c.fit.center - lidar_xy_).norm() > config_.coverage_radius_m) {
      ++lidar_stats_.clusters_out_of_coverage;
      continue;
    } else {
      c.fitted = true;
      fitted.push_back({c.fit.center, c.fit.yaw, c.fit.length0, c.fit.length1, cluster.points.size()});
      fitted_candidate.push_back(candidates.size());
    }
    candidates.push_back(std::move(c));
  }
  if (candidates.empty())
    return;

  // One prediction time for the batch (its clusters were swept within a few degrees of each other).
  std::vector<TimeNs> times;
  for (const Candidate& c : candidates)
    times.push_back(c.sweep_time);
  std::nth_element(times.begin(), times.begin() + static_cast<std::ptrdiff_t>(times.size() / 2), times.end());
  const TimeNs batch_time = times[times.size() / 2];

  // A vehicle is fixed once per rotation: one already fixed in this rotation is not offered again (a
  // later cluster near it is something else). One still held (gathering) is offered again.
  std::vector<const v2i::RegisteredVehicle*> vehicles;
  std::vector<v2i::VehicleHypothesis> hypotheses;
  for (const v2i::RegisteredVehicle* v : registry_.active(now)) {
    const auto it = channels_.find(v->announcement.vehicle_id);
    if (it != channels_.end() && it->second.matched &&
        std::abs(batch_time - it->second.last_matched_sweep) < rotation_period_ns() / 2) {
      continue;
    }
    vehicles.push_back(v);
    hypotheses.push_back(v2i::predict_hypothesis(v->announcement, batch_time, config_.hypothesis));
  }
  lidar_stats_.vehicles_in_batches += vehicles.size();
  if (vehicles.empty()) {
    lidar_stats_.clusters_unmatched += candidates.size();
    return;
  }
  const v2i::AssociationResult association = v2i::associate(fitted, hypotheses, config_.association);

  // Each vehicle's predicted footprint grown by its uncertainty: every corner moved out by the margin.
  const GatheringConfig& g = config_.gathering;
  std::vector<std::array<Eigen::Vector2d, 4>> grown(vehicles.size());
  std::vector<Eigen::Vector2d> grown_half(vehicles.size());
  std::vector<double> centre_sigmas(vehicles.size());
  for (std::size_t j = 0; j < vehicles.size(); ++j) {
    const v2i::VehicleHypothesis& h = hypotheses[j];
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(h.covariance.topLeftCorner<2, 2>());
    const double centre_sigma = std::sqrt(std::max(0.0, eig.eigenvalues().maxCoeff()));
    centre_sigmas[j] = std::isfinite(centre_sigma) ? std::min(centre_sigma, g.max_margin_m) : g.max_margin_m;
    const double yaw_sigma = std::sqrt(std::max(0.0, h.covariance(2, 2)));
    const double half_diagonal = 0.5 * std::hypot(h.size.length_m, h.size.width_m);
    double margin = g.footprint_sigmas * (centre_sigma + std::min(yaw_sigma, 1.0) * half_diagonal);
    margin = std::isfinite(margin) ? std::clamp(margin, g.min_margin_m, g.max_margin_m) : g.max_margin_m;
    grown_half[j] = {0.5 * h.size.length_m + margin, 0.5 * h.size.width_m + margin};
    const Eigen::Rotation2Dd r(h.yaw);
    int k = 0;
    for (const double sx : {-1.0, 1.0}) {
      for (const double sy : {-1.0, 1.0}) {
        grown[j][static_cast<std::size_t>(k++)] =
            h.centre + r * Eigen::Vector2d(sx * grown_half[j].x(), sy * grown_half[j].y());
      }
    }
  }
  const auto fraction_inside = [&](const Candidate& c, std::size_t j, const Eigen::Vector2d& half) {
    const Eigen::Rotation2Dd to_box(-hypotheses[j].yaw);
    std::size_t inside = 0;
    for (const Eigen::Vector2d& p : c.footprint) {
      const Eigen::Vector2d q = (to_box * (p - hypotheses[j].centre)).cwiseAbs();
      if (q.x() <= half.x() && q.y() <= half.y())
        ++inside;
    }
    return static_cast<double>(inside) / static_cast<double>(c.footprint.size());
  };
  const auto inside_fraction = [&](const Candidate& c, std::size_t j) {
    return fraction_inside(c, j, grown_half[j]);
  };
  // Whether a cluster lies in the vehicle's predicted footprint grown by the minimum margin and one
  // sigma of its predicted centre only (a vehicle that knows it is lost may be found farther off).
  const auto tightly_inside = [&](const Candidate& c, std::size_t j) {
    const double margin = g.min_margin_m + centre_sigmas[j];
    const Eigen::Vector2d half(0.5 * hypotheses[j].size.length_m + margin,
                               0.5 * hypotheses[j].size.width_m + margin);
    return fraction_inside(c, j, half) >= g.min_inside_fraction;
  };

  // Members: the cluster the assignment gave each vehicle, and every other cluster mostly inside its
  // grown footprint (or, the rule before footprints, passing its gate while the vehicle got a cluster).
  std::vector<std::vector<std::size_t>> members(vehicles.size());
  std::vector<bool> taken(candidates.size(), false);
  std::vector<double> assigned_distance(vehicles.size(), -1.0);  // the assigned cluster is members.front()
  for (const v2i::AssociatedPair& pair : association.pairs) {
    const std::size_t c = fitted_candidate[pair.cluster];
    members[pair.vehicle].push_back(c);
    assigned_distance[pair.vehicle] = pair.distance_sq;
    taken[c] = true;
  }
  std::vector<std::size_t> fitted_index(candidates.size(), std::numeric_limits<std::size_t>::max());
  for (std::size_t i = 0; i < fitted_candidate.size(); ++i)
    fitted_index[fitted_candidate[i]] = i;
  for (std::size_t c = 0; c < candidates.size(); ++c) {
    if (taken[c])
      continue;
    std::ptrdiff_t best = -1;
    double best_fraction = g.min_inside_fraction;
    for (std::size_t j = 0; j < vehicles.size(); ++j) {
      const double f = inside_fraction(candidates[c], j);
      if (f >= best_fraction) {
        best_fraction = f;
        best = static_cast<std::ptrdiff_t>(j);
      }
    }
    if (best < 0 && candidates[c].fitted) {
      double best_distance = std::numeric_limits<double>::infinity();
      for (std::size_t j = 0; j < vehicles.size(); ++j) {
        if (members[j].empty())
          continue;
        const v2i::PairCheck check =
            v2i::check_pair(fitted[fitted_index[c]], hypotheses[j], config_.association);
        if (check.verdict == v2i::PairGate::kPass && check.distance_sq < best_distance) {
          best_distance = check.distance_sq;
          best = static_cast<std::ptrdiff_t>(j);
        }
      }
    }
    if (best >= 0) {
      members[static_cast<std::size_t>(best)].push_back(c);
    } else {
      ++lidar_stats_.clusters_unmatched;
    }
  }

  for (std::size_t j = 0; j < vehicles.size(); ++j) {
    if (members[j].empty())
      continue;
    const std::uint64_t id = vehicles[j]->announcement.vehicle_id;
    auto it =
        std::find_if(held_.begin(), held_.end(), [id](const HeldVehicle& h) { return h.vehicle_id == id; });
    if (it == held_.end()) {
      HeldVehicle fresh;
      fresh.vehicle_id = id;
      fresh.first_time = candidates[members[j].front()].sweep_time;
      held_.push_back(std::move(fresh));
      it = std::prev(held_.end());
    }
    HeldVehicle& held = *it;
    std::vector<Eigen::Vector2d> outline(grown[j].begin(), grown[j].end());
    for (const std::size_t c : members[j]) {
      const Candidate& part = candidates[c];
      const bool assigned = c == members[j].front() && assigned_distance[j] >= 0.0;
      if (assigned && (held.assigned_part_size == 0 || assigned_distance[j] < held.assigned_distance_sq)) {
        held.assigned_part_begin = held.footprint.size();
        held.assigned_part_size = part.footprint.size();
        held.assigned_part_time = part.sweep_time;
        held.assigned_distance_sq = assigned_distance[j];
        held.assigned_own = tightly_inside(part, j);
      }
      held.footprint.insert(held.footprint.end(), part.footprint.begin(), part.footprint.end());
      held.heights.insert(held.heights.end(), part.heights.begin(), part.heights.end());
      held.weighted_offset +=
          static_cast<TimeNs>(part.footprint.size()) * (part.sweep_time - held.first_time);
      ++held.parts;
      outline.insert(outline.end(), part.footprint.begin(), part.footprint.end());
    }
    // Hold until the sweep has passed the grown footprint and the gathered clusters (a vehicle whose
    // estimate is off may extend beyond its footprint), never longer than half a rotation. Far vehicles
    // are held (fragments). A near one is not split across batches (its faces are dense and its rings
    // close together), so its fix goes as soon as the sweep clusterer releases it (latency, issue 4) -
    // if the cluster the assignment gave it lies in its footprint grown by the minimum margin only. If
    // not, that cluster may be a neighbour's released first (an unconnected car beside it, farther from
    // the LiDAR, whose visible face falls inside the vehicle's gate): the vehicle is held until the
    // sweep has passed its grown footprint, so that its own cluster, released later, is assigned too and
    // wins as the nearer (issue 7, mis-association).
    const bool far = (hypotheses[j].centre - lidar_xy_).norm() > g.hold_beyond_m;
    held.far = far;
    const bool own = assigned_distance[j] >= 0.0 && tightly_inside(candidates[members[j].front()], j);
    held.release_at =
        far || !own
            ? std::max(
                  held.release_at,
                  std::min(passed_time(far ? outline
                                           : std::vector<Eigen::Vector2d>(grown[j].begin(), grown[j].end())),
                           held.first_time + rotation_period_ns() / 2))
            : held.first_time;
  }
}

void RsuCore::release_held(bool everything, TimeNs now, LidarStepResult& result) {
  for (auto it = held_.begin(); it != held_.end();) {
    if (everything || !sweep_known_ || it->release_at <= sweep_point_.time_ns) {
      const HeldVehicle held = std::move(*it);
      it = held_.erase(it);
      correct_held(held, now, result);
    } else {
      ++it;
    }
  }
}

perception::VehicleFix RsuCore::fix_announced(std::span<const Eigen::Vector3d> points,
                                              const v2i::VehicleAnnouncement& a, TimeNs sweep_time) const {
  // The yaw prior: the announced yaw carried to the sweep time with the announced motion (the
  // hypothesis model), with its grown uncertainty.
  const v2i::VehicleHypothesis at_sweep = v2i::predict_hypothesis(a, sweep_time, config_.hypothesis);
  const double yaw_var = at_sweep.covariance(2, 2);
  perception::AnnouncedVehicle vehicle;
  vehicle.size = {a.size.length_m, a.size.width_m, a.size.height_m};
  if (std::isfinite(at_sweep.yaw) && std::isfinite(yaw_var) && yaw_var >= 0.0) {
    vehicle.yaw_prior = perception::YawPrior{at_sweep.yaw, std::max(std::sqrt(yaw_var), 1e-3)};
  }
  return perception::fix_vehicle(points, vehicle, sensor_to_map_.translation(), config_.perception.fix);
}

void RsuCore::correct_held(const HeldVehicle& held, TimeNs now, LidarStepResult& result) {
  const v2i::RegisteredVehicle* vehicle = registry_.find(held.vehicle_id, now);
  if (vehicle == nullptr || held.footprint.empty())
    return;
  const v2i::VehicleAnnouncement& a = vehicle->announcement;
  // A near vehicle was held because its assigned cluster lay outside its footprint (gather()); if no
  // cluster of its own came while the sweep passed it, that one is more likely a neighbour's (its own
  // hidden, or its packets lost): no fix rather than someone else's.
  if (!held.far && held.assigned_part_size > 0 && !held.assigned_own) {
    ++lidar_stats_.clusters_unmatched;
    return;
  }

  std::vector<Eigen::Vector3d> gathered(held.footprint.size());
  for (std::size_t i = 0; i < gathered.size(); ++i)
    gathered[i] = {held.footprint[i].x(), held.footprint[i].y(), static_cast<double>(held.heights[i])};
  std::span<const Eigen::Vector3d> points(gathered);
  TimeNs sweep_time = held.first_time + held.weighted_offset / static_cast<TimeNs>(held.footprint.size());
  perception::VehicleFix fix = fix_announced(points, a, sweep_time);
  const auto fits_vehicle = [&](const perception::RectangleFit& f, TimeNs t, std::size_t n) {
    const v2i::FittedCluster as_cluster{f.center, f.yaw, f.length0, f.length1, n};
    return f.ok() &&
           v2i::check_pair(as_cluster, v2i::predict_hypothesis(a, t, config_.hypothesis), config_.association)
                   .verdict == v2i::PairGate::kPass;
  };
  if (held.parts > 1) {
    if (fits_vehicle(fix.fit, sweep_time, points.size())) {
      lidar_stats_.fragments_merged += held.parts - 1;
    } else {
      // The union is not one vehicle of this size (something else was inside the footprint): the
      // cluster the assignment chose, alone; the correction's consistency check guards it. Without
      // one, every part was only gathered (inside the grown footprint): none is known to be this
      // vehicle's rather than a neighbour's, so no fix.
      lidar_stats_.clusters_unmatched += held.parts - 1;
      if (held.assigned_part_size == 0) {
        ++lidar_stats_.corrections_failed;
        return;
      }
      points = points.subspan(held.assigned_part_begin, held.assigned_part_size);
      sweep_time = held.assigned_part_time;
      fix = fix_announced(points, a, sweep_time);
    }
  }
  if (!fix.fit.ok()) {
    ++lidar_stats_.corrections_failed;
    return;
  }
  if ((fix.fit.center - lidar_xy_).norm() > config_.coverage_radius_m) {
    ++lidar_stats_.clusters_out_of_coverage;
    return;
  }
  if (fix.status() == perception::CorrectionStatus::inconsistent_box ||
      fix.status() == perception::CorrectionStatus::ambiguous_position) {
    ++lidar_stats_.corrections_inconsistent;
    return;
  }
  if (!fix.ok()) {
    ++lidar_stats_.corrections_failed;
    return;
  }
  VehicleChannel& channel = channels_[a.vehicle_id];
  CorrectionInputs inputs;
  inputs.rsu_id = config_.rsu_id;
  inputs.vehicle_id = a.vehicle_id;
  inputs.sequence = channel.next_sequence;
  inputs.announcement_sequence = a.sequence;
  inputs.sweep_time = sweep_time;
  inputs.points_used = fix.points_used;
  OutgoingCorrection out;
  out.correction = make_correction(inputs, fix.corrected, fix.fit, lidar_xy_);
  out.bytes = signer_.encode(out.correction, now);
  if (out.bytes.empty()) {
    ++lidar_stats_.corrections_encode_failed;
    return;
  }
  out.destination = a.reply_to;
  ++channel.next_sequence;  // wraps modulo 2^32, as the wire says
  channel.matched = true;
  channel.last_matched_sweep = sweep_time;
  ++lidar_stats_.corrections;
  result.corrections.push_back(std::move(out));
}

std::size_t RsuCore::expire(TimeNs now) {
  const std::size_t n = registry_.expire(now);
  flood_limiter_.prune(now);
  peer_flood_limiter_.prune(now);
  authenticator_.expire(now);
  for (auto it = channels_.begin(); it != channels_.end();) {
    it = registry_.find(it->first, now) == nullptr ? channels_.erase(it) : std::next(it);
  }
  return n;
}

ReloadSummary RsuCore::reload(const RsuCoreConfig& next, TimeNs now) {
  RsuCore fresh(next);  // throws, leaving *this untouched, if `next` is unusable
  ReloadSummary summary;
  summary.vehicles_before = registry_.active(now).size();
  if (same_registry_setup(config_.registry, next.registry)) {
    fresh.registry_ = std::move(registry_);
  } else {
    // Re-enter the vehicles in the order they were last heard, at those times (a fresh rate limiter
    // starts full, so only a source with more vehicles than its burst loses some).
    auto active = registry_.active(now);
    std::sort(active.begin(), active.end(),
              [](const auto* a, const auto* b) { return a->last_heard < b->last_heard; });
    for (const v2i::RegisteredVehicle* v : active)
      fresh.registry_.upsert(v->announcement, v->source, v->last_heard);
  }
  summary.vehicles_after = fresh.registry_.active(now).size();
  summary.background_kept = same_background_setup(config_, next);
  if (summary.background_kept) {
    fresh.background_ = std::move(background_);
    fresh.background_ready_ = background_ready_;
    fresh.lidar_stats_.background_frames = lidar_stats_.background_frames;
  }
  if (same_sensor_setup(config_, next))
    fresh.decoder_ = std::move(decoder_);  // its counters and measured rate go on
  fresh.channels_ = std::move(channels_);
  fresh.authenticator_ = std::move(authenticator_);
  fresh.authenticator_.reconfigure(next.security, next.trust_list);
  fresh.signer_ =
      v2i::MessageSigner(next.security.mode == v2i::SecurityMode::kSigned ? next.signing_key : std::nullopt,
                         signer_.next_sequence());
  fresh.datagram_stages_ = datagram_stages_;
  fresh.peer_stages_ = peer_stages_;
  fresh.decode_counts_ = decode_counts_;
  *this = std::move(fresh);
  return summary;
}

std::vector<std::uint8_t> RsuCore::advertisement(TimeNs now) {
  v2i::RsuAdvertisement ad;
  ad.rsu_id = config_.rsu_id;
  ad.lidar_pose = config_.mount;
  ad.coverage_radius_m = config_.coverage_radius_m;
  ad.correction_port = config_.correction_port;
  ad.announcement_port = config_.announcement_port;
  return signer_.encode(ad, now);
}

std::vector<std::pair<std::string, std::uint64_t>> RsuCore::counters() const {
  std::vector<std::pair<std::string, std::uint64_t>> out;
  for (std::size_t i = 0; i < static_cast<std::size_t>(DatagramStage::kCount); ++i) {
    const auto s = static_cast<DatagramStage>(i);
    out.emplace_back(std::string("datagram.") + to_string(s), datagram_stages_.count(s));
  }
  for (std::size_t i = 0; i < static_cast<std::size_t>(DatagramStage::kCount); ++i) {
    const auto s = static_cast<DatagramStage>(i);
    out.emplace_back(std::string("peer.") + to_string(s), peer_stages_.count(s));
  }
  for (std::size_t i = 1; i < static_cast<std::size_t>(v2i::DecodeStatus::kCount); ++i) {
    const auto s = static_cast<v2i::DecodeStatus>(i);
    out.emplace_back(std::string("decode.") + v2i::to_string(s), decode_counts_.count(s));
  }
  for (std::size_t i = 0; i < static_cast<std::size_t>(v2i::AuthVerdict::kCount); ++i) {
    const auto v = static_cast<v2i::AuthVerdict>(i);
    out.emplace_back(std::string("auth.") + v2i::to_string(v), authenticator_.counts().count(v));
  }
  out.emplace_back("auth.signers_tracked", authenticator_.replay().tracked());
  out.emplace_back("auth.sequence_restarts", authenticator_.replay().stats().restarts);
  out.emplace_back("auth.signers_evicted", authenticator_.replay().stats().evictions);
  out.emplace_back("auth.trusted_keys", authenticator_.trust_list().size());
  // 1 while running without signatures: local development only (the daemon also warns).
  out.emplace_back("security.insecure_mode", authenticator_.mode() == v2i::SecurityMode::kInsecure ? 1 : 0);
  for (std::size_t i = 1; i < static_cast<std::size_t>(v2i::AnnouncementReason::kCount); ++i) {
    const auto r = static_cast<v2i::AnnouncementReason>(i);
    out.emplace_back(std::string("validation.") + v2i::to_string(r), validator_.counts().count(r));
  }
  for (std::size_t i = 0; i < static_cast<std::size_t>(v2i::UpsertOutcome::kCount); ++i) {
    const auto o = static_cast<v2i::UpsertOutcome>(i);
    out.emplace_back(std::string("registry.") + v2i::to_string(o), registry_.stats().outcomes.count(o));
  }
  out.emplace_back("registry.expired", registry_.stats().expired);
  out.emplace_back("registry.vehicles", registry_.size());
  // The decoder's outcomes as packet.<outcome>, its informational counts as decoder.<name>.
  for (const auto& [name, value] : decoder_->counters()) {
    if (name.starts_with("note."))
      out.emplace_back("decoder." + name.substr(5), value);
    else
      out.emplace_back("packet." + name, value);
  }
  const PacketOrderStats& o = packet_order_.stats();
  out.emplace_back("packet.lost", o.lost);
  out.emplace_back("packet.reordered", o.reordered);
  out.emplace_back("packet.late_dropped", o.late);
  out.emplace_back("packet.duplicate", o.duplicate);
  out.emplace_back("packet.stream_gaps", o.stream_gaps);
  out.emplace_back("packet.too_late", lidar_stats_.packets_too_late);
  out.emplace_back("packet.clock_offset", lidar_stats_.packets_clock_offset);
  const SweepClustererStats& s = clusterer_.stats();
  out.emplace_back("sweep.foreground_points", s.foreground_points);
  out.emplace_back("sweep.clusters_released", s.clusters_released);
  out.emplace_back("sweep.clusters_dropped_small", s.clusters_dropped_small);
  out.emplace_back("sweep.clusters_dropped_large", s.clusters_dropped_large);
  out.emplace_back("sweep.points_dropped_stale", s.points_dropped_stale);
  out.emplace_back("sweep.points_dropped_overflow", s.points_dropped_overflow);
  out.emplace_back("sweep.points_dropped_restart", s.points_dropped_restart);
  out.emplace_back("sweep.invalid_points", s.invalid_points);
  out.emplace_back("sweep.restarts", s.restarts);
  const LidarStats& l = lidar_stats_;
  out.emplace_back("lidar.background_frames", l.background_frames);
  out.emplace_back("lidar.fits_failed", l.fits_failed);
  out.emplace_back("lidar.clusters_out_of_coverage", l.clusters_out_of_coverage);
  out.emplace_back("lidar.clusters_unmatched", l.clusters_unmatched);
  out.emplace_back("lidar.fragments_merged", l.fragments_merged);
  out.emplace_back("lidar.corrections_failed", l.corrections_failed);
  out.emplace_back("lidar.corrections_inconsistent", l.corrections_inconsistent);
  out.emplace_back("lidar.corrections_encode_failed", l.corrections_encode_failed);
  out.emplace_back("lidar.corrections", l.corrections);
  return out;
}

}  // namespace rsu::core
