// SPDX-License-Identifier: Apache-2.0
#include "sim/raycaster.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "geometry_checks.h"
#include "sim/trajectory.h"
#include "street_with_traffic.h"

namespace rsu::sim {
namespace {

constexpr double kMm = 1e-3;

Eigen::Vector3d random_unit(std::mt19937& rng) {
  std::normal_distribution<double> n;
  Eigen::Vector3d d(n(rng), n(rng), n(rng));
  return d.normalized();
}

Scene ground_only() {
  Scene s;
  s.ground.half_extent_m = 200.0;
  return s;
}

TEST(SimRaycaster, HitsTheGroundPlaneExactly) {
  const Raycaster rc(ground_only());
  std::mt19937 rng(1);
  const Eigen::Vector3d origin(1.0, 2.0, 3.0);
  int tested = 0;
  for (int i = 0; i < 500; ++i) {
    Eigen::Vector3d d = random_unit(rng);
    if (d.z() > -0.05) {
      continue;  // the plane must be hit within its 200 m extent
    }
    ++tested;
    const double expected = origin.z() / -d.z();  // origin.z + s d.z = 0
    const RayHit h = rc.cast(origin, d, 0);
    ASSERT_TRUE(h.hit());
    EXPECT_NEAR(h.range, expected, kMm);
    EXPECT_EQ(h.surface, SurfaceClass::kGround);
    EXPECT_DOUBLE_EQ(h.reflectivity, Reflectivity{}.ground);
    EXPECT_NEAR(h.normal.z(), 1.0, 1e-6);
  }
  EXPECT_GT(tested, 200);
  // Upward rays and rays beyond max_range miss.
  EXPECT_FALSE(rc.cast(origin, {0.3, 0.1, 1.0}, 0).hit());
  EXPECT_FALSE(rc.cast(origin, {0.0, 0.0, -1.0}, 0, 2.9).hit());
  EXPECT_TRUE(rc.cast(origin, {0.0, 0.0, -1.0}, 0, 3.1).hit());
  // The ground ends at its half extent (the raycaster intersects the plane itself, not triangles):
  // a ray meeting the plane at x = 301 m misses it, one meeting it at 151 m does not.
  EXPECT_FALSE(rc.cast(origin, Eigen::Vector3d(300.0, 0.0, -3.0).normalized(), 0).hit());
  EXPECT_NEAR(rc.cast(origin, Eigen::Vector3d(150.0, 0.0, -3.0).normalized(), 0).range,
              std::hypot(150.0, 3.0), kMm);
  // Seen from below, as Embree's two-sided triangles were.
  const RayHit below = rc.cast({1.0, 2.0, -3.0}, {0.0, 0.6, 0.8}, 0);
  ASSERT_TRUE(below.hit());
  EXPECT_NEAR(below.range, 3.75, kMm);
  EXPECT_NEAR(below.normal.z(), -1.0, 1e-6);
  // Along it or from it: no hit.
  EXPECT_FALSE(rc.cast({1.0, 2.0, 0.0}, {0.0, 0.6, -0.8}, 0).hit());
  EXPECT_FALSE(rc.cast(origin, {1.0, 0.0, 0.0}, 0).hit());
}

TEST(SimRaycaster, HitsARotatedBuildingWhereTheSlabTestSays) {
  Scene scene = ground_only();
  Building b;
  b.x = 20.0;
  b.y = 5.0;
  b.yaw = 0.3;
  b.length = 10.0;
  b.width = 6.0;
  b.height = 8.0;
  scene.buildings.push_back(b);
  const Raycaster rc(scene);
  // The test's own model: the box [-l/2, l/2] x [-w/2, w/2] x [0, h] in the building frame.
  const Eigen::Affine3d to_map =
      Eigen::Translation3d(b.x, b.y, 0.0) * Eigen::AngleAxisd(b.yaw, Eigen::Vector3d::UnitZ());
  const Eigen::Affine3d to_box = to_map.inverse();
  const Eigen::Vector3d lo(-5.0, -3.0, 0.0), hi(5.0, 3.0, 8.0);
  const Eigen::Vector3d origin(0.0, 0.0, 2.0);
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int hits = 0;
  for (int i = 0; i < 300; ++i) {
    // Aim at random points of the box volume (and a bit around it).
    const Eigen::Vector3d target = to_map * Eigen::Vector3d(6.0 * u(rng), 3.6 * u(rng), 4.0 + 5.0 * u(rng));
    const Eigen::Vector3d d = (target - origin).normalized();
    const auto expected = testing::ray_box(to_box * origin, to_box.linear() * d, lo, hi);
    const RayHit h = rc.cast(origin, d, 0);
    if (!expected) {
      EXPECT_NE(h.surface, SurfaceClass::kBuilding);
      continue;
    }
    ++hits;
    ASSERT_EQ(h.surface, SurfaceClass::kBuilding);
    EXPECT_NEAR(h.range, expected->s, kMm);
    EXPECT_NEAR((h.normal - to_map.linear() * expected->normal).norm(), 0.0, 1e-5);
    EXPECT_DOUBLE_EQ(h.reflectivity, Reflectivity{}.building);
  }
  EXPECT_GT(hits, 100);
}

// A fine icosphere is an inscribed polyhedron: every hit lies between the circumscribed sphere (its
// vertices' radius r) and the inscribed sphere (the smallest distance from the centre to a face
// plane, computed here from the mesh's faces), and the test requires the latter to be within 0.5 %.
TEST(SimRaycaster, HitsASphereBetweenItsInscribedAndCircumscribedSpheres) {
  Scene scene = ground_only();
  Shrub ball;  // equal extents: a sphere of radius 1 centred 1 m above the ground
  ball.x = 8.0;
  ball.y = -3.0;
  ball.length = ball.width = ball.height = 2.0;
  scene.shrubs.push_back(ball);
  RaycasterConfig config;
  config.sphere_subdivisions = 4;
  const Raycaster rc(scene, config);
  const Eigen::Vector3d centre(8.0, -3.0, 1.0);
  const double r = 1.0;
  const TriangleMesh& mesh = rc.static_mesh(SurfaceClass::kVegetation);
  double r_in = std::numeric_limits<double>::infinity();
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3d a = testing::vertex(mesh, t[0]);
    const Eigen::Vector3d n =
        (testing::vertex(mesh, t[1]) - a).cross(testing::vertex(mesh, t[2]) - a).normalized();
    r_in = std::min(r_in, std::abs(n.dot(a - centre)));
  }
  ASSERT_GT(r_in, 0.995 * r);
  const Eigen::Vector3d origin(0.0, 0.0, 1.5);
  std::mt19937 rng(3);
  for (int i = 0; i < 200; ++i) {
    const Eigen::Vector3d target = centre + 0.9 * r_in * random_unit(rng);
    const Eigen::Vector3d d = (target - origin).normalized();
    const auto outer = testing::ray_sphere(origin, d, centre, r);
    const auto inner = testing::ray_sphere(origin, d, centre, r_in);
    ASSERT_TRUE(outer && inner);
    const RayHit h = rc.cast(origin, d, 0);
    ASSERT_EQ(h.surface, SurfaceClass::kVegetation);
    EXPECT_GE(h.range, *outer - kMm);
    EXPECT_LE(h.range, *inner + kMm);
    // The facet normal is within a facet's angular size of the radial direction.
    const Eigen::Vector3d radial = (origin + h.range * d - centre).normalized();
    EXPECT_GT(h.normal.dot(radial), 0.99);
  }
}

TEST(SimRaycaster, BadRaysMissWithoutCrashing) {
  const Raycaster rc(ground_only());
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(rc.cast({nan, 0, 1}, {0, 0, -1}, 0).hit());
  EXPECT_FALSE(rc.cast({0, 0, 1}, {0, 0, 0}, 0).hit());
  EXPECT_FALSE(rc.cast({0, 0, 1}, {0, nan, -1}, 0).hit());
  EXPECT_FALSE(rc.cast({0, 0, 1}, {0, 0, -1}, 0, -5.0).hit());
  std::vector<Ray> rays(3);
  rays[0].origin = {0, 0, 1};
  rays[0].direction = {0, 0, -1};
  rays[1].origin = {nan, 0, 1};
  rays[2].direction = {0, 0, 0};
  std::vector<RayHit> hits(3);
  rc.cast_batch(rays, hits);
  EXPECT_TRUE(hits[0].hit());
  EXPECT_FALSE(hits[1].hit());
  EXPECT_FALSE(hits[2].hit());
  std::vector<RayHit> too_few(2);
  EXPECT_THROW(rc.cast_batch(rays, too_few), std::invalid_argument);
}

TEST(SimRaycaster, InvalidScenesThrowNamingTheObject) {
  Scene scene = ground_only();
  scene.buildings.push_back(Building{});
  scene.buildings.push_back(Building{});
  scene.buildings[1].height = std::numeric_limits<double>::quiet_NaN();
  try {
    const Raycaster rc(scene);
    ADD_FAILURE() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("building 1"), std::string::npos) << e.what();
  }
  Scene twins = ground_only();
  twins.vehicles.resize(2);
  twins.vehicles[0].id = twins.vehicles[1].id = 4;
  EXPECT_THROW(const Raycaster rc(twins), std::invalid_argument);
  Scene bad_shape = ground_only();
  bad_shape.vehicles.resize(1);
  bad_shape.vehicles[0].shape.width = -1.0;
  EXPECT_THROW(const Raycaster rc(bad_shape), std::invalid_argument);
}

