// SPDX-License-Identifier: Apache-2.0
#include "sim/vehicle_mesh.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "common/angles.h"

namespace rsu::sim {
namespace {

// Fixed small proportions of the model (not worth a VehicleShape field each).
constexpr double kArchGap = 0.05;        // clearance between tyre and wheel arch, m
constexpr double kWheelInset = 0.02;     // tyre outer face inboard of the body side, m
constexpr double kWellClearance = 0.02;  // wheel-well inner wall inboard of the tyre's inner face, m
constexpr double kTumblehome = 0.05;     // roof narrower than the glasshouse base, each side, m
constexpr double kMirrorLength = 0.20;   // along x
constexpr double kMirrorHeight = 0.15;
constexpr double kMirrorLift = 0.05;     // above the belt line
constexpr double kMirrorSetback = 0.25;  // behind the windscreen base
constexpr double kMirrorEmbed = 0.12;    // how far the mirror reaches into the glasshouse
constexpr double kMirrorSideGap = 0.01;  // inboard of the body side, so the footprint stays exact
constexpr int kBodyArcSegments = 8;
constexpr int kWheelSegments = 24;

void require(bool ok, const std::string& what) {
  if (!ok) {
    throw std::invalid_argument("vehicle shape: " + what);
  }
}

double arch_top(const VehicleShape& s) {
  return 2.0 * s.wheel_radius + kArchGap;
}
double windscreen_base_x(const VehicleShape& s) {
  return 0.5 * s.length - s.hood_length;
}
double well_half_width(const VehicleShape& s) {
  return 0.5 * s.width - kWheelInset - s.wheel_width - kWellClearance;
}

// Rounded rectangle spanning [x0, x1] x [-hy, hy] with corner radius r clamped to fit.
std::vector<Eigen::Vector2d> plan_outline(double x0, double x1, double hy, double r) {
  const double hx = 0.5 * (x1 - x0);
  return rounded_rectangle(0.5 * (x0 + x1), 0.0, hx, hy, std::clamp(r, 0.0, std::min(hx, hy)),
                           kBodyArcSegments);
}

TriangleMesh make_lower_body(const VehicleShape& s) {
  const double half_l = 0.5 * s.length;
  const double half_w = 0.5 * s.width;
  const double top_of_arch = arch_top(s);
  const auto outline = plan_outline(-half_l, half_l, half_w, s.corner_radius);
  const double arch_half = s.wheel_radius + kArchGap;
  const double front_arch_min = 0.5 * s.wheelbase - arch_half;
  const double front_arch_max = 0.5 * s.wheelbase + arch_half;

  TriangleMesh body;
  // Above the arches: the full outline up to the belt line.
  body.append(make_prism(outline, top_of_arch, s.belt_height));
  // Below the arch tops: full width ahead of, between and behind the arches ...
  body.append(make_prism(clip_polygon_x(outline, front_arch_max, half_l), s.ground_clearance, top_of_arch));
  body.append(
      make_prism(clip_polygon_x(outline, -front_arch_min, front_arch_min), s.ground_clearance, top_of_arch));
  body.append(make_prism(clip_polygon_x(outline, -half_l, -front_arch_max), s.ground_clearance, top_of_arch));
  // ... and only the narrow wheel-well core inside the arches, so the tyres are exposed to low rays.
  const double core = well_half_width(s);
  for (const double sign : {1.0, -1.0}) {
    const double lo = sign > 0 ? front_arch_min : -front_arch_max;
    const double hi = sign > 0 ? front_arch_max : -front_arch_min;
    body.append(make_box({lo, -core, s.ground_clearance}, {hi, core, top_of_arch}));
  }
  return body;
}

TriangleMesh make_glasshouse(const VehicleShape& s) {
  const double half_l = 0.5 * s.length;
  const double base_half_w = 0.5 * s.width - s.cabin_inset;
  const double roof_half_w = base_half_w - kTumblehome;
  const double base_x0 = -half_l + s.cabin_inset;
  const double base_x1 = windscreen_base_x(s);
  const double roof_x0 = base_x0 + s.rear_slope_run;
  const double roof_x1 = base_x1 - s.windscreen_run;
  // The glasshouse corners follow the body's rounding, shrunk by the inset (at least 5 cm).
  const double r = std::max(s.corner_radius - s.cabin_inset, 0.05);
  return make_loft(plan_outline(base_x0, base_x1, base_half_w, r), s.belt_height,
                   plan_outline(roof_x0, roof_x1, roof_half_w, r), s.height);
}

TriangleMesh make_wheels(const VehicleShape& s) {
  TriangleMesh wheels;
  // A cylinder along z from y_in to y_out, turned so that its axis is y: rotation of -90 deg about x
  // maps +z to +y (a proper rotation, so the winding stays outward).
  const double outer = 0.5 * s.width - kWheelInset;
  const TriangleMesh left = make_cylinder(s.wheel_radius, outer - s.wheel_width, outer, kWheelSegments);
  const TriangleMesh right = make_cylinder(s.wheel_radius, -outer, -outer + s.wheel_width, kWheelSegments);
  const Eigen::AngleAxisd z_to_y(-0.5 * kPi, Eigen::Vector3d::UnitX());
  for (const double x : {0.5 * s.wheelbase, -0.5 * s.wheelbase}) {
    const Eigen::Affine3d place = Eigen::Translation3d(x, 0.0, s.wheel_radius) * z_to_y;
    wheels.append(transformed(left, place));
    wheels.append(transformed(right, place));
  }
  return wheels;
}

TriangleMesh make_mirrors(const VehicleShape& s) {
  TriangleMesh mirrors;
  const double x1 = windscreen_base_x(s) - kMirrorSetback;
  const double x0 = x1 - kMirrorLength;
  const double z0 = s.belt_height + kMirrorLift;
  const double z1 = z0 + kMirrorHeight;
  const double outer = 0.5 * s.width - kMirrorSideGap;
  const double inner = 0.5 * s.width - s.cabin_inset - kMirrorEmbed;
  mirrors.append(make_box({x0, inner, z0}, {x1, outer, z1}));
  mirrors.append(make_box({x0, -outer, z0}, {x1, -inner, z1}));
  return mirrors;
}

}  // namespace

void validate_vehicle_shape(const VehicleShape& s) {
  const auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  require(positive(s.length), "length must be positive and finite");
  require(positive(s.width), "width must be positive and finite");
  require(positive(s.height), "height must be positive and finite");
  require(positive(s.ground_clearance), "ground_clearance must be positive and finite");
  require(positive(s.belt_height) && s.belt_height > arch_top(s) && s.belt_height > s.ground_clearance,
          "belt_height must be above the wheel arch tops (2 * wheel_radius + 5 cm)");
  require(std::isfinite(s.corner_radius) && s.corner_radius >= 0.0 &&
              s.corner_radius < 0.5 * std::min(s.length, s.width),
          "corner_radius must be in [0, min(length, width) / 2)");
  require(s.height >= s.belt_height + kMirrorLift + kMirrorHeight + 0.05,
          "height must exceed belt_height by at least 25 cm (glasshouse and mirrors)");
  require(std::isfinite(s.cabin_inset) && s.cabin_inset >= 0.0 &&
              0.5 * s.width - s.cabin_inset - kTumblehome >= 0.1,
          "cabin_inset must leave a glasshouse at least 20 cm wide");
  require(positive(s.wheel_radius) && s.ground_clearance < arch_top(s),
          "wheel_radius must be positive and the arches must reach above ground_clearance");
  require(positive(s.wheel_width) && well_half_width(s) >= 0.1,
          "wheel_width must leave a wheel-well core at least 20 cm wide");
  require(positive(s.wheelbase) && s.wheelbase > 2.0 * (s.wheel_radius + kArchGap) + 0.1 &&
              0.5 * s.wheelbase + s.wheel_radius + kArchGap < 0.5 * s.length - 0.05,
          "wheelbase must keep the wheel arches apart and inside the length");
  require(std::isfinite(s.hood_length) && s.hood_length >= 0.0 && std::isfinite(s.windscreen_run) &&
              s.windscreen_run >= 0.0 && std::isfinite(s.rear_slope_run) && s.rear_slope_run >= 0.0,
          "hood_length, windscreen_run and rear_slope_run must be finite and >= 0");
  const double roof_length =
      windscreen_base_x(s) - s.windscreen_run - (-0.5 * s.length + s.cabin_inset) - s.rear_slope_run;
  require(roof_length >= 0.3,
          "hood_length + windscreen_run + rear_slope_run leave a roof shorter than 30 cm");
  require(windscreen_base_x(s) - kMirrorSetback - kMirrorLength >
              -0.5 * s.length + s.cabin_inset + s.rear_slope_run,
          "hood_length leaves no room for the mirrors beside the glasshouse");
}

TriangleMesh make_vehicle_mesh(const VehicleShape& shape) {
  validate_vehicle_shape(shape);
  TriangleMesh mesh = make_lower_body(shape);
  mesh.append(make_glasshouse(shape));
  mesh.append(make_wheels(shape));
  mesh.append(make_mirrors(shape));
  return mesh;
}

}  // namespace rsu::sim
