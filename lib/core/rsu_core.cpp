// SPDX-License-Identifier: Apache-2.0
#include "core/rsu_core.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>

#include "common/angles.h"
#include "common/counter_list.h"
#include "tracking/association.h"

namespace rsu::core {
namespace {

// `config` after the checks its parts do not make themselves (the decoder checks the sensor).
const RsuCoreConfig& checked(const RsuCoreConfig& config) {
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
  return config;
}

// The release rule's margin grows by how far beams may lead the rotor at their firing (the VLP-32C's
// precision azimuth: sensor_model.h), so that the exact rule stays exact.
perception::SweepConfig sweep_config(const RsuCoreConfig& config, const lidar::SweepGeometry& geometry) {
  perception::SweepConfig c = config.sweep;
  c.release_margin_deg += rad_to_deg(geometry.azimuth_lead_rad);
  return c;
}

lidar::FrameAssemblerConfig assembler_config(const lidar::SweepGeometry& geometry) {
  lidar::FrameAssemblerConfig c;
  c.rotation_hz = geometry.rotation_hz;
  c.cut_azimuth_deg = rad_to_deg(geometry.rotation_start_azimuth_rad);
  return c;
}

// Whether a learned background stays valid under `b`: it depends on the sensor, its pose and the
// background model's parameters only.
bool same_background_setup(const RsuCoreConfig& a, const RsuCoreConfig& b) {
  return a.sensor_model == b.sensor_model && a.sensor_options == b.sensor_options && a.mount == b.mount &&
         perception::background_model_config(a.perception) ==
             perception::background_model_config(b.perception);
}

void append(LidarStepResult& into, LidarStepResult&& step) {
  for (OutgoingCorrection& c : step.corrections)
    into.corrections.push_back(std::move(c));
  for (OutgoingNotice& n : step.withheld_notices)
    into.withheld_notices.push_back(std::move(n));
  into.background_became_ready = into.background_became_ready || step.background_became_ready;
}

}  // namespace

RsuCore::RsuCore(const RsuCoreConfig& config)
    : config_(checked(config)),
      mount_(config.mount),
      packets_(config),
      assembler_(assembler_config(packets_.decoder().geometry())),
      background_(perception::background_model_config(config.perception), mount_.xy()),
      clusterer_(sweep_config(config, packets_.decoder().geometry()), config.perception.clustering,
                 mount_.xy(), packets_.decoder().geometry().rotation_hz,
                 packets_.decoder().geometry().ring_azimuth_offset_rad),
      sweep_(mount_, config.perception.clustering.tolerance_m, config.sweep.release_margin_deg,
             packets_.decoder().geometry()),
      background_ready_(config.background.learning_frames == 0),
      announcements_(config),
      gatherer_(config.gathering, config.association, mount_.xy()),
      occluders_(mount_.xy(), sweep_.rotation_period_ns()),
      fixer_(std::make_shared<const GatheredVehicleFixer>(config, mount_)),
      tracks_(config.footprint_track),
      corrections_(config),
      refusals_(config.refusal_notices),
      withheld_(config.withheld_notices),
      monitor_assembler_(assembler_config(packets_.decoder().geometry())) {}

DatagramOutcome RsuCore::on_datagram(std::span<const std::uint8_t> bytes, const SourceEndpoint& source,
                                     TimeNs now, const v2i::SignatureCheck* checked,
                                     std::optional<TimeNs> received) {
  DatagramOutcome out = announcements_.on_datagram(bytes, source, now, checked, received);
  if (const auto notice = refusals_.consider(out, config_.rsu_id, now))
    out.refusal_notice = corrections_.notice(*notice, now);
  return out;
}

// The map of the daemon: one batch of the sweep, through the paper's steps (docs/architecture.md).
LidarStepResult RsuCore::process(std::span<const lidar::LidarPoint> points, Release release, TimeNs now) {
  // Foreground: the static scene removed point by point (the learned background, paper Sec. 4.1).
  for (const lidar::LidarPoint& p : points)
    clusterer_.add(p, background_.classify(p) == perception::PointClass::foreground);
  sweep_.advance(points);
  // Clusters: Euclidean clustering, each cluster released as soon as the sweep has passed it (or its
  // vehicle's fixed box: released open, prepared_fixes.h).
  std::vector<perception::SweptCluster> clusters = release == Release::everything
                                                       ? clusterer_.release_all()
                                                       : clusterer_.release_closed(fixed_open_swept());
  std::erase_if(fixed_open_, [&](const FixedOpenCluster& f) {
    return std::any_of(clusters.begin(), clusters.end(),
                       [&](const perception::SweptCluster& c) { return c.id == f.name.id; });
  });
  unfinished_current_ = false;  // the clusters open now (occluders_of)
  // Fit: a rectangle for each cluster (L-shape fitting, paper Sec. 3.1).
  std::vector<perception::Detection> detections = detect(std::move(clusters));
  if (!detections.empty()) {
    // Predict: the announced vehicles carried to the batch's sweep time.
    const std::vector<tracking::VehicleHypothesis> vehicles = predict_announced(detections, now);
    // Associate: which detection is which vehicle (gates, one global assignment).
    const tracking::AssociationResult pairs = tracking::associate(detections, vehicles, config_.association);
    // Gather: each vehicle's detections, across batches, until the sweep has passed it (fragments);
    // every detection is also what may hide part of another vehicle from the LiDAR.
    occluders_.add(detections);
    lidar_stats_.clusters_unmatched += gatherer_.gather(std::move(detections), vehicles, pairs, sweep_);
  }
  // Fix and correction: each vehicle the sweep has passed, size-corrected with its announced size
  // (paper Sec. 3.2, Algorithm 1 or the improved correction), its correction to send.
  LidarStepResult result;
  for (const HeldVehicle& held : gatherer_.release(release == Release::everything, sweep_))
    correct(held, now, result);
  if (release == Release::passed && config_.prepare_fixes)
    prepare_due_ = now;  // after the corrections are sent (prepare_pending)
  else
    prepare_due_.reset();
  return result;
}

void RsuCore::prepare_pending() {
  // Twice at most: the fitted clusters' vehicles are fixed in the second (record_prepared chains them).
  for (Preparation p = take_preparation(); !p.empty(); p = take_preparation())
    record_prepared(prepare(std::move(p)));
}

std::vector<perception::Detection> RsuCore::detect(std::vector<perception::SweptCluster>&& clusters) {
  std::vector<perception::Detection> detections;
  for (const perception::SweptCluster& cluster : clusters) {
    if (cluster.points.empty())
      continue;
    auto d = prepared_.fit(cluster.points, *fixer_);
    d.ahead_of_open = cluster.ahead_of_open;
    d.open_beyond = cluster.open_beyond;
    ++lidar_stats_.clusters_fitted;
    if (!d.fit.ok()) {
      ++lidar_stats_.fits_failed;  // too small or thin to fit alone, but maybe a fragment of a vehicle
    } else if ((d.fit.center - mount_.xy()).norm() > config_.coverage_radius_m) {
      ++lidar_stats_.clusters_out_of_coverage;
      continue;
    }
    detections.push_back(std::move(d));
  }
  return detections;
}

// The registered vehicles not corrected yet in this rotation, predicted to the batch's sweep time: the
// median of its detections' (they were swept within a few degrees of each other).
std::vector<tracking::VehicleHypothesis> RsuCore::predict_announced(
    std::span<const perception::Detection> detections, TimeNs now) {
  std::vector<TimeNs> times;
  for (const perception::Detection& d : detections)
    times.push_back(d.sweep_time_ns);
  std::nth_element(times.begin(), times.begin() + static_cast<std::ptrdiff_t>(times.size() / 2), times.end());
  const TimeNs batch_time = times[times.size() / 2];
  std::vector<tracking::VehicleHypothesis> vehicles;
  for (const v2i::RegisteredVehicle* v : announcements_.registry().active(now)) {
    if (!corrections_.corrected_this_rotation(v->announcement.vehicle_id, batch_time,
                                              sweep_.rotation_period_ns()))
      vehicles.push_back(tracking::predict_hypothesis(v->announcement, batch_time, config_.hypothesis));
  }
  lidar_stats_.vehicles_in_batches += vehicles.size();
  return vehicles;
}

void RsuCore::correct(const HeldVehicle& held, TimeNs now, LidarStepResult& result) {
  const v2i::RegisteredVehicle* vehicle = announcements_.registry().find(held.vehicle_id, now);
  if (vehicle == nullptr || held.points.empty())
    return;
  // Packets lost while the sweep crossed the vehicle (or just before its first points: its leading part
  // may be what was lost).
  const bool lost = lost_near(held);
  GatheredFix fix =
      prepared_.fix(*fixer_, held, vehicle->announcement, lost, occluders_of(held), lidar_stats_);
  // Combined with what earlier rotations bounded (footprint_track.h); a stopped mount breaks every chain.
  if (mount_serving())
    tracks_.combine(fix, vehicle->announcement, held.assigned_size > 0, sweep_.rotation_period_ns(),
                    perception::max_position_sigma_m(!lost, config_.perception.fix.correction),
                    config_.hypothesis, lidar_stats_);
  else
    tracks_.reset(lidar_stats_);
  count(fix, lidar_stats_);
  if (fix.ok() && !mount_serving())
    ++lidar_stats_.corrections_withheld_mount;  // the LiDAR moved: its fixes are off (rsu_core.h)
  if (!fix.ok() || !mount_serving()) {
    tell_withheld(fix, vehicle->announcement, lost, now, result);
    return;
  }
  std::optional<OutgoingCorrection> out =
      corrections_.build(vehicle->announcement, fix.fix, fix.sweep_time, now);
  if (!out) {
    ++lidar_stats_.corrections_encode_failed;
    return;
  }
  ++lidar_stats_.corrections;
  result.corrections.push_back(std::move(*out));
}

void RsuCore::tell_withheld(const GatheredFix& fix, const v2i::VehicleAnnouncement& a, bool lost_nearby,
                            TimeNs now, LidarStepResult& result) {
  if (!withheld_.enabled())
    return;
  // A vehicle withheld because the LiDAR moved is told so too, though the advertisement says it: that
  // goes to one configured address, off by default, where a vehicle may not listen; this to the vehicle.
  std::optional<v2i::FixWithheld> notice = withheld_notice(
      fix, a, config_.rsu_id, lost_nearby, fixes_withheld(), config_.perception.fix.correction);
  // A later release of a vehicle corrected in this rotation holds what lay beside or ahead of it.
  if (!notice ||
      corrections_.corrected_this_rotation(a.vehicle_id, fix.sweep_time, sweep_.rotation_period_ns()))
    return;
  notice = withheld_.consider(std::move(*notice), now);
  std::vector<std::uint8_t> bytes = notice ? corrections_.notice(*notice, now) : std::vector<std::uint8_t>{};
  if (!bytes.empty())
    result.withheld_notices.push_back({a.reply_to, std::move(bytes), std::move(*notice)});
}

LidarStepResult RsuCore::on_lidar_packet(std::span<const std::uint8_t> payload, TimeNs now) {
  LidarStepResult result;
  const PacketIntakeStep step = packets_.push(payload, now);
  result.packet = step.packet;
  if (!step.packet.is_data())
    return result;  // counted by the decoder, by kind and reason
  follow_geometry();
  if (step.clock_refused) {
    ++lidar_stats_.packets_clock_offset;
    return result;
  }
  if (step.shedding_began)
    clusterer_.restart();  // what is open now lacks the shed points: never fitted as whole
  if (step.shed) {
    ++lidar_stats_.packets_too_late;
    return result;
  }
  while (packets_.pop(ordered_scratch_)) {
    if (packets_.order_stats().lost != packets_lost_ && !ordered_scratch_.empty()) {
      packets_lost_ = packets_.order_stats().lost;
      last_loss_ns_ = ordered_scratch_.front().time_ns;
    }
    append(result, on_lidar_points(ordered_scratch_, now));
  }
  return result;
}

LidarStepResult RsuCore::on_lidar_points(std::span<const lidar::LidarPoint> points, TimeNs now) {
  if (!background_ready_)
    return learn(points, false);
  prepare_pending();  // what the caller left (rsu_core.h)
  check_mount_pending();
  mount_.to_map_frame(points, map_scratch_);
  LidarStepResult result = process(map_scratch_, Release::passed, now);
  watch_mount(points, false);  // after the corrections: the check waits for check_mount_pending()
  return result;
}

LidarStepResult RsuCore::on_lidar_frame(std::span<const lidar::LidarPoint> points, TimeNs now) {
  if (!background_ready_)
    return learn(points, true);
  prepare_pending();
  check_mount_pending();
  mount_.to_map_frame(points, map_scratch_);
  LidarStepResult result = process(map_scratch_, Release::everything, now);  // every vehicle swept
  watch_mount(points, true);
  return result;
}

LidarStepResult RsuCore::flush(TimeNs now) {
  LidarStepResult result;
  while (packets_.pop(ordered_scratch_, true))
    append(result, on_lidar_points(ordered_scratch_, now));
  if (background_ready_)
    append(result, process({}, Release::everything, now));
  return result;
}

void RsuCore::follow_geometry() {
  const lidar::SweepGeometry& g = packets_.decoder().geometry();
  sweep_.follow(g);
  // A rotation rate measured anew (the decoder smooths it packet by packet): passed on when it moved
  // by more than 0.1 %, which is what unwrapping across gaps and the rotation period need.
  if (std::abs(g.rotation_hz - sweep_.rotation_hz()) <= 1e-3 * sweep_.rotation_hz())
    return;
  sweep_.set_rotation_hz(g.rotation_hz);
  assembler_.set_rotation_hz(g.rotation_hz);
  monitor_assembler_.set_rotation_hz(g.rotation_hz);
  clusterer_.set_rotation_hz(g.rotation_hz);
  occluders_.set_rotation_period(sweep_.rotation_period_ns());
}

std::vector<std::string> RsuCore::take_lidar_notices() {
  std::vector<std::string> notices = packets_.take_notices();
  for (std::string& n : mount_notices_)
    notices.push_back(std::move(n));
  mount_notices_.clear();
  return notices;
}

void RsuCore::add_background_frame(std::vector<lidar::LidarPoint>&& sensor_points) {
  // Kept as it came, moved, not copied: a 128 x 2048 rotation is 8 MB, and writing 8 MB of memory
  // touched for the first time took 31-34 ms here (1 ms warm), on the loop.
  background_frames_->push_back(std::move(sensor_points));
  const std::vector<lidar::LidarPoint>& frame = background_frames_->back();
  mount_.to_map_frame(frame, map_scratch_);
  background_.add_background_frame(map_scratch_);
  const perception::GroundHeightFilterConfig& ground = config_.perception.ground;
  occluders_.add_static(map_scratch_, ground.ground_z + ground.min_height);
  ++lidar_stats_.background_frames;
}

LidarStepResult RsuCore::learn(std::span<const lidar::LidarPoint> sensor_points, bool whole_frame) {
  LidarStepResult result;
  if (whole_frame) {
    add_background_frame({sensor_points.begin(), sensor_points.end()});
  } else {
    for (lidar::LidarFrame& frame : assembler_.add(sensor_points))
      add_background_frame(std::move(frame.points));
  }
  if (static_cast<int>(lidar_stats_.background_frames) >= config_.background.learning_frames) {
    background_ready_ = true;
    result.background_became_ready = true;
    start_mount_monitor();
  }
  return result;
}

void RsuCore::load_background(const std::vector<std::vector<lidar::LidarPoint>>& frames,
                              bool saved_by_earlier_run) {
  for (const auto& frame : frames)
    add_background_frame(std::vector<lidar::LidarPoint>(frame));
  background_ready_ = true;
  start_mount_monitor();
  mount_unverified_ = saved_by_earlier_run && monitor_due_;  // it may have moved since (rsu_core.h)
}

std::size_t RsuCore::expire(TimeNs now) {
  const std::size_t n = announcements_.expire(now);
  corrections_.forget_unregistered(announcements_.registry(), now);
  refusals_.prune(now);
  withheld_.prune(now);
  tracks_.prune(now - kNsPerSecond);
  return n;
}

ReloadSummary RsuCore::reload(const RsuCoreConfig& next, TimeNs now) {
  RsuCore fresh(next);  // throws, leaving *this untouched, if `next` is unusable
  ReloadSummary summary;
  summary.vehicles_before = announcements_.registry().active(now).size();
  fresh.announcements_ = std::move(announcements_).reloaded(next, now);
  summary.vehicles_after = fresh.announcements_.registry().active(now).size();
  summary.background_kept = same_background_setup(config_, next);
  if (summary.background_kept) {
    fresh.background_ = std::move(background_);
    fresh.background_ready_ = background_ready_;
    fresh.background_frames_ = std::move(background_frames_);
    fresh.occluders_.take_static(std::move(occluders_));
    fresh.monitor_ = std::move(monitor_);
    fresh.monitor_due_ = monitor_due_;
    fresh.monitor_building_ = monitor_building_;
    fresh.mount_unverified_ = mount_unverified_;
    fresh.lidar_stats_.background_frames = lidar_stats_.background_frames;
  }
  fresh.packets_ = std::move(packets_).reloaded(next);
  fresh.sweep_.follow(fresh.packets_.decoder().geometry());
  fresh.corrections_ = std::move(corrections_).reloaded(next);
  fresh.refusals_ = refusals_.reloaded(next.refusal_notices);
  fresh.withheld_ = withheld_.reloaded(next.withheld_notices);
  *this = std::move(fresh);
  return summary;
}

void RsuCore::report(CounterList& out) const {
  announcements_.report(out);
  refusals_.report(out);
  withheld_.report(out);
  packets_.report(out);
  core::report(packets_.order_stats(), clusterer_.stats(), lidar_stats_, out);
  packets_.report_clock(out);
  core::report_mount(monitor_ ? &*monitor_ : nullptr, mount_rotations_gappy_, out);
}

std::vector<std::pair<std::string, std::uint64_t>> RsuCore::counters() const {
  CounterList out;
  report(out);
  return out.entries();
}

}  // namespace rsu::core