// Side view of a parked car: a low horizontal ray over the wheel centre hits the tyre (slightly
// inboard of the body side, through the arch); the same ray between the axles hits the body side.
TEST(SimRaycaster, LowRaysHitTyresThroughTheArchesAndTheBodyBetweenThem) {
  Scene scene = ground_only();
  Vehicle v;
  v.id = 42;
  v.trajectory = StaticPose{{5.0, 10.0, 0.4}};
  scene.vehicles.push_back(v);
  const Raycaster rc(scene);
  const VehicleShape& s = v.shape;
  const Eigen::Matrix3d rot = Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Eigen::Vector3d pos(5.0, 10.0, 0.0);
  const Eigen::Vector3d inward = rot * Eigen::Vector3d(0, -1, 0);  // from the car's left side
  for (const double x_v : {0.5 * s.wheelbase, -0.5 * s.wheelbase, 0.0}) {
    const Eigen::Vector3d origin = pos + rot * Eigen::Vector3d(x_v, 5.0, s.wheel_radius);
    const RayHit h = rc.cast(origin, inward, 0);
    ASSERT_EQ(h.surface, SurfaceClass::kVehicle);
    EXPECT_EQ(h.vehicle_id, 42U);
    EXPECT_DOUBLE_EQ(h.reflectivity, Reflectivity{}.vehicle);
    const double y_hit = 5.0 - h.range;  // vehicle-frame y of the hit
    if (x_v == 0.0) {
      EXPECT_NEAR(y_hit, 0.5 * s.width, kMm);  // body side
    } else {
      EXPECT_LT(y_hit, 0.5 * s.width - 0.01);  // tyre, inboard
      EXPECT_GT(y_hit, 0.5 * s.width - 0.05);
    }
    EXPECT_NEAR((h.normal - rot * Eigen::Vector3d(0, 1, 0)).norm(), 0.0, 1e-3);
  }
}

