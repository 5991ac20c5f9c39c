// SPDX-License-Identifier: Apache-2.0
#include "sim/lidar_simulator.h"
#include "lidar/point_eigen.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <map>
#include <stdexcept>
#include <vector>

#include "common/angles.h"
#include "geometry_checks.h"
#include "lidar/ouster/ouster_decoder.h"
#include "lidar/velodyne_decoder.h"
#include "sim/ouster_simulator.h"
#include "sim/trajectory.h"

namespace rsu::sim {
namespace {

NoiseModel no_noise() {
  NoiseModel n;
  n.range_sigma_m = 0.0;
  n.angle_sigma_rad = 0.0;
  return n;
}

Scene flat_ground() {
  Scene s;
  s.ground.half_extent_m = 250.0;
  return s;
}

// A wall whose near face is the plane at 8 m from the origin along the direction 0.6 rad.
Building wall_at_8m() {
  return Building{.x = 13.0 * std::cos(0.6),
                  .y = 13.0 * std::sin(0.6),
                  .yaw = 0.6,
                  .length = 10.0,
                  .width = 60.0,
                  .height = 30.0};
}

Eigen::Vector3d xyz(const lidar::LidarPoint& p) {
  return lidar::position_of(p);
}

// A VLP-16 2 m above an empty ground plane: each downward ring draws a circle of radius
// 2 / tan(|elevation|), if that is within the 100 m maximum range; no other ring returns.
TEST(SimLidarSimulator, Vlp16EmptyGroundRingsAtTheExpectedDistances) {
  const lidar::SensorModel model = lidar::make_vlp16();
  const Raycaster rc(flat_ground());
  const LidarSimulator sim(model, Pose3{0, 0, 2.0, 0, 0, 0}, no_noise(), rc);
  const SimulatedFrame f = sim.simulate_frame(0);
  // 0.1 s / 55.296 us = 1808.4 firing sequences of 16 lasers.
  const double sequences = 0.1 / 55.296e-6;
  EXPECT_NEAR(static_cast<double>(f.counts.firings), 16.0 * sequences, 16.0);
  EXPECT_EQ(f.counts.outside_sector, 0U);
  EXPECT_EQ(f.counts.returns, f.frame.points.size());
  EXPECT_EQ(f.truth.size(), f.frame.points.size());
  EXPECT_EQ(f.counts.firings, f.counts.returns + f.counts.no_hit + f.counts.out_of_range);
  EXPECT_GE(f.frame.start_ns, 0);
  EXPECT_LT(f.frame.end_ns, 100'000'000);
  EXPECT_GT(f.frame.end_ns, 99'900'000);

  std::map<int, int> per_ring;
  for (std::size_t i = 0; i < f.frame.points.size(); ++i) {
    const lidar::LidarPoint& p = f.frame.points[i];
    ++per_ring[p.ring];
    const double w = model.elevation_deg.at(p.ring) * kPi / 180.0;
    ASSERT_LT(w, 0.0) << "an upward ring returned";
    const double horizontal = 2.0 / std::tan(-w);
    // Quantisation: range to within half a distance unit (1 mm), plus float rounding.
    EXPECT_NEAR(std::hypot(static_cast<double>(p.x), static_cast<double>(p.y)), horizontal,
                1e-3 + 1e-5 * horizontal);
    EXPECT_NEAR(p.z, -2.0, 1e-3);
    EXPECT_EQ(f.truth[i].surface, SurfaceClass::kGround);
    // Lambertian intensity: incidence cosine on a horizontal plane is sin|elevation|.
    EXPECT_NEAR(p.intensity, std::round(255.0 * Reflectivity{}.ground * std::sin(-w)), 1.0);
  }
  for (std::size_t laser = 0; laser < model.laser_count(); ++laser) {
    const double w = model.elevation_deg[laser] * kPi / 180.0;
    const bool reaches = w < 0.0 && 2.0 / std::sin(-w) <= model.max_range_m;
    const int n = per_ring.count(static_cast<int>(laser)) != 0 ? per_ring[static_cast<int>(laser)] : 0;
    if (reaches) {
      EXPECT_NEAR(n, sequences, 2.0) << "laser " << laser;
    } else {
      EXPECT_EQ(n, 0) << "laser " << laser;
    }
  }
  // -1 deg would land at 114.6 m, beyond 100 m: 7 rings of 16 return.
  EXPECT_EQ(per_ring.size(), 7U);
}

TEST(SimLidarSimulator, SameSeedSameFrameDifferentSeedDifferentFrame) {
  Scene scene = flat_ground();
  Vehicle v;
  v.id = 3;
  v.trajectory = StaticPose{{9.0, 4.0, 1.0}};
  scene.vehicles.push_back(v);
  const Raycaster rc(scene);
  const lidar::SensorModel model = lidar::make_vlp32c();
  NoiseModel noise;  // the paper's defaults
  noise.seed = 17;
  const LidarSimulator a(model, Pose3{0, 0, 2.0, 0, 0, 0.2}, noise, rc);
  const LidarSimulator b(model, Pose3{0, 0, 2.0, 0, 0, 0.2}, noise, rc);
  noise.seed = 18;
  const LidarSimulator c(model, Pose3{0, 0, 2.0, 0, 0, 0.2}, noise, rc);
  const SimulatedFrame fa = a.simulate_frame(1'000'000);
  const SimulatedFrame fb = b.simulate_frame(1'000'000);
  const SimulatedFrame fc = c.simulate_frame(1'000'000);
  ASSERT_EQ(fa.frame.points.size(), fb.frame.points.size());
  ASSERT_GT(fa.frame.points.size(), 10000U);
  for (std::size_t i = 0; i < fa.frame.points.size(); ++i) {
    ASSERT_EQ(xyz(fa.frame.points[i]), xyz(fb.frame.points[i]));
    ASSERT_EQ(fa.frame.points[i].time_ns, fb.frame.points[i].time_ns);
    ASSERT_EQ(fa.frame.points[i].intensity, fb.frame.points[i].intensity);
  }
  std::size_t differing = 0;
  const std::size_t n = std::min(fa.frame.points.size(), fc.frame.points.size());
  for (std::size_t i = 0; i < n; ++i) {
    differing += xyz(fa.frame.points[i]) != xyz(fc.frame.points[i]) ? 1 : 0;
  }
  EXPECT_GT(differing, n / 2);
}

// Range noise: measured (quantised) range minus the true range along the cast ray is zero-mean with
// the configured sigma (plus the quantisation's unit^2 / 12).
TEST(SimLidarSimulator, RangeNoiseHasTheConfiguredSigma) {
  const lidar::SensorModel model = lidar::make_vlp16();
  const Raycaster rc(flat_ground());
  NoiseModel noise;
  noise.range_sigma_m = 0.02;
  noise.angle_sigma_rad = 0.001;
  const LidarSimulator sim(model, Pose3{0, 0, 2.0, 0, 0, 0}, noise, rc);
  const SimulatedFrame f = sim.simulate_frame(0);
  double sum = 0.0, sum_sq = 0.0;
  for (std::size_t i = 0; i < f.frame.points.size(); ++i) {
    const double e = xyz(f.frame.points[i]).norm() - f.truth[i].true_range_m;
    sum += e;
    sum_sq += e * e;
  }
  const double n = static_cast<double>(f.frame.points.size());
  ASSERT_GT(n, 10000.0);
  const double mean = sum / n;
  const double sigma = std::sqrt(sum_sq / n - mean * mean);
  const double expected = std::sqrt(0.02 * 0.02 + 0.002 * 0.002 / 12.0);
  EXPECT_NEAR(mean, 0.0, 4.0 * expected / std::sqrt(n));
  EXPECT_NEAR(sigma, expected, 0.05 * expected);
  // Angular noise moves the ray: the points are not all exactly on their ring's circle any more.
  int off_circle = 0;
  for (const lidar::LidarPoint& p : f.frame.points) {
    const double w = model.elevation_deg.at(p.ring) * kPi / 180.0;
    off_circle +=
        std::abs(std::hypot(static_cast<double>(p.x), static_cast<double>(p.y)) - 2.0 / std::tan(-w)) > 0.05
            ? 1
            : 0;
  }
  EXPECT_GT(off_circle, 100);
}

// Every point labelled as the vehicle, put back into the map frame, lies on the vehicle's mesh
// (distance computed here by brute force), within the distance quantum, when noise is off; within
// a few sigma when it is on.
TEST(SimLidarSimulator, VehiclePointsLieOnTheMeshSurface) {
  Scene scene = flat_ground();
  Vehicle v;
  v.id = 9;
  v.trajectory = StaticPose{{7.0, -5.0, 0.6}};
  scene.vehicles.push_back(v);
  const Raycaster rc(scene);
  const Pose3 mount{0, 0, 2.0, 0, 0, 0.3};
  const Eigen::Isometry3d to_map = mount.to_isometry();
  const Eigen::Affine3d to_vehicle =
      (Eigen::Translation3d(7.0, -5.0, 0.0) * Eigen::AngleAxisd(0.6, Eigen::Vector3d::UnitZ())).inverse();
  const TriangleMesh& mesh = rc.vehicle_mesh(0);
  for (const bool noisy : {false, true}) {
    NoiseModel noise = noisy ? NoiseModel{} : no_noise();
    const LidarSimulator sim(lidar::make_vlp16(), mount, noise, rc);
    const SimulatedFrame f = sim.simulate_frame(0);
    int checked = 0;
    for (std::size_t i = 0; i < f.frame.points.size(); ++i) {
      if (f.truth[i].surface != SurfaceClass::kVehicle) {
        continue;
      }
      EXPECT_EQ(f.truth[i].vehicle_id, 9U);
      const Eigen::Vector3d p = to_map * xyz(f.frame.points[i]);
      const double range = f.truth[i].true_range_m;
      // Noise off: half a 2 mm unit plus float; on: 4 sigma of range noise and of the angular
      // offset between the nominal beam (reported) and the cast ray, which moves the point sideways.
      const double tolerance =
          noisy ? 4.0 * (noise.range_sigma_m + std::sqrt(2.0) * noise.angle_sigma_rad * range) : 1.5e-3;
      EXPECT_LT(testing::distance_to_mesh(to_vehicle * p, mesh), tolerance) << "point " << i;
      ++checked;
    }
    EXPECT_GT(checked, 200);
  }
}

// A vehicle driving away at 30 m/s, seen from behind at belt height: the flat part of its rear face
// is at x(t) - length / 2 at each point's own firing time t, so points fired later are farther.
TEST(SimLidarSimulator, MovingVehicleIsSeenWhereItIsAtEachPointsTime) {
  Scene scene = flat_ground();
  Vehicle v;
  v.id = 1;
  const double speed = 30.0;
  const double x0 = 8.0;
  Waypoints w;
  w.points = {{0, {x0, 0.0, 0.0}}, {1'000'000'000, {x0 + speed, 0.0, 0.0}}};
  v.trajectory = w;
  scene.vehicles.push_back(v);
  const Raycaster rc(scene);
  const VehicleShape& s = v.shape;
  const LidarSimulator sim(lidar::make_vlp32c(), Pose3{0, 0, 0.9, 0, 0, 0}, no_noise(), rc);
  const SimulatedFrame f = sim.simulate_frame(0);
  int on_rear_face = 0;
  double x_min = 1e9, x_max = -1e9;
  for (std::size_t i = 0; i < f.frame.points.size(); ++i) {
    const lidar::LidarPoint& p = f.frame.points[i];
    if (f.truth[i].surface != SurfaceClass::kVehicle) {
      continue;
    }
    const double z = static_cast<double>(p.z) + 0.9;
    // Flat rear face: between the arch tops and the belt line, clear of the rounded corners.
    if (z < 0.82 || z > 0.98 || std::abs(static_cast<double>(p.y)) > 0.5 * s.width - s.corner_radius - 0.05) {
      continue;
    }
    const double expected_x = x0 + speed * to_seconds(p.time_ns) - 0.5 * s.length;
    EXPECT_NEAR(p.x, expected_x, 3e-3) << "t = " << p.time_ns;
    ++on_rear_face;
    x_min = std::min(x_min, static_cast<double>(p.x));
    x_max = std::max(x_max, static_cast<double>(p.x));
  }
  EXPECT_GT(on_rear_face, 20);
  // The sweep takes milliseconds to cross the face: a frozen vehicle would give one x.
  EXPECT_GT(x_max - x_min, 0.05);
}

// What the simulator calls a point is what a decoder rebuilds from the simulator's packets.
TEST(SimLidarSimulator, FramePointsEqualDecodedPackets) {
  Scene scene = flat_ground();
  Vehicle v;
  v.id = 5;
  v.trajectory = StaticPose{{3.0, 6.0, 2.0}};
  scene.vehicles.push_back(v);
  Building b;
  b.x = -15;
  b.y = 0;
  scene.buildings.push_back(b);
  const Raycaster rc(scene);
  for (const lidar::SensorModel& model : {lidar::make_vlp16(), lidar::make_vlp32c()}) {
    const LidarSimulator sim(model, Pose3{0.5, -0.5, 2.0, 0.01, -0.02, 0.4}, NoiseModel{}, rc, 0, 90.0);
    const std::int64_t k0 = 10;
    const std::int64_t k1 = 40;
    const TimeNs start = sim.schedule().packet(k0).first_firing_ns;
    const TimeNs stop = sim.schedule().packet(k1 + 1).first_firing_ns;
    lidar::VelodyneDecoder decoder(model);
    std::vector<lidar::LidarPoint> decoded;
    for (std::int64_t k = k0; k <= k1; ++k) {
      const lidar::PacketReturns returns = sim.simulate_packet(k);
      std::array<std::uint8_t, lidar::kPacketBytes> bytes{};
      lidar::encode_packet(model, returns, bytes);
      ASSERT_TRUE(decoder.decode(bytes, returns.blocks.first_firing_ns, decoded).is_data());
    }
    const SimulatedFrame f = sim.simulate_frame(start);
    std::vector<lidar::LidarPoint> framed;
    for (const lidar::LidarPoint& p : f.frame.points) {
      if (p.time_ns < stop) {
        framed.push_back(p);
      }
    }
    ASSERT_GT(decoded.size(), 1000U);
    ASSERT_EQ(framed.size(), decoded.size()) << model.name;
    for (std::size_t i = 0; i < decoded.size(); ++i) {
      ASSERT_EQ(framed[i].x, decoded[i].x) << i;
      ASSERT_EQ(framed[i].y, decoded[i].y) << i;
      ASSERT_EQ(framed[i].z, decoded[i].z) << i;
      ASSERT_EQ(framed[i].intensity, decoded[i].intensity) << i;
      ASSERT_EQ(framed[i].ring, decoded[i].ring) << i;
      ASSERT_EQ(framed[i].azimuth_rad, decoded[i].azimuth_rad) << i;
      ASSERT_EQ(framed[i].time_ns, decoded[i].time_ns) << i;
    }
  }
}

// The simulator's VLP-32C rays are the beams the manual and the Velodyne calibration files define, and
// the decoder turns its packets back into points on those rays. Independent truth: the calibration
// files' rot_correction (here, not the library's table) is SUBTRACTED from the manual's precision
// azimuth (block azimuth + gap x K x 2.304 us / 55.296 us for channels K, K + 1); an oblique wall makes
// a ray cast in another direction land off the decoded beam. With the offsets added, as before the
// sign fix, every offset laser is 2.8 or 8.4 deg off.
TEST(SimLidarSimulator, Vlp32cPacketsDecodeToPointsOnTheCalibratedBeams) {
  constexpr std::array<double, 32> kRotCorrectionDeg = {
      -1.4, 4.2, -1.4, 1.4, -1.4, 1.4, -4.2, 1.4, -1.4, 4.2, -1.4, 1.4, -4.2, 1.4, -4.2, 1.4,
      -1.4, 4.2, -1.4, 4.2, -4.2, 1.4, -1.4, 1.4, -1.4, 1.4, -1.4, 4.2, -4.2, 1.4, -1.4, 1.4};
  Scene scene = flat_ground();
  scene.buildings.push_back(wall_at_8m());  // in front of the LiDAR
  const Raycaster rc(scene);
  const Pose3 mount{0.0, 0.0, 2.0, 0.0, 0.0, 0.0};
  const lidar::SensorModel model = lidar::make_vlp32c();
  const LidarSimulator sim(model, mount, no_noise(), rc, 0, 300.0);
  lidar::VelodyneDecoder decoder(model);
  const Eigen::Vector2d normal(std::cos(0.6), std::sin(0.6));
  int on_wall = 0;
  for (std::int64_t k = 0; k < 300; ++k) {  // 0.2 s: the wall at about 0..70 deg azimuth clockwise
    const lidar::PacketReturns returns = sim.simulate_packet(k);
    std::array<std::uint8_t, lidar::kPacketBytes> bytes{};
    lidar::encode_packet(model, returns, bytes);
    std::vector<lidar::LidarPoint> points;
    ASSERT_TRUE(decoder.decode(bytes, returns.blocks.first_firing_ns, points).is_data());
    std::size_t next = 0;
    for (int b = 0; b < lidar::kBlocksPerPacket; ++b) {
      const auto bi = static_cast<std::size_t>(b);
      const int from = b < lidar::kBlocksPerPacket - 1 ? b : b - 1;
      const double gap_deg =
          std::fmod(returns.blocks.azimuth_cdeg[static_cast<std::size_t>(from + 1)] -
                        returns.blocks.azimuth_cdeg[static_cast<std::size_t>(from)] + 36000.0,
                    36000.0) /
          100.0;
      for (int c = 0; c < lidar::kChannelsPerBlock; ++c) {
        if (returns.distance_raw[bi][static_cast<std::size_t>(c)] == 0)
          continue;
        ASSERT_LT(next, points.size());
        const lidar::LidarPoint& p = points[next++];
        ASSERT_EQ(p.ring, c);
        const double azimuth_deg = returns.blocks.azimuth_cdeg[bi] / 100.0 +
                                   gap_deg * (c - c % 2) * 2.304 / 55.296 -
                                   kRotCorrectionDeg[static_cast<std::size_t>(c)];
        const double decoded_deg =
            std::atan2(-static_cast<double>(p.y), static_cast<double>(p.x)) * 180.0 / kPi;
        EXPECT_NEAR(std::remainder(decoded_deg - azimuth_deg, 360.0), 0.0, 1e-4)
            << "packet " << k << " channel " << c;
        // On the ray the simulator cast: the wall's face (map frame = sensor frame shifted up 2 m).
        const double along = Eigen::Vector2d(static_cast<double>(p.x), static_cast<double>(p.y)).dot(normal);
        if (std::abs(along - 8.0) < 0.5 && p.z > -1.95F) {  // not the ground (2 m below the LiDAR)
          ++on_wall;
          EXPECT_NEAR(along, 8.0, 0.01) << "packet " << k << " channel " << c;
        }
      }
    }
    EXPECT_EQ(next, points.size());
  }
  EXPECT_GT(on_wall, 20000);
}

// rsu-sim stream --ouster's packets (sim/ouster_simulator.h), decoded by rsud's Ouster decoder with the
// metadata the simulator writes, in each profile: every packet accepted, whole frames, and every point
// on the surface its ray hit (the ground plane, or the wall's face at 8 m), placed by the mount.
TEST(SimOusterSimulator, PacketsDecodeToPointsOnTheSceneInEachProfile) {
  Scene scene = flat_ground();
  scene.buildings.push_back(wall_at_8m());
  const Raycaster rc(scene);
  const Pose3 mount{1.0, -2.0, 2.0, 0.0, 0.0, 0.3};
  const Eigen::Isometry3d to_map = mount.to_isometry();
  // The wall's face in the map frame: points x with n . x = 8 (n the unit vector along 0.6 rad).
  const Eigen::Vector2d normal(std::cos(0.6), std::sin(0.6));
  for (const auto profile : {lidar::ouster::UdpProfile::rng19_rfl8_sig16_nir16,
                             lidar::ouster::UdpProfile::legacy, lidar::ouster::UdpProfile::rng15_rfl8_nir8}) {
    SCOPED_TRACE(std::string(lidar::ouster::to_string(profile)));
    const std::string json = ouster_metadata_json({"os1-64", "512x20", profile});
    const lidar::ouster::Metadata m = lidar::ouster::parse_metadata(json, "simulated");
    EXPECT_EQ(m.prod_line, "OS-1-64");
    EXPECT_EQ(m.columns_per_frame, 512);
    EXPECT_EQ(m.frequency_hz, 20);
    const OusterSimulator sim(m, mount, no_noise(), rc);
    EXPECT_EQ(sim.packets_per_frame(), 32);
    lidar::ouster::Decoder decoder(m);
    // The range field's unit (RNG15: 8 mm) bounds how far a decoded point lies from its surface.
    const double tolerance = profile == lidar::ouster::UdpProfile::rng15_rfl8_nir8 ? 0.006 : 0.0015;
    int on_ground = 0, on_wall = 0, elsewhere = 0;
    std::vector<std::uint8_t> bytes;
    std::vector<lidar::LidarPoint> points;
    for (std::int64_t k = 0; k < 2 * sim.packets_per_frame(); ++k) {
      sim.packet(k, 1'000'000'000, bytes);
      points.clear();
      ASSERT_EQ(decoder.decode(bytes, points), lidar::ouster::PacketResult::accepted) << k;
      EXPECT_EQ(decoder.last_packet().first_time_ns, sim.packet_time_ns(k) + 1'000'000'000);
      for (const lidar::LidarPoint& p : points) {
        const Eigen::Vector3d x = to_map * lidar::position_of(p);
        if (std::abs(x.z()) < tolerance)
          ++on_ground;
        else if (std::abs(x.head<2>().dot(normal) - 8.0) < tolerance)
          ++on_wall;
        else
          ++elsewhere;
      }
    }
    EXPECT_EQ(decoder.stats().frames_complete, 2U);
    EXPECT_EQ(decoder.stats().columns_skipped, 0U);
    EXPECT_EQ(elsewhere, 0);
    EXPECT_GT(on_wall, 2000);
    EXPECT_GT(on_ground, 10000);
  }
  EXPECT_THROW(ouster_metadata_json({"os1-128", "2048x20"}), std::exception);  // not a mode the sensor has
  EXPECT_THROW(ouster_metadata_json({"os3-128", "1024x10"}), std::invalid_argument);
}

// Sector simulation casts only the firings in the window, and those come out exactly as in the full
// frame (noise is keyed by firing, not by draw order).
TEST(SimLidarSimulator, SectorMatchesTheFullFrameInsideTheWindow) {
  Scene scene = flat_ground();
  Vehicle v;
  v.trajectory = StaticPose{{6.0, -6.0, 0.0}};
  scene.vehicles.push_back(v);
  const Raycaster rc(scene);
  const LidarSimulator sim(lidar::make_vlp32c(), Pose3{0, 0, 2.0, 0, 0, 0}, NoiseModel{}, rc);
  for (const AzimuthSector sector : {AzimuthSector{0.5, 1.2}, AzimuthSector{6.0, 0.4}}) {
    const SimulatedFrame full = sim.simulate_frame(0);
    const SimulatedFrame part = sim.simulate_frame(0, sector);
    EXPECT_EQ(part.counts.firings, full.counts.firings);
    EXPECT_GT(part.counts.outside_sector, part.counts.firings / 2);
    std::vector<lidar::LidarPoint> expected;
    for (const lidar::LidarPoint& p : full.frame.points) {
      const double a = static_cast<double>(p.azimuth_rad);
      const bool inside = sector.begin_rad <= sector.end_rad ? (a >= sector.begin_rad && a <= sector.end_rad)
                                                             : (a >= sector.begin_rad || a <= sector.end_rad);
      if (inside) {
        expected.push_back(p);
      }
    }
    ASSERT_GT(expected.size(), 1000U);
    ASSERT_EQ(part.frame.points.size(), expected.size());
    for (std::size_t i = 0; i < expected.size(); ++i) {
      ASSERT_EQ(xyz(part.frame.points[i]), xyz(expected[i]));
      ASSERT_EQ(part.frame.points[i].time_ns, expected[i].time_ns);
    }
  }
}

TEST(SimLidarSimulator, PacketsOutsideTheSectorReportNoReturn) {
  const Raycaster rc(flat_ground());
  const LidarSimulator sim(lidar::make_vlp16(), Pose3{0, 0, 2.0, 0, 0, 0}, no_noise(), rc);
  // Packet 0 spans azimuths 0 .. 2.4 deg: a sector elsewhere leaves it empty.
  const lidar::PacketReturns empty = sim.simulate_packet(0, AzimuthSector{1.0, 2.0});
  const lidar::PacketReturns full = sim.simulate_packet(0);
  int full_returns = 0;
  for (int b = 0; b < lidar::kBlocksPerPacket; ++b) {
    for (int c = 0; c < lidar::kChannelsPerBlock; ++c) {
      EXPECT_EQ(empty.distance_raw[static_cast<std::size_t>(b)][static_cast<std::size_t>(c)], 0);
      full_returns +=
          full.distance_raw[static_cast<std::size_t>(b)][static_cast<std::size_t>(c)] != 0 ? 1 : 0;
    }
  }
  EXPECT_EQ(full_returns, 12 * 2 * 7);  // 7 downward rings reach the ground, 2 sequences per block
}

TEST(SimLidarSimulator, BadConfigurationThrows) {
  const Raycaster rc(flat_ground());
  NoiseModel negative;
  negative.range_sigma_m = -1.0;
  EXPECT_THROW(LidarSimulator(lidar::make_vlp16(), Pose3{}, negative, rc), std::invalid_argument);
  EXPECT_THROW(LidarSimulator(lidar::make_vlp16(), Pose3{0, 0, std::nan(""), 0, 0, 0}, NoiseModel{}, rc),
               std::invalid_argument);
  lidar::SensorModel broken = lidar::make_vlp16();
  broken.elevation_deg.pop_back();
  EXPECT_THROW(LidarSimulator(broken, Pose3{}, NoiseModel{}, rc), std::invalid_argument);
  const LidarSimulator generic(lidar::make_generic(64), Pose3{0, 0, 2, 0, 0, 0}, NoiseModel{}, rc);
  EXPECT_THROW(generic.simulate_packet(0), std::invalid_argument);
  EXPECT_GT(generic.simulate_frame(0).frame.points.size(), 50000U);  // frames work without a packet format
}

TEST(SimLidarSimulator, OwnsItsRaycasterWhenBuiltFromAScene) {
  const LidarSimulator sim(lidar::make_vlp16(), Pose3{0, 0, 2.0, 0, 0, 0}, no_noise(), flat_ground());
  EXPECT_GT(sim.simulate_frame(0).frame.points.size(), 12000U);
}

}  // namespace
}  // namespace rsu::sim
