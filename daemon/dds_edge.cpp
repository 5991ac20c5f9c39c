// SPDX-License-Identifier: Apache-2.0
#include "daemon/dds_edge.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <sstream>

#include "daemon/dds_config.h"
#include "dds/pose_messages.h"
#include "edge/host_clock.h"
#include "ros/correction_pose.h"
#include "ros/ros_time.h"

namespace rsu::daemon {

namespace {

using dds::to_msg_time;

void fill_pose(const v2i::Correction& c, geometry_msgs_msg_dds__PoseWithCovariance_& out) {
  dds::to_msg_pose(ros::to_ros_pose(c), out);
}

// Percentile (0..1) of `values` by nearest rank; 0 when empty.
std::int64_t percentile(std::vector<std::int64_t> values, double q) {
  if (values.empty())
    return 0;
  const auto k = static_cast<std::size_t>(q * static_cast<double>(values.size() - 1) + 0.5);
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
  return values[k];
}

}  // namespace

DdsEdge::DdsEdge(boost::asio::io_context& io, const DdsConfig& config, std::uint64_t rsu_id,
                 BadInputLog& bad_input)
    : io_(io), config_(config), rsu_id_(rsu_id), bad_input_(bad_input), participant_(config.participant) {
  if (!config_.object_list_topic.empty()) {
    object_list_topic_ = std::make_unique<dds::Topic>(participant_, dds::ros_topic(config_.object_list_topic),
                                                      rsu_msgs_msg_dds__VehicleFixArray__desc);
    object_list_writer_ =
        std::make_unique<dds::Writer<FixArray>>(participant_, *object_list_topic_, config_.object_list_qos);
  }
  spdlog::info("dds: participant in domain {}{}", participant_.domain_id(),
               config_.participant.cyclone_config.empty()
                   ? std::string()
                   : " configured by " + config_.participant.cyclone_config);
}

DdsEdge::~DdsEdge() {
  cloud_reader_.reset();  // no listener call runs past this point
}

void DdsEdge::start_input(const DdsPointCloud2Input& input, std::span<const double> elevation_deg,
                          CloudHandler on_cloud) {
  input_ = input;
  on_cloud_ = std::move(on_cloud);
  if (input.ring_order == ros::RingOrder::kElevation)
    ring_map_ = ros::ring_rank_to_channel(elevation_deg);
  cloud_topic_ = std::make_unique<dds::Topic>(participant_, dds::ros_topic(input.topic),
                                              sensor_msgs_msg_dds__PointCloud2__desc);
  cloud_reader_ = std::make_unique<dds::Reader<PointCloud2>>(participant_, *cloud_topic_, input.qos,
                                                             [this] { on_data_available(); });
  spdlog::info("dds: subscribed to PointCloud2 on {} ({})", cloud_topic_->name(),
               input.whole_rotation ? "each message one rotation" : "each message a part of a rotation");
  // Samples that arrived before the listener was attached would otherwise wait for the next one.
  on_data_available();
}

void DdsEdge::on_data_available() {
  if (!take_posted_.exchange(true))
    boost::asio::post(io_, [this] { take_clouds(); });
}

void DdsEdge::take_clouds() {
  take_posted_.store(false);
  try {
    cloud_reader_->take(
        64, [this](const PointCloud2& cloud, const dds_sample_info_t& info) { on_cloud(cloud, info); });
  } catch (const dds::DdsError& e) {
    bad_input_.report("dds_take", e.what());
  }
}

void DdsEdge::on_cloud(const PointCloud2& cloud, const dds_sample_info_t& info) {
  const TimeNs taken = edge::host_now_ns();
  ++clouds_received_;
  if (take_latency_ns_.size() < kLatencyWindow)
    take_latency_ns_.push_back(taken - info.source_timestamp);
  else
    take_latency_ns_[next_latency_++ % kLatencyWindow] = taken - info.source_timestamp;

  const auto stamp = dds::from_msg_time(cloud.header.stamp);
  if (!stamp) {
    ++clouds_bad_stamp_;
    bad_input_.report("dds_pointcloud2.bad_stamp",
                      "header.stamp.nanosec " + std::to_string(cloud.header.stamp.nanosec) + " >= 1e9");
    return;
  }
  const char* frame = cloud.header.frame_id != nullptr ? cloud.header.frame_id : "";
  if (!input_.frame_id.empty() && input_.frame_id != frame) {
    ++clouds_wrong_frame_;
    bad_input_.report("dds_pointcloud2.frame_id",
                      "header.frame_id \"" + std::string(frame) + "\", expected \"" + input_.frame_id + "\"");
    return;
  }
  std::vector<ros::PointFieldView> fields;
  fields.reserve(cloud.fields._length);
  for (std::uint32_t i = 0; i < cloud.fields._length; ++i) {
    const auto& f = cloud.fields._buffer[i];
    fields.push_back(
        {f.name != nullptr ? std::string_view(f.name) : std::string_view(), f.offset, f.datatype, f.count});
  }
  ros::PointCloud2View view;
  view.stamp = *stamp;
  view.height = cloud.height;
  view.width = cloud.width;
  view.fields = fields;
  view.is_bigendian = cloud.is_bigendian;
  view.point_step = cloud.point_step;
  view.row_step = cloud.row_step;
  view.data = std::span<const std::uint8_t>(cloud.data._buffer, cloud.data._length);
  view.is_dense = cloud.is_dense;

  const ros::LayoutResult layout = ros::parse_layout(view);
  if (!layout.ok()) {
    ++clouds_rejected_[static_cast<std::size_t>(layout.reject)];
    bad_input_.report(std::string("dds_pointcloud2.") + ros::to_string(layout.reject),
                      std::to_string(cloud.width) + "x" + std::to_string(cloud.height) +
                          " points, point_step " + std::to_string(cloud.point_step) + ", row_step " +
                          std::to_string(cloud.row_step) + ", " + std::to_string(cloud.data._length) +
                          " bytes, " + std::to_string(cloud.fields._length) + " fields");
    return;
  }
  points_.clear();
  const ros::CloudDecodeStats s = ros::decode_points(view, layout.layout, ring_map_, points_);
  ++clouds_accepted_;
  points_accepted_ += s.points;
  points_non_finite_ += s.non_finite_skipped;  // organised clouds' holes: counted, not warned about
  points_bad_ring_ += s.bad_ring_skipped;
  points_bad_time_ += s.bad_time_skipped;
  if (s.bad_ring_skipped + s.bad_time_skipped > 0) {
    bad_input_.report("dds_pointcloud2.bad_points", std::to_string(s.bad_ring_skipped) + " bad rings, " +
                                                        std::to_string(s.bad_time_skipped) +
                                                        " bad times skipped in one cloud");
  }
  if (points_.empty()) {
    // Nothing to see (all holes, or width 0): not a rotation for the background to learn from either.
    ++clouds_empty_;
    return;
  }
  on_cloud_(points_, input_.whole_rotation);
}

void DdsEdge::publish(const std::vector<core::OutgoingCorrection>& corrections) {
  for (const core::OutgoingCorrection& out : corrections) {
    const v2i::Correction& c = out.correction;
    latest_fix_[c.vehicle_id] = c;
    if (config_.pose_topic.empty())
      continue;
    try {
      auto& slot = pose_writers_[c.vehicle_id];
      if (!slot) {
        dds::Topic topic(participant_, dds::ros_topic(vehicle_pose_topic(config_.pose_topic, c.vehicle_id)),
                         geometry_msgs_msg_dds__PoseWithCovarianceStamped__desc);
        dds::Writer<PoseStamped> writer(participant_, topic, config_.pose_qos);
        slot = std::make_unique<VehicleWriter>(VehicleWriter{std::move(topic), std::move(writer), 0});
      }
      PoseStamped msg{};
      msg.header.stamp = to_msg_time(c.sweep_time);  // when the LiDAR swept the vehicle (docs/design.md §3)
      msg.header.frame_id = config_.frame_id.data();
      fill_pose(c, msg.pose);
      slot->writer.write(msg);
      slot->last_fix = c.sweep_time;
      ++poses_published_;
    } catch (const std::exception& e) {
      ++pose_writes_failed_;
      bad_input_.report("dds_pose_write", "vehicle " + std::to_string(c.vehicle_id) + ": " + e.what());
    }
  }
}

void DdsEdge::publish_object_list(TimeNs now) {
  const TimeNs max_age = from_seconds(config_.object_list_max_age_s);
  std::vector<rsu_msgs_msg_dds__VehicleFix_> fixes;
  for (auto it = latest_fix_.begin(); it != latest_fix_.end();) {
    const v2i::Correction& c = it->second;
    if (now - c.sweep_time > max_age) {
      it = latest_fix_.erase(it);
      continue;
    }
    rsu_msgs_msg_dds__VehicleFix_ f{};
    f.vehicle_id = c.vehicle_id;
    f.fix_sequence = c.sequence;
    f.sweep_time = to_msg_time(c.sweep_time);
    fill_pose(c, f.pose);
    f.points_used = c.quality.points_used;
    f.faces_seen = c.quality.faces_seen;
    f.range_m = c.quality.range_m;
    f.yaw_resolution = static_cast<std::uint8_t>(c.quality.yaw_resolution);
    f.confidence = c.quality.confidence;
    fixes.push_back(f);
    ++it;
  }
  if (!object_list_writer_)
    return;
  std::sort(fixes.begin(), fixes.end(),
            [](const auto& a, const auto& b) { return a.vehicle_id < b.vehicle_id; });
  FixArray msg{};
  msg.header.stamp = to_msg_time(now);
  msg.header.frame_id = config_.frame_id.data();
  msg.rsu_id = rsu_id_;
  msg.fixes._buffer = fixes.data();
  msg.fixes._length = static_cast<std::uint32_t>(fixes.size());
  msg.fixes._maximum = msg.fixes._length;
  msg.fixes._release = false;
  try {
    object_list_writer_->write(msg);
    ++object_lists_published_;
  } catch (const dds::DdsError& e) {
    ++object_list_writes_failed_;
    bad_input_.report("dds_object_list_write", e.what());
  }
}

void DdsEdge::forget_quiet_vehicles(TimeNs now) {
  std::erase_if(pose_writers_,
                [now](const auto& kv) { return now - kv.second->last_fix > 60 * kNsPerSecond; });
}

void DdsEdge::report(CounterList& out) const {
  out.add("dds", "clouds_received", clouds_received_);
  out.add("dds", "clouds_accepted", clouds_accepted_);
  out.add("dds", "clouds_empty", clouds_empty_);
  out.add("dds", "clouds_rejected.bad_stamp", clouds_bad_stamp_);
  out.add("dds", "clouds_rejected.frame_id", clouds_wrong_frame_);
  for (std::size_t i = 1; i < clouds_rejected_.size(); ++i)
    out.add("dds", "clouds_rejected." + std::string(ros::to_string(static_cast<ros::CloudReject>(i))),
            clouds_rejected_[i]);
  out.add("dds", "points_accepted", points_accepted_);
  out.add("dds", "points_skipped.non_finite", points_non_finite_);
  out.add("dds", "points_skipped.bad_ring", points_bad_ring_);
  out.add("dds", "points_skipped.bad_time", points_bad_time_);
  out.add("dds", "poses_published", poses_published_);
  out.add("dds", "pose_writes_failed", pose_writes_failed_);
  out.add("dds", "object_lists_published", object_lists_published_);
  out.add("dds", "object_list_writes_failed", object_list_writes_failed_);
  // Over the recent clouds kept for it (not since start).
  for (const auto& [name, q] :
       {std::pair{"take_latency_us.p50", 0.5}, {"take_latency_us.p99", 0.99}, {"take_latency_us.max", 1.0}})
    out.add_measured("dds", name, static_cast<double>(percentile(take_latency_ns_, q) / 1000));
}

std::string DdsEdge::stats_line() const {
  std::ostringstream out;
  std::uint64_t rejected = clouds_bad_stamp_ + clouds_wrong_frame_;
  for (const std::uint64_t n : clouds_rejected_)
    rejected += n;
  out << "dds: clouds_received=" << clouds_received_ << " clouds_rejected=" << rejected
      << " poses_published=" << poses_published_ << " pose_writes_failed=" << pose_writes_failed_
      << " object_lists_published=" << object_lists_published_;
  return out.str();
}

}  // namespace rsu::daemon
