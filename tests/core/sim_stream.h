// SPDX-License-Identifier: Apache-2.0
// Test helper: a simulated VLP-16 on a roadside mount sending real Velodyne packets (sim/ + the packet
// encoder), fed to RsuCore with hand-stepped time. The first `empty_rotations` and a half come from the
// scene without vehicles (the background the RSU learns), the rest from the same scene with them: the
// switch happens at azimuth 180 deg, where the tests put no vehicle, so no vehicle is swept half empty.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "common/angles.h"
#include "common/pose.h"
#include "core/rsu_core.h"
#include "lidar/sensor_model.h"
#include "lidar/velodyne_packet.h"
#include "sim/lidar_simulator.h"
#include "sim/scene.h"
#include "v2i/messages.h"

namespace rsu::core::testing {

// A street corner: ground, one building behind the road, a lamp post. The LiDAR stands off the
// origin and turned, so that the mount transform matters.
inline sim::Scene street_scene() {
  sim::Scene s;
  s.ground.half_extent_m = 80.0;
  s.buildings.push_back({.x = 10.0, .y = 35.0, .yaw = 0.0, .length = 40.0, .width = 10.0, .height = 12.0});
  s.poles.push_back({.x = -6.0, .y = 4.0, .radius = 0.15, .height = 6.0});
  return s;
}

inline Pose3 roadside_mount() {
  return {.x = 2.0, .y = -3.0, .z = 2.0, .roll = 0.0, .pitch = 0.0, .yaw = 0.3};
}

inline sim::Vehicle static_vehicle(std::uint32_t id, const Pose2& pose) {
  sim::Vehicle v;
  v.id = id;
  v.trajectory = sim::StaticPose{pose};
  return v;
}

class SimStream {
 public:
  SimStream(const std::vector<sim::Vehicle>& vehicles, int empty_rotations)
      : SimStream(street_scene(), vehicles, lidar::make_vlp16(), roadside_mount(), sim::NoiseModel{},
                  empty_rotations) {}

  // Any scene (its own vehicles ignored), sensor and mount.
  SimStream(const sim::Scene& scene, const std::vector<sim::Vehicle>& vehicles,
            const lidar::SensorModel& model, const Pose3& mount, const sim::NoiseModel& noise,
            int empty_rotations)
      : model_(model), empty_rotations_(empty_rotations) {
    sim::Scene empty = scene;
    empty.vehicles.clear();
    sim::Scene busy = empty;
    busy.vehicles = vehicles;
    empty_ = std::make_unique<sim::LidarSimulator>(model_, mount, noise, empty);
    busy_ = std::make_unique<sim::LidarSimulator>(model_, mount, noise, busy);
  }

  TimeNs rotation_ns() const { return busy_->rotation_period_ns(); }
  const lidar::SensorModel& model() const { return model_; }

  // Time at which packet k has been received (its last firing plus a little).
  TimeNs arrival(std::int64_t k) const {
    return busy_->simulate_packet(k).blocks.first_firing_ns + 1'400'000;
  }

  // Feeds packets [next, first packet at or after `until`) and calls on_step per packet.
  void run_until(RsuCore& core, TimeNs until,
                 const std::function<void(const LidarStepResult&, TimeNs now)>& on_step = {}) {
    run_until(core, nullptr, until, on_step);
  }
  // The same packets to `core` and to `twin` too (twin_corrections(): what it sent).
  void run_until(RsuCore& core, RsuCore* twin, TimeNs until,
                 const std::function<void(const LidarStepResult&, TimeNs now)>& on_step = {}) {
    const std::int64_t last = busy_->packet_index_at(until);
    const std::int64_t empty_packets =
        busy_->packet_index_at(rotation_ns() * empty_rotations_ + rotation_ns() / 2);
    std::array<std::uint8_t, lidar::kPacketBytes> payload{};
    for (; next_ <= last; ++next_) {
      const sim::LidarSimulator& source = next_ < empty_packets ? *empty_ : *busy_;
      const lidar::PacketReturns returns = source.simulate_packet(next_);
      lidar::encode_packet(model_, returns, payload);
      const TimeNs now = returns.blocks.first_firing_ns + 1'400'000;
      const LidarStepResult r = core.on_lidar_packet(payload, now);
      for (const auto& c : r.corrections)
        corrections_.push_back({c, now});
      for (const auto& c : twin != nullptr ? twin->on_lidar_packet(payload, now).corrections
                                           : std::vector<OutgoingCorrection>{})
        twin_corrections_.push_back({c, now});
      if (on_step)
        on_step(r, now);
    }
  }

  struct Received {
    OutgoingCorrection correction;
    TimeNs emitted_at;
  };
  const std::vector<Received>& corrections() const { return corrections_; }
  const std::vector<Received>& twin_corrections() const { return twin_corrections_; }

 private:
  lidar::SensorModel model_;
  int empty_rotations_;
  std::unique_ptr<sim::LidarSimulator> empty_;
  std::unique_ptr<sim::LidarSimulator> busy_;
  std::int64_t next_ = 0;
  std::vector<Received> corrections_;
  std::vector<Received> twin_corrections_;
};

// The port every test vehicle announces from and receives on (reply_to must be the source's).
inline constexpr std::uint16_t kVehiclePort = 40000;

// An announcement of a Lexus-sized vehicle (docs/design.md §2) that reports its box centre.
inline v2i::VehicleAnnouncement announce(std::uint64_t id, std::uint32_t sequence, TimeNs now,
                                         const Pose2& pose, const std::string& address) {
  v2i::VehicleAnnouncement a;
  a.vehicle_id = id;
  a.sequence = sequence;
  a.generation_time = now;
  a.size = {4.89, 1.92, 1.70};
  a.pose = pose;
  a.pose_covariance = Eigen::Vector3d(0.25, 0.25, 0.01).asDiagonal();
  a.speed_mps = 0.0;
  a.yaw_rate_rps = 0.0;
  a.reply_to = {address, kVehiclePort};
  return a;
}

}  // namespace rsu::core::testing
