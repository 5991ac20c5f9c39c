// SPDX-License-Identifier: Apache-2.0
// The simulator on several threads (issue 16 item 3): a frame, a batch of rays and an Ouster frame's
// packets must come out the same bits whatever the thread count, since experiments compare runs and the
// decoders' tests compare with the simulator. Labelled `threads`: CI also runs these under TSan.
#include <gtest/gtest.h>

#include <array>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "lidar/ouster/ouster_metadata.h"
#include "lidar/sensor_model.h"
#include "lidar/velodyne_packet.h"
#include "sim/lidar_simulator.h"
#include "sim/ouster_simulator.h"
#include "sim/parallel_indices.h"
#include "sim/raycaster.h"
#include "street_with_traffic.h"

namespace rsu::sim {
namespace {

// Bit for bit: == would take -0.0 for 0.0.
bool same(double a, double b) {
  return std::bit_cast<std::uint64_t>(a) == std::bit_cast<std::uint64_t>(b);
}
bool same(float a, float b) {
  return std::bit_cast<std::uint32_t>(a) == std::bit_cast<std::uint32_t>(b);
}

// The car of street_with_traffic passes the origin at t = 0.5 s.
constexpr TimeNs kFrameStart = 450'000'000;

TEST(SimThreads, EveryIndexRunsOnceAndAJobsExceptionReachesTheCaller) {
  std::vector<std::atomic<int>> runs(1000);
  run_indices_in_parallel(runs.size(), 3, [&](std::size_t i) { ++runs[i]; });
  for (std::size_t i = 0; i < runs.size(); ++i)
    ASSERT_EQ(runs[i].load(), 1) << i;
  for (const int threads : {1, 3}) {
    std::atomic<int> done{0};
    EXPECT_THROW(run_indices_in_parallel(1000, threads,
                                         [&](std::size_t i) {
                                           if (i == 10)
                                             throw std::runtime_error("job 10");
                                           ++done;
                                         }),
                 std::runtime_error);
    if (threads == 1) {
      EXPECT_EQ(done.load(), 10);  // in index order; none taken after the throw
    }
  }
}

// A VLP-32C-like rotation (150 packets of 32 beams x 12 firings, elevation order) and rays the caster
// must refuse, 57,603 in all: not a whole number of the threads' 1,024-ray parts.
TEST(SimThreads, BatchHitsAreTheSameBitsOnAnyThreadCount) {
  const Raycaster rc(testing::street_with_traffic());
  std::vector<Ray> rays;
  for (int packet = 0; packet < 150; ++packet) {
    for (int laser = 0; laser < 32; ++laser) {
      for (int block = 0; block < 12; ++block) {
        const int firing = 12 * packet + block;
        const double elevation = (-25.0 + 40.0 * laser / 31.0) * std::numbers::pi / 180.0;
        const double azimuth = 0.2 * std::numbers::pi / 180.0 * firing;
        Ray r;
        r.origin = {0.0, 0.0, 2.0};
        r.direction = {std::cos(elevation) * std::cos(azimuth), std::cos(elevation) * std::sin(azimuth),
                       std::sin(elevation)};
        r.time_ns = kFrameStart + firing * 55'296 + laser * 1'728;
        r.max_range = 200.0;
        rays.push_back(r);
      }
    }
  }
  Ray bad;
  bad.direction = Eigen::Vector3d::Zero();
  rays.insert(rays.begin() + 5000, bad);
  bad.direction = {std::numeric_limits<double>::quiet_NaN(), 0.0, 0.0};
  rays.insert(rays.begin() + 30000, bad);
  bad.direction = Eigen::Vector3d::UnitX();
  bad.max_range = 0.0;
  rays.push_back(bad);

  std::vector<RayHit> one(rays.size());
  rc.cast_batch(rays, one);
  int vehicle_hits = 0;
  for (const RayHit& h : one)
    vehicle_hits += h.surface == SurfaceClass::kVehicle ? 1 : 0;
  EXPECT_GT(vehicle_hits, 1000);  // both posed vehicles are in it
  EXPECT_FALSE(one[5000].hit());
  for (const int threads : {2, 3, 4}) {
    std::vector<RayHit> many(rays.size());
    rc.cast_batch(rays, many, threads);
    for (std::size_t i = 0; i < rays.size(); ++i) {
      ASSERT_EQ(many[i].surface, one[i].surface) << threads << " threads, ray " << i;
      ASSERT_EQ(many[i].vehicle_id, one[i].vehicle_id) << threads << " threads, ray " << i;
      ASSERT_TRUE(same(many[i].range, one[i].range)) << threads << " threads, ray " << i;
      ASSERT_TRUE(same(many[i].reflectivity, one[i].reflectivity)) << threads << " threads, ray " << i;
      for (int k = 0; k < 3; ++k)
        ASSERT_TRUE(same(many[i].normal[k], one[i].normal[k])) << threads << " threads, ray " << i;
    }
  }
  EXPECT_THROW(rc.cast_batch(rays, one, 0), std::invalid_argument);
}

void expect_same_frames(const SimulatedFrame& many, const SimulatedFrame& one, const std::string& what) {
  EXPECT_EQ(many.frame.start_ns, one.frame.start_ns) << what;
  EXPECT_EQ(many.frame.end_ns, one.frame.end_ns) << what;
  EXPECT_EQ(many.counts.firings, one.counts.firings) << what;
  EXPECT_EQ(many.counts.outside_sector, one.counts.outside_sector) << what;
  EXPECT_EQ(many.counts.no_hit, one.counts.no_hit) << what;
  EXPECT_EQ(many.counts.out_of_range, one.counts.out_of_range) << what;
  EXPECT_EQ(many.counts.returns, one.counts.returns) << what;
  ASSERT_EQ(many.frame.points.size(), one.frame.points.size()) << what;
  ASSERT_EQ(many.truth.size(), one.truth.size()) << what;
  for (std::size_t i = 0; i < one.frame.points.size(); ++i) {
    const lidar::LidarPoint& a = many.frame.points[i];
    const lidar::LidarPoint& b = one.frame.points[i];
    ASSERT_TRUE(same(a.x, b.x) && same(a.y, b.y) && same(a.z, b.z)) << what << ", point " << i;
    ASSERT_TRUE(same(a.intensity, b.intensity) && same(a.azimuth_rad, b.azimuth_rad))
        << what << ", point " << i;
    ASSERT_EQ(a.ring, b.ring) << what << ", point " << i;
    ASSERT_EQ(a.echo, b.echo) << what << ", point " << i;
    ASSERT_EQ(a.time_ns, b.time_ns) << what << ", point " << i;
    ASSERT_EQ(many.truth[i].surface, one.truth[i].surface) << what << ", point " << i;
    ASSERT_EQ(many.truth[i].vehicle_id, one.truth[i].vehicle_id) << what << ", point " << i;
    ASSERT_TRUE(same(many.truth[i].true_range_m, one.truth[i].true_range_m)) << what << ", point " << i;
  }
}

// A VLP-32C 2 m up in the street with the paper's noise: the whole rotation and a sector around the
// passing car, on 2 to 4 threads against one.
TEST(SimThreads, VelodyneFramesAreTheSameBitsOnAnyThreadCount) {
  const Raycaster rc(testing::street_with_traffic());
  const LidarSimulator sim(lidar::make_vlp32c(), Pose3{0.0, 0.0, 2.0, 0.0, 0.0, 0.0}, NoiseModel{}, rc, 0,
                           37.0);
  const AzimuthSector sector{4.2, 5.25};
  for (const std::optional<AzimuthSector>& s : {std::optional<AzimuthSector>{}, std::optional{sector}}) {
    const std::string what = s ? "sector" : "rotation";
    const SimulatedFrame one = sim.simulate_frame(kFrameStart, s);
    int vehicle_points = 0;
    for (const PointTruth& t : one.truth)
      vehicle_points += t.surface == SurfaceClass::kVehicle ? 1 : 0;
    EXPECT_GT(vehicle_points, s ? 100 : 1000) << what;
    EXPECT_GT(one.counts.no_hit, 0U) << what;
    for (const int threads : {2, 3, 4})
      expect_same_frames(sim.simulate_frame(kFrameStart, s, threads), one,
                         what + " on " + std::to_string(threads) + " threads");
  }
  EXPECT_THROW(sim.simulate_frame(kFrameStart, std::nullopt, 0), std::invalid_argument);
}

// The same VLP-32C's packets for a pcap (rsu-sim simulate): 3 rotations' on 2 to 4 threads against
// simulate_packet one by one, compared as the bytes the encoder writes.
TEST(SimThreads, VelodynePacketsAreTheSameBytesOnAnyThreadCount) {
  const Raycaster rc(testing::street_with_traffic());
  const lidar::SensorModel model = lidar::make_vlp32c();
  const LidarSimulator sim(model, Pose3{0.0, 0.0, 2.0, 0.0, 0.0, 0.0}, NoiseModel{}, rc, 0, 37.0);
  const std::int64_t first = sim.packet_index_at(kFrameStart);
  std::vector<lidar::PacketReturns> one(3 * 151);
  for (std::size_t i = 0; i < one.size(); ++i)
    one[i] = sim.simulate_packet(first + static_cast<std::int64_t>(i));
  std::array<std::uint8_t, lidar::kPacketBytes> expected{};
  std::array<std::uint8_t, lidar::kPacketBytes> actual{};
  for (const int threads : {1, 2, 3, 4}) {
    std::vector<lidar::PacketReturns> many(one.size());
    sim.simulate_packets(first, many, threads);
    for (std::size_t i = 0; i < one.size(); ++i) {
      lidar::encode_packet(model, one[i], expected);
      lidar::encode_packet(model, many[i], actual);
      ASSERT_EQ(actual, expected) << threads << " threads, packet " << i;
    }
  }
  EXPECT_THROW(sim.simulate_packets(first, one, 0), std::invalid_argument);
}

// An OS1-128 at 1024x10 with noise: a frame's packets on 2 to 4 threads against packet() one by one.
TEST(SimThreads, OusterPacketsAreTheSameBytesOnAnyThreadCount) {
  const Raycaster rc(testing::street_with_traffic());
  const std::string json =
      ouster_metadata_json({"os1-128", "1024x10", lidar::ouster::UdpProfile::rng19_rfl8_sig16_nir16});
  const OusterSimulator sim(lidar::ouster::parse_metadata(json, "simulated"),
                            Pose3{0.0, 0.0, 2.0, 0.0, 0.0, 0.4}, NoiseModel{}, rc);
  const std::int64_t first = sim.packet_index_at(kFrameStart);
  const auto count = static_cast<std::size_t>(sim.packets_per_frame());
  std::vector<std::vector<std::uint8_t>> one(count);
  std::size_t vehicle_returns = 0;
  for (std::size_t i = 0; i < count; ++i)
    vehicle_returns += sim.packet(first + static_cast<std::int64_t>(i), 1'000, one[i]);
  EXPECT_GT(vehicle_returns, 1000U);
  for (const int threads : {1, 2, 3, 4}) {
    std::vector<std::vector<std::uint8_t>> many(count);
    EXPECT_EQ(sim.packets(first, 1'000, many, threads), vehicle_returns) << threads << " threads";
    for (std::size_t i = 0; i < count; ++i)
      ASSERT_EQ(many[i], one[i]) << threads << " threads, packet " << i;
  }
  std::vector<std::vector<std::uint8_t>> none(1);
  EXPECT_THROW(sim.packets(first, 0, none, 0), std::invalid_argument);
}

}  // namespace
}  // namespace rsu::sim
