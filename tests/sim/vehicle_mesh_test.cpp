// SPDX-License-Identifier: Apache-2.0
#include "sim/vehicle_mesh.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>

#include "geometry_checks.h"

namespace rsu::sim {
namespace {

struct Extent {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e9);
  Eigen::Vector3d hi = Eigen::Vector3d::Constant(-1e9);
};

Extent extent_of(const TriangleMesh& m) {
  Extent e;
  for (const auto& v : m.vertices) {
    e.lo = e.lo.cwiseMin(v.cast<double>());
    e.hi = e.hi.cwiseMax(v.cast<double>());
  }
  return e;
}

void expect_footprint(const VehicleShape& s) {
  const Extent e = extent_of(make_vehicle_mesh(s));
  EXPECT_NEAR(e.lo.x(), -0.5 * s.length, 0.01);
  EXPECT_NEAR(e.hi.x(), 0.5 * s.length, 0.01);
  EXPECT_NEAR(e.lo.y(), -0.5 * s.width, 0.01);
  EXPECT_NEAR(e.hi.y(), 0.5 * s.width, 0.01);
  EXPECT_NEAR(e.lo.z(), 0.0, 1e-4);  // tyres on the ground
  EXPECT_NEAR(e.hi.z(), s.height, 1e-4);
}

VehicleShape random_shape(std::mt19937& rng) {
  auto u = [&rng](double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); };
  VehicleShape s;
  s.length = u(3.6, 6.0);
  s.width = u(1.6, 2.2);
  s.belt_height = u(0.9, 1.1);
  s.height = s.belt_height + u(0.35, 1.0);
  s.corner_radius = u(0.05, 0.5);
  s.ground_clearance = u(0.12, 0.3);
  s.cabin_inset = u(0.05, 0.2);
  s.hood_length = u(0.6, 0.25 * s.length);
  s.windscreen_run = u(0.3, 0.8);
  s.rear_slope_run = u(0.1, 0.4);
  s.wheel_radius = u(0.28, 0.38);
  s.wheel_width = u(0.18, 0.3);
  s.wheelbase = u(0.55, 0.62) * s.length;
  return s;
}

TEST(SimVehicleMesh, DefaultFootprintIsLengthByWidth) {
  expect_footprint(VehicleShape{});
}

TEST(SimVehicleMesh, RandomShapesFootprintIsLengthByWidth) {
  std::mt19937 rng(7);
  for (int i = 0; i < 40; ++i) {
    const VehicleShape s = random_shape(rng);
    SCOPED_TRACE("shape " + std::to_string(i));
    expect_footprint(s);
  }
}

TEST(SimVehicleMesh, EveryComponentIsClosedAndOutward) {
  std::mt19937 rng(11);
  for (int i = 0; i < 5; ++i) {
    const VehicleShape s = i == 0 ? VehicleShape{} : random_shape(rng);
    const TriangleMesh m = make_vehicle_mesh(s);
    EXPECT_EQ(testing::closed_mesh_problem(m), "");
    const auto parts = testing::components(m);
    // lower body (1 upper band + 3 full-width pieces + 2 well cores) + glasshouse + 4 wheels + 2 mirrors
    EXPECT_EQ(parts.size(), 6U + 1U + 4U + 2U);
    for (const auto& p : parts) {
      EXPECT_GT(testing::signed_volume(p), 0.0);
    }
  }
}

TEST(SimVehicleMesh, IsShapedLikeACarNotABox) {
  const VehicleShape s;
  const TriangleMesh m = make_vehicle_mesh(s);
  const double half_l = 0.5 * s.length;
  const double half_w = 0.5 * s.width;
  for (const auto& v : m.vertices) {
    const Eigen::Vector3d p = v.cast<double>();
    // Rounded plan-view corners: nothing reaches the corner of the footprint rectangle.
    const Eigen::Vector2d corner(std::copysign(half_l, p.x()), std::copysign(half_w, p.y()));
    EXPECT_GT((p.head<2>() - corner).norm(), s.corner_radius * (std::sqrt(2.0) - 1.0) - 1e-3);
    // Above the mirrors only the glasshouse: inset each side and behind the windscreen base.
    if (p.z() > s.belt_height + 0.21) {
      EXPECT_LE(std::abs(p.y()), half_w - s.cabin_inset + 1e-4);
      EXPECT_LE(p.x(), half_l - s.hood_length + 1e-4);
    }
    // The roof is shortened by the windscreen and rear-window slopes.
    if (p.z() > s.height - 1e-4) {
      EXPECT_LE(p.x(), half_l - s.hood_length - s.windscreen_run + 1e-4);
      EXPECT_GE(p.x(), -half_l + s.cabin_inset + s.rear_slope_run - 1e-4);
    }
  }
}

TEST(SimVehicleMesh, InconsistentShapesThrowNamingTheField) {
  VehicleShape s;
  s.belt_height = 2.0;  // above the roof
  EXPECT_THROW(make_vehicle_mesh(s), std::invalid_argument);
  s = VehicleShape{};
  s.length = std::numeric_limits<double>::quiet_NaN();
  try {
    make_vehicle_mesh(s);
    ADD_FAILURE() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("length"), std::string::npos) << e.what();
  }
  s = VehicleShape{};
  s.corner_radius = 1.5;  // more than half the width
  EXPECT_THROW(make_vehicle_mesh(s), std::invalid_argument);
  s = VehicleShape{};
  s.wheelbase = 4.8;  // arches outside the body
  EXPECT_THROW(make_vehicle_mesh(s), std::invalid_argument);
}

}  // namespace
}  // namespace rsu::sim