// A vehicle driving along +x at 30 m/s: each ray sees it where it is at that ray's own time.
TEST(SimRaycaster, EachRaySeesTheVehicleAtItsOwnTime) {
  Scene scene = ground_only();
  Vehicle v;
  v.id = 7;
  const double speed = 30.0;
  Waypoints w;
  w.points = {{0, {0.0, 0.0, 0.0}}, {2'000'000'000, {speed * 2.0, 0.0, 0.0}}};
  v.trajectory = w;
  scene.vehicles.push_back(v);
  const Raycaster rc(scene);
  const double half_l = 0.5 * v.shape.length;
  // From behind along +x, at a height between the arch tops and the belt line: the flat rear face.
  const Eigen::Vector3d origin(-20.0, 0.0, 0.9);
  for (const TimeNs t : {TimeNs{0}, TimeNs{1'000'000}, TimeNs{50'000'000}, TimeNs{777'777'777}}) {
    const double x_rear = speed * to_seconds(t) - half_l;  // the test's own kinematics
    const RayHit h = rc.cast(origin, Eigen::Vector3d::UnitX(), t);
    ASSERT_EQ(h.surface, SurfaceClass::kVehicle);
    EXPECT_NEAR(h.range, x_rear - origin.x(), kMm) << "t = " << t;
  }
}

// Every field of the hit, exactly: the batch path must give the single-ray path's hits bit for bit (but for
// the face reported at an edge both faces meet at the same range).
// Cast in batches of `packet` rays, as the simulators cast a packet's.
void expect_same_hits(const Raycaster& rc, const std::vector<Ray>& rays, std::size_t packet,
                      const std::string& what) {
  std::vector<RayHit> batch(rays.size());
  for (std::size_t i = 0; i < rays.size(); i += packet) {
    const std::size_t n = std::min(packet, rays.size() - i);
    rc.cast_batch(std::span<const Ray>(rays).subspan(i, n), std::span<RayHit>(batch).subspan(i, n));
  }
  int vehicle_hits = 0;
  int hits = 0;
  int edge_ties = 0;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const RayHit single = rc.cast(rays[i].origin, rays[i].direction, rays[i].time_ns, rays[i].max_range);
    ASSERT_EQ(batch[i].surface, single.surface) << what << ", ray " << i;
    ASSERT_EQ(batch[i].vehicle_id, single.vehicle_id) << what << ", ray " << i;
    if (!single.hit()) {
      continue;
    }
    ++hits;
    ASSERT_EQ(batch[i].range, single.range) << what << ", ray " << i;
    ASSERT_EQ(batch[i].reflectivity, single.reflectivity) << what << ", ray " << i;
    if (batch[i].normal != single.normal) {
      // A ray exactly on the edge between two faces (a pole's facets): both faces are hit at the same
      // range, and Embree's packet and single-ray traversals may report either.
      ++edge_ties;
      EXPECT_LT(batch[i].normal.dot(rays[i].direction), 0.0) << what << ", ray " << i;
    }
    vehicle_hits += single.surface == SurfaceClass::kVehicle ? 1 : 0;
  }
  EXPECT_LE(edge_ties, hits / 10000) << what;
  EXPECT_GT(vehicle_hits, 50) << what;  // the vehicle path is exercised
}

// Rays as the simulators cast them, coherent, from a LiDAR 2 m up by the road: a VLP-32C-like packet
// (12 firings of 32 beams, each beam at its own time, in elevation order) and an Ouster-like packet
// (16 columns of 128 beams, a column's beams at one time), over a whole rotation each.
TEST(SimRaycaster, CoherentLidarBatchesMatchSingleRaysExactly) {
  const Raycaster rc(testing::street_with_traffic());
  const Eigen::Vector3d origin(0.0, 0.0, 2.0);
  const auto beam = [](double elevation, double azimuth) {
    return Eigen::Vector3d(std::cos(elevation) * std::cos(azimuth), std::cos(elevation) * std::sin(azimuth),
                           std::sin(elevation));
  };
  const double deg = std::acos(-1.0) / 180.0;
  // The car drives past within 3 m at t = 0.5 s: one rotation around that time.
  const TimeNs t0 = 450'000'000;
  std::vector<Ray> velodyne;
  for (int packet = 0; packet < 150; ++packet) {
    for (int laser = 0; laser < 32; ++laser) {
      for (int block = 0; block < 12; ++block) {
        const int firing = 12 * packet + block;
        Ray r;
        r.origin = origin;
        r.direction = beam((-25.0 + 40.0 * laser / 31.0) * deg, 0.2 * deg * firing);
        r.time_ns = t0 + firing * 55'296 + laser * 1'728;
        r.max_range = 200.0;
        velodyne.push_back(r);
      }
    }
  }
  expect_same_hits(rc, velodyne, 384, "VLP-32C-like");
  std::vector<Ray> ouster;
  for (int column = 0; column < 1024; ++column) {
    for (int row = 0; row < 128; ++row) {
      Ray r;
      r.origin = origin;
      r.direction = beam((-22.5 + 45.0 * row / 127.0) * deg, 2.0 * std::acos(-1.0) * column / 1024.0);
      r.time_ns = t0 + column * 97'656;
      r.max_range = 120.0;
      ouster.push_back(r);
    }
  }
  expect_same_hits(rc, ouster, 2048, "OS1-128-like");
}

TEST(SimRaycaster, BatchedCastingMatchesSingleRays) {
  const Scene scene = testing::street_with_traffic();
  std::mt19937 rng(5);
  std::vector<Ray> rays(2000);
  for (std::size_t i = 0; i < rays.size(); ++i) {
    rays[i].origin = {0.0, 0.0, 2.0};
    rays[i].direction = random_unit(rng);
    rays[i].time_ns = static_cast<TimeNs>(i) * 200'000;  // 0.4 s of sweep
    rays[i].max_range = 80.0;
  }
  for (const BatchMode mode : {BatchMode::kSingle, BatchMode::kPacket16, BatchMode::kStream}) {
    RaycasterConfig config;
    config.batch_mode = mode;
    const Raycaster rc(scene, config);
    std::vector<RayHit> batch(rays.size());
    rc.cast_batch(rays, batch);
    int vehicle_hits = 0;
    for (std::size_t i = 0; i < rays.size(); ++i) {
      const RayHit single = rc.cast(rays[i].origin, rays[i].direction, rays[i].time_ns, rays[i].max_range);
      ASSERT_EQ(batch[i].surface, single.surface) << "ray " << i;
      ASSERT_EQ(batch[i].vehicle_id, single.vehicle_id);
      if (single.hit()) {
        EXPECT_NEAR(batch[i].range, single.range, 1e-4);
      }
      vehicle_hits += single.surface == SurfaceClass::kVehicle ? 1 : 0;
    }
    EXPECT_GT(vehicle_hits, 5);
  }
}

}  // namespace
}  // namespace rsu::sim
