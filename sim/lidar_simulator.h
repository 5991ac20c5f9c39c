// SPDX-License-Identifier: Apache-2.0
// A spinning LiDAR simulated firing by firing: Velodyne packets (for the encoder / pcap writer) and
// whole frames of points with ground-truth labels (for experiments and tests).
//
// Every firing of the FiringSchedule (lidar/firing_schedule.h) becomes one ray cast at the firing's
// own time, so a moving vehicle is smeared exactly as in a real sweep. Noise follows the paper's
// simulator (RobotecGPULidar in AWSIM, docs/design.md §2): the ray's elevation and azimuth are perturbed
// (sigma angle_sigma_rad) and Gaussian noise (sigma range_sigma_m) is added to the range, which is
// then quantised to the sensor's distance unit. The reported point is rebuilt like a decoder does:
// the quantised range along the NOMINAL beam, since a real sensor reports its nominal angles.
// Noise is drawn from common/random.h keyed by (seed, packet index, channel): reproducible, and the
// same whether a firing is simulated in a frame, in a packet, or in a sector.
#pragma once

#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "common/pose.h"
#include "common/time.h"
#include "lidar/firing_schedule.h"
#include "lidar/point.h"
#include "lidar/sensor_model.h"
#include "lidar/velodyne_packet.h"
#include "sim/raycaster.h"
#include "sim/scene.h"

namespace rsu::sim {

// Beam rotation angles [begin, end] (Velodyne convention: clockwise from sensor +x, radians),
// inclusive; wraps through 0 when begin > end. Only firings inside are cast.
struct AzimuthSector {
  double begin_rad = 0.0;
  double end_rad = 0.0;

  bool contains(double azimuth_rad) const;
};

// Ground truth of one simulated point.
struct PointTruth {
  SurfaceClass surface = SurfaceClass::kNone;
  std::uint32_t vehicle_id = 0;  // when surface == kVehicle
  double true_range_m = 0.0;     // noise-free range along the cast (perturbed) ray
};

// What happened to the firings of a frame.
struct SimulationCounts {
  std::uint64_t firings = 0;         // firings in the frame's time window
  std::uint64_t outside_sector = 0;  // not cast (sector simulation)
  std::uint64_t no_hit = 0;          // nothing within the maximum range
  std::uint64_t out_of_range = 0;    // a hit whose measured range fell outside [min, max] range
  std::uint64_t returns = 0;         // points produced
};

// The standard normal variates of one firing's noise (scaled by NoiseModel's sigmas).
struct FiringNoise {
  double elevation = 0.0;
  double azimuth = 0.0;
  double range = 0.0;
};

struct SimulatedFrame {
  lidar::LidarFrame frame;        // points in the SENSOR frame, in firing order
  std::vector<PointTruth> truth;  // parallel to frame.points
  SimulationCounts counts;
};

class LidarSimulator {
 public:
  // `raycaster` must outlive the simulator. The schedule's packet 0 starts at `schedule_t0` with the
  // encoder at `start_azimuth_deg`. Throws std::invalid_argument for an unusable sensor model, a
  // non-finite mount or negative / non-finite noise sigmas.
  // carrier: when given, the LiDAR rides on a vehicle following that trajectory (a vehicle's own roof
  // LiDAR): `mount` is then in the vehicle frame, and each ray starts from where the vehicle is at the
  // ray's firing time. Points stay in the sensor frame (with the sweep's motion in them, as a real
  // moving LiDAR reports them).
  LidarSimulator(const lidar::SensorModel& model, const Pose3& mount, const NoiseModel& noise,
                 const Raycaster& raycaster, TimeNs schedule_t0 = 0, double start_azimuth_deg = 0.0,
                 const Trajectory* carrier = nullptr);
  // Builds (and owns) the ray caster for `scene`.
  LidarSimulator(const lidar::SensorModel& model, const Pose3& mount, const NoiseModel& noise,
                 const Scene& scene, TimeNs schedule_t0 = 0, double start_azimuth_deg = 0.0);

  // Packet k of the schedule, as the Velodyne encoder packs it (strongest return). Firings outside
  // `sector` report no return. vehicles_hit, when given, receives the ids of the vehicles its returns
  // are on (ascending, each once: the ray caster's truth of which packets cover a vehicle, for latency
  // measured from the last of them). Throws std::invalid_argument if the model has no packet format.
  lidar::PacketReturns simulate_packet(std::int64_t k,
                                       const std::optional<AzimuthSector>& sector = std::nullopt,
                                       std::vector<std::uint32_t>* vehicles_hit = nullptr) const;
  // Packets first, first + 1, ... into out[0], out[1], ..., each as simulate_packet makes it, on `threads`
  // threads (the caller's among them; started per call: for many packets, not one). Throws as
  // simulate_packet, and std::invalid_argument for threads < 1.
  void simulate_packets(std::int64_t first, std::span<lidar::PacketReturns> out, int threads) const;

