// SPDX-License-Identifier: Apache-2.0
// rsud's DDS edge (issue 6): the participant, the PointCloud2 input and the pose / object-list
// outputs. Only moves samples: conversions are lib/ros's, decisions RsuCore's.
//
// Threading: Cyclone delivers on its own threads. The reader's data-available listener only posts
// one "take now" to rsud's io_context (coalesced by an atomic flag); samples are taken, converted and
// handed to RsuCore on the io_context thread, like every other input. Writes happen on that thread.
#pragma once

#include <utility>  // before Asio: Boost 1.74's awaitable.hpp uses std::exchange under C++20

#include <boost/asio.hpp>

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <ostream>
#include <span>
#include <string>
#include <unordered_map>
#include <vector>

#include "common/counter_list.h"
#include "core/rsu_core.h"
#include "daemon/bad_input_log.h"
#include "daemon/config.h"
#include "dds/participant.h"
#include "dds/typed_entities.h"
#include "geometry_msgs.h"
#include "lidar/point.h"
#include "rsu_msgs.h"
#include "sensor_msgs.h"

namespace rsu::daemon {

class DdsEdge {
 public:
  // Points of one PointCloud2, sensor frame; `whole_rotation` as configured for the input.
  using CloudHandler = std::function<void(std::span<const lidar::LidarPoint> points, bool whole_rotation)>;

  // Creates the participant and the object-list writer. Throws dds::DdsError / std::runtime_error.
  DdsEdge(boost::asio::io_context& io, const DdsConfig& config, std::uint64_t rsu_id, BadInputLog& bad_input);
  ~DdsEdge();
  DdsEdge(const DdsEdge&) = delete;
  DdsEdge& operator=(const DdsEdge&) = delete;

  // Subscribes to the PointCloud2 input. `elevation_deg` (the sensor model's, channel order) maps
  // elevation-ordered rings to channels when the input says ring_order: elevation.
  void start_input(const DdsPointCloud2Input& input, std::span<const double> elevation_deg,
                   CloudHandler on_cloud);

  // Each correction as PoseWithCovarianceStamped on its vehicle's topic; remembered for the object list.
  void publish(const std::vector<core::OutgoingCorrection>& corrections);
  // The current fixes (sweep time within object_list_max_age_s of `now`) as one VehicleFixArray.
  void publish_object_list(TimeNs now);
  // Drops the pose writers of vehicles without a fix for a minute (vehicles come and go).
  void forget_quiet_vehicles(TimeNs now);

  // For the other users of the bus in rsud (daemon/peer_bus.h): one participant per process.
  const dds::Participant& participant() const { return participant_; }

  // Its counters (the stats file and the metrics) and one log line.
  void report(CounterList& out) const;
  std::string stats_line() const;

 private:
  using PoseStamped = geometry_msgs_msg_dds__PoseWithCovarianceStamped_;
  using PointCloud2 = sensor_msgs_msg_dds__PointCloud2_;
  using FixArray = rsu_msgs_msg_dds__VehicleFixArray_;

  struct VehicleWriter {
    dds::Topic topic;
    dds::Writer<PoseStamped> writer;
    TimeNs last_fix = 0;
  };

  void on_data_available();  // Cyclone's thread
  void take_clouds();        // io_context thread
  void on_cloud(const PointCloud2& cloud, const dds_sample_info_t& info);

  boost::asio::io_context& io_;
  DdsConfig config_;
  std::uint64_t rsu_id_;
  BadInputLog& bad_input_;
  dds::Participant participant_;

  std::unique_ptr<dds::Topic> object_list_topic_;
  std::unique_ptr<dds::Writer<FixArray>> object_list_writer_;
  std::unordered_map<std::uint64_t, std::unique_ptr<VehicleWriter>> pose_writers_;
  std::unordered_map<std::uint64_t, v2i::Correction> latest_fix_;  // by vehicle

  DdsPointCloud2Input input_;
  std::vector<std::uint16_t> ring_map_;  // elevation rank -> channel, or empty
  CloudHandler on_cloud_;
  std::unique_ptr<dds::Topic> cloud_topic_;
  std::atomic<bool> take_posted_{false};
  std::unique_ptr<dds::Reader<PointCloud2>> cloud_reader_;  // last: deleted first (its listener posts)
  std::vector<lidar::LidarPoint> points_;                   // reused cloud after cloud

  // Counters (stats file); every rejection also goes to the rate-limited bad-input log.
  std::uint64_t clouds_received_ = 0;
  std::uint64_t clouds_accepted_ = 0;
  std::uint64_t clouds_empty_ = 0;  // accepted, but without a usable point
  std::uint64_t clouds_bad_stamp_ = 0;
  std::uint64_t clouds_wrong_frame_ = 0;
  std::array<std::uint64_t, static_cast<std::size_t>(ros::CloudReject::kCount)> clouds_rejected_{};
  std::uint64_t points_accepted_ = 0;
  std::uint64_t points_non_finite_ = 0;
  std::uint64_t points_bad_ring_ = 0;
  std::uint64_t points_bad_time_ = 0;
  std::uint64_t poses_published_ = 0;
  std::uint64_t pose_writes_failed_ = 0;
  std::uint64_t object_lists_published_ = 0;
  std::uint64_t object_list_writes_failed_ = 0;
  // Source timestamp -> taken on the io_context thread, the last kLatencyWindow clouds (ns).
  static constexpr std::size_t kLatencyWindow = 1024;
  std::vector<std::int64_t> take_latency_ns_;
  std::size_t next_latency_ = 0;
};

}  // namespace rsu::daemon