  // One rotation: every firing with time in [start, start + 1 / rotation rate) (0.1 s at 10 Hz),
  // from all packets that overlap that window. Points are those a decoder would rebuild from the
  // packets, bit for bit. threads > 1 simulates runs of packets on that many threads (the caller's
  // among them; started per call) with the same frame, bit for bit, as on one. Throws
  // std::invalid_argument for threads < 1.
  SimulatedFrame simulate_frame(TimeNs start, const std::optional<AzimuthSector>& sector = std::nullopt,
                                int threads = 1) const;

  // Index of the packet whose first firing is the last one at or before t.
  std::int64_t packet_index_at(TimeNs t) const;
  TimeNs rotation_period_ns() const;

  const lidar::SensorModel& model() const { return schedule_.model(); }
  const lidar::FiringSchedule& schedule() const { return schedule_; }
  const Pose3& mount() const { return mount_; }
  const NoiseModel& noise() const { return noise_; }
  const Raycaster& raycaster() const { return *raycaster_; }

 private:
  LidarSimulator(const lidar::SensorModel& model, const Pose3& mount, const NoiseModel& noise,
                 std::shared_ptr<const Raycaster> owned, const Raycaster* borrowed, TimeNs schedule_t0,
                 double start_azimuth_deg, const Trajectory* carrier);

  // One firing's outcome (parallel to the packet's firings); raw == 0 means no return.
  struct Outcome {
    std::uint16_t raw = 0;
    std::uint8_t intensity = 0;
    PointTruth truth;
    FiringNoise noise;         // standard normal variates (zero without noise)
    double cos_azimuth = 1.0;  // of the nominal beam rotation angle
    double sin_azimuth = 0.0;
    bool cast = false;  // inside the sector and the time window
  };

  // Buffers reused from packet to packet (no allocation per packet once warm).
  struct PacketScratch {
    std::vector<lidar::Firing> firings;
    std::vector<Outcome> outcomes;
    std::vector<Ray> rays;
    std::vector<RayHit> hits;
    std::vector<std::size_t> ray_outcome;
  };

  // Fills scratch.firings with packet k's firings and scratch.outcomes with their outcomes: firings
  // with time in [t_begin, t_end) and inside `sector` are cast, the others only listed.
  void run_packet(std::int64_t k, TimeNs t_begin, TimeNs t_end, const std::optional<AzimuthSector>& sector,
                  PacketScratch& scratch) const;
  lidar::LidarPoint to_point(const lidar::Firing& f, const Outcome& o) const;
  lidar::PacketReturns packet_returns(std::int64_t k, const std::optional<AzimuthSector>& sector,
                                      PacketScratch& scratch) const;
  // What one run of a frame's packets produced: its points (and truth) stand in the frame from
  // first_point on, counts.returns of them.
  struct RunResult {
    std::size_t first_point = 0;
    SimulationCounts counts;
    TimeNs start_ns = std::numeric_limits<TimeNs>::max();
    TimeNs end_ns = std::numeric_limits<TimeNs>::min();
  };
  // Simulates packets [k_begin, k_end) and writes their firings in [start, end) into frame's points and
  // truth from run.first_point on (room made by the caller), counting them in `run`.
  void write_packets(std::int64_t k_begin, std::int64_t k_end, TimeNs start, TimeNs end,
                     const std::optional<AzimuthSector>& sector, SimulatedFrame& frame, RunResult& run) const;

  std::shared_ptr<const Raycaster> owned_raycaster_;
  const Raycaster* raycaster_;
  lidar::FiringSchedule schedule_;
  TimeNs schedule_t0_;
  Pose3 mount_;
  Eigen::Isometry3d mount_to_map_;  // without a carrier; with one, mount -> carrier vehicle frame
  std::optional<Trajectory> carrier_;
  NoiseModel noise_;
  std::vector<double> elevation_rad_;  // per laser
  std::vector<double> cos_elevation_;  // per laser, nominal (the decoder's values)
  std::vector<double> sin_elevation_;
  std::vector<std::size_t> cast_order_;  // a packet's firing slots sorted by beam elevation
};

}  // namespace rsu::sim
