// SPDX-License-Identifier: Apache-2.0
// The fix covariance grows where the fit is weakly constrained: fewer points, one face seen, longer
// range. Checked on the model directly and end to end on scans of known boxes.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

#include <Eigen/Core>

#include "common/angles.h"
#include "common/symmetric_eigen.h"
#include "perception/fix_covariance.h"
#include "perception/informative_face.h"
#include "perception/l_shape_fitting.h"
#include "perception/lidar_geometry.h"
#include "perception/size_correction.h"
#include "synthetic_scene.h"

namespace rsu::perception {
namespace {

using test::TrueBox;

// Variance of the position along unit direction d.
double variance_along(const Eigen::Matrix3d& cov, const Eigen::Vector2d& d) {
  return d.dot(cov.topLeftCorner<2, 2>() * d);
}

bool positive_semidefinite(const Eigen::Matrix3d& cov) {
  const SymmetricEigen3 eig(cov);
  return eig.eigenvalues().minCoeff() >= -1e-15 && (cov - cov.transpose()).norm() < 1e-15;
}

// The points' laser ranks, as the fix gives them to informative_face.
std::vector<std::size_t> ranks_of(const std::vector<Eigen::Vector3d>& points, const LidarGeometry& lidar) {
  return LaserLookup(lidar.elevations_rad).ranks(points, lidar.position);
}

FixEvidence two_faces(double range, std::size_t points_per_face) {
  FixEvidence e;
  e.range_m = range;
  e.yaw = 0.3;
  e.lever = Eigen::Vector2d(1.5, 1.7);
  e.length_axis = {AxisAnchor::face, points_per_face};
  e.width_axis = {AxisAnchor::face, points_per_face};
  e.seen_faces = {FaceEvidence{points_per_face, 4.8}, FaceEvidence{points_per_face, 1.9}};
  return e;
}

// A direction the faces' refit does not settle on is known no better than it moves: its variance adds.
TEST(FixCovariance, UnsettledFacesWidenTheirYaw) {
  const FixEvidence settled = two_faces(30.0, 12);
  FixEvidence unsettled = settled;
  unsettled.faces_unsettled_rad = deg_to_rad(4.0);
  const double settled_info = face_yaw_information(settled);
  ASSERT_GT(settled_info, 0.0);
  EXPECT_NEAR(1.0 / face_yaw_information(unsettled), 1.0 / settled_info + std::pow(deg_to_rad(4.0), 2),
              1e-12);
  EXPECT_GT(fix_covariance(unsettled)(2, 2), fix_covariance(settled)(2, 2));
  // No faces, no information, whatever the refit did.
  FixEvidence none = unsettled;
  none.seen_faces = {};
  EXPECT_EQ(face_yaw_information(none), 0.0);
}

// Without a range the points' noise is unknown: the faces tell nothing, the position is unbounded (every
// cap refuses it) and the yaw states the most a fix may; before, it was taken as 0 m, the smallest noise.
TEST(FixCovariance, AnUnknownRangeBoundsNothing) {
  for (const double range : {std::nan(""), std::numeric_limits<double>::infinity()}) {
    const FixEvidence evidence = two_faces(range, 60);
    EXPECT_EQ(face_yaw_information(evidence), 0.0) << range;
    const Eigen::Matrix3d cov = fix_covariance(evidence);
    EXPECT_TRUE(std::isinf(cov(0, 0)) && std::isinf(cov(1, 1))) << range;
    const CovarianceModelConfig config;
    EXPECT_DOUBLE_EQ(cov(2, 2), config.max_yaw_sigma_rad * config.max_yaw_sigma_rad);
    CorrectedPose fix;
    fix.covariance = cov;
    EXPECT_TRUE(std::isinf(position_sigma_m(fix)));
    EXPECT_GT(position_sigma_m(fix), max_position_sigma_m(true, CorrectionConfig{}));
  }
}

// A covariance holding NaN states no bound: unbounded, not 0 (std::max(0, NaN) is 0, a perfect fix).
TEST(FixCovariance, ANotANumberCovarianceIsUnbounded) {
  CorrectedPose fix;
  fix.covariance = Eigen::Matrix3d::Identity() * 0.01;
  EXPECT_NEAR(position_sigma_m(fix), 0.1, 1e-12);
  fix.covariance(0, 1) = fix.covariance(1, 0) = std::nan("");
  EXPECT_TRUE(std::isinf(position_sigma_m(fix)));
  fix.covariance = Eigen::Matrix3d::Identity() * 0.01;
  fix.covariance(1, 1) = std::nan("");
  EXPECT_GT(position_sigma_m(fix), max_position_sigma_m(false, CorrectionConfig{}));
}

TEST(FixCovariance, ModelIsMonotoneInPointsRangeAndFaces) {
  const Eigen::Matrix3d base = fix_covariance(two_faces(15.0, 60));
  ASSERT_TRUE(positive_semidefinite(base));
  const Eigen::Vector2d u(std::cos(0.3), std::sin(0.3)), v(-u.y(), u.x());

  const Eigen::Matrix3d few = fix_covariance(two_faces(15.0, 8));
  EXPECT_GT(variance_along(few, u), variance_along(base, u));
  EXPECT_GT(variance_along(few, v), variance_along(base, v));
  EXPECT_GT(few(2, 2), base(2, 2));

  const Eigen::Matrix3d far = fix_covariance(two_faces(40.0, 60));
  EXPECT_GT(variance_along(far, u), variance_along(base, u));
  EXPECT_GT(variance_along(far, v), variance_along(base, v));
  EXPECT_GT(far(2, 2), base(2, 2));

  // Only the front (perpendicular to the length axis) seen: the width-axis position comes from the
  // front's two ends and the yaw from one short face.
  FixEvidence front = two_faces(15.0, 60);
  front.width_axis = {AxisAnchor::midpoint, 0};
  front.seen_faces = {FaceEvidence{60, 1.9}, FaceEvidence{}};
  const Eigen::Matrix3d one_face = fix_covariance(front);
  EXPECT_GT(variance_along(one_face, v), variance_along(base, v));
  EXPECT_GT(one_face(2, 2), base(2, 2));
  FixEvidence one_end = front;
  one_end.width_axis = {AxisAnchor::one_end, 0};
  EXPECT_GT(variance_along(fix_covariance(one_end), v), variance_along(one_face, v));

  // The middle of two ends whose span falls short of the known size: the centre may lie anywhere the
  // shortfall leaves (one end cut by a rounded corner, the other not): its uniform spread is added.
  FixEvidence short_span = front;
  short_span.width_axis.interval_m = 0.28;
  EXPECT_NEAR(variance_along(fix_covariance(short_span), v) - variance_along(one_face, v), 0.28 * 0.28 / 12.0,
              1e-9);

  // The yaw's effect on the centre covers both the lever's (a small turn about the evidence) and the
  // probes' (the box placed again far out): probes that moved the box along its length leave the lever's
  // turn across it, and vice versa; where they agree nothing is added.
  FixEvidence probed = two_faces(15.0, 60);
  probed.lever = 1.8 * u;  // a small turn moves the centre across (along v) by 1.8 m/rad
  probed.yaw_probe_rad = {0.25, -0.25};
  probed.yaw_probe_shift = {0.25 * 3.0 * u, -0.25 * 3.0 * u};  // the probes moved it along by 3 m/rad
  const Eigen::Matrix3d probed_cov = fix_covariance(probed);
  const double var_yaw = probed_cov(2, 2);
  FixEvidence about_centre = two_faces(15.0, 60);  // a turn moves the centre nowhere
  about_centre.lever = Eigen::Vector2d::Zero();
  const Eigen::Matrix3d unturned = fix_covariance(about_centre);
  EXPECT_GE(variance_along(probed_cov, v) - variance_along(unturned, v), var_yaw * 1.8 * 1.8 * 0.99);
  EXPECT_GE(variance_along(probed_cov, u) - variance_along(unturned, u), var_yaw * 3.0 * 3.0 * 0.99);
  FixEvidence agreeing = probed;
  agreeing.yaw_probe_shift = {0.25 * 1.8 * v, -0.25 * 1.8 * v};
  EXPECT_NEAR(variance_along(fix_covariance(agreeing), v), variance_along(unturned, v) + var_yaw * 1.8 * 1.8,
              1e-5);
  EXPECT_TRUE(positive_semidefinite(probed_cov));

  // An uncertain length/width assignment adds the other hypothesis' spread.
  FixEvidence doubtful = two_faces(15.0, 60);
  doubtful.assignment_confidence = 0.6;
  doubtful.alternative_offset = Eigen::Vector2d(1.4, -0.2);
  const Eigen::Matrix3d mixed = fix_covariance(doubtful);
  EXPECT_GT(mixed(0, 0), base(0, 0) + 0.3);
  EXPECT_GT(mixed(2, 2), base(2, 2) + 0.3);
  for (const auto& c : {few, far, one_face, mixed})
    EXPECT_TRUE(positive_semidefinite(c));
}

// A face seen at grazing incidence, or whose points scatter about their line more than the point noise
// explains (a body that is not a flat face), fixes the direction less well; a scatter the noise explains
// changes nothing (it already averages out over the points).
TEST(FixCovariance, GrazingOrBulgingFacesGiveLessCertainYaw) {
  const FixEvidence base = two_faces(15.0, 60);
  const double base_yaw = fix_covariance(base)(2, 2);

  FixEvidence grazing = base;
  grazing.seen_faces[0].incidence_sin = 0.3;
  EXPECT_GT(fix_covariance(grazing)(2, 2), base_yaw);
  FixEvidence more_grazing = grazing;
  more_grazing.seen_faces[0].incidence_sin = 0.15;
  EXPECT_GT(fix_covariance(more_grazing)(2, 2), fix_covariance(grazing)(2, 2));

  const CovarianceModelConfig config;
  const double noise_sigma = std::hypot(config.range_sigma_m, 15.0 * config.angle_sigma_rad);
  FixEvidence noisy = base;
  noisy.seen_faces[0].residual_spread_m = 0.9 * noise_sigma;
  EXPECT_DOUBLE_EQ(fix_covariance(noisy)(2, 2), base_yaw);
  FixEvidence bulging = base;
  bulging.seen_faces[0].residual_spread_m = 0.1;
  EXPECT_GT(fix_covariance(bulging)(2, 2), base_yaw);
  EXPECT_TRUE(positive_semidefinite(fix_covariance(bulging)));
}

// The incidence of a fitted edge is measured from the LiDAR to the edge's midpoint.
TEST(FixCovariance, FaceEvidenceMeasuresTheIncidence) {
  RectangleFit fit;
  fit.status = FitStatus::ok;
  fit.length0 = 4.0;
  fit.length1 = 2.0;
  fit.corners = {Eigen::Vector2d(10.0, 0.0), Eigen::Vector2d(14.0, 0.0), Eigen::Vector2d(14.0, 2.0),
                 Eigen::Vector2d(10.0, 2.0)};
  fit.edges[0].support_points = 17;
  const Eigen::Vector2d lidar(12.0, -8.0);  // straight below edge 0's midpoint: head-on
  const FaceEvidence head_on = face_evidence(fit, 0, lidar);
  EXPECT_EQ(head_on.points, 17U);
  EXPECT_DOUBLE_EQ(head_on.length_m, 4.0);
  EXPECT_NEAR(head_on.incidence_sin, 1.0, 1e-12);
  // Edge 3 (x = 10, from y = 2 to 0) seen from (12, -8): line of sight to (10, 1) is (-2, 9).
  const FaceEvidence side = face_evidence(fit, 3, lidar);
  EXPECT_DOUBLE_EQ(side.length_m, 2.0);
  EXPECT_NEAR(side.incidence_sin, 2.0 / std::hypot(2.0, 9.0), 1e-12);
}

// A face of length l along x from the origin, seen head-on from 8 m by a LiDAR 2 m up, its points 2 cm apart
// at 0.5 m (the lower body); `near_corner` / `far_corner`: that end is a quarter circle of radius r curving
// into the box (a rounded corner), of which the points within the face's support band are kept.
struct CornerFace {
  std::vector<Eigen::Vector3d> points;
  RectangleFit fit;
  LidarGeometry lidar;
};

CornerFace corner_face(double l, double r, bool near_corner, bool far_corner, double band) {
  CornerFace f;
  const auto add = [&](double x, double y) {
    if (y <= band)
      f.points.emplace_back(x, y, 0.5);
  };
  const double step = 0.02;
  const double straight_from = near_corner ? r : 0.0;
  const double straight_to = far_corner ? l - r : l;
  for (double x = straight_from; x <= straight_to + 1e-9; x += step)
    add(x, 0.0);
  const int arc_points = static_cast<int>(std::numbers::pi / 2.0 * r / step);
  for (int i = 1; i <= arc_points; ++i) {
    const double t = std::numbers::pi / 2.0 * i / arc_points;
    if (far_corner)
      add(l - r + r * std::sin(t), r - r * std::cos(t));
    if (near_corner)
      add(r - r * std::sin(t), r - r * std::cos(t));
  }
  f.fit.status = FitStatus::ok;
  f.fit.length0 = l;
  f.fit.length1 = 1.8;
  f.fit.corners = {Eigen::Vector2d(0.0, 0.0), Eigen::Vector2d(l, 0.0), Eigen::Vector2d(l, 1.8),
                   Eigen::Vector2d(0.0, 1.8)};
  f.fit.edges[0].support_points = f.points.size();
  f.fit.edges[0].seen = true;
  f.lidar.position = Eigen::Vector3d(0.5 * l, -8.0, 2.0);
  return f;
}

// The yaw sigma one seen face states (no prior).
double face_sigma(const CornerFace& f, const VehicleSize& size) {
  const CorrectionConfig config;
  FixEvidence e;
  e.range_m = 8.0;
  e.seen_faces[0] =
      informative_face(f.points, ranks_of(f.points, f.lidar), f.lidar, config, 0.78, 0.02, f.fit, 0, size);
  return 1.0 / std::sqrt(face_yaw_information(e, config.covariance));
}

// A rounded corner at one end of a face turns its least-squares line (the test fits it); the face's stated
// direction sigma covers that turn for corner radii 0.2-0.35 m on an end shorter than the vehicle's width
// (its other end unseen; longer faces are refit on their middle, face_refinement.h).
TEST(InformativeFace, RoundedCornerTurnIsCovered) {
  const CorrectionConfig config;
  const VehicleSize size{4.6, 1.8, 1.42};
  for (const double l : {1.0, 1.2, 1.4}) {
    for (const double r : {0.2, 0.3, 0.35}) {
      const CornerFace f = corner_face(l, r, false, true, config.fit.edge_support_m);
      double mx = 0.0, my = 0.0;
      for (const auto& p : f.points) {
        mx += p.x();
        my += p.y();
      }
      mx /= static_cast<double>(f.points.size());
      my /= static_cast<double>(f.points.size());
      double sxx = 0.0, sxy = 0.0;
      for (const auto& p : f.points) {
        sxx += (p.x() - mx) * (p.x() - mx);
        sxy += (p.x() - mx) * (p.y() - my);
      }
      const double turn = std::abs(std::atan(sxy / sxx));
      EXPECT_GT(turn, deg_to_rad(0.1)) << l << " " << r;  // the corner turns it
      EXPECT_GE(face_sigma(f, size), turn) << l << " " << r;
    }
  }
}

// An end seen whole (both rounded corners, the vehicle's width within full_face_tolerance_m): the corners
// turn it in opposite senses, and it states a surer direction than the same end with one corner unseen.
TEST(InformativeFace, WholeEndWithBothCornersIsSurerThanPartOfIt) {
  const CorrectionConfig config;
  const VehicleSize size{4.6, 1.8, 1.42};
  const CornerFace whole = corner_face(1.8, 0.3, true, true, config.fit.edge_support_m);
  const VehicleSize wider{4.6, 2.5, 1.42};  // the same points, an end 0.7 m wider than they span
  EXPECT_LT(face_sigma(whole, size), face_sigma(whole, wider));
}

// A coupe's fitted rectangle, 4.5 x 1.9 m, its edge 0 along x from 0 to 4.5 m seen.
RectangleFit coupe_fit() {
  RectangleFit fit;
  fit.status = FitStatus::ok;
  fit.length0 = 4.5;
  fit.length1 = 1.9;
  fit.corners = {Eigen::Vector2d(0.0, 0.0), Eigen::Vector2d(4.5, 0.0), Eigen::Vector2d(4.5, 1.9),
                 Eigen::Vector2d(0.0, 1.9)};
  fit.edges[0].seen = true;
  return fit;
}

// A face's returns at `along` (x, on y = 0 at 0.5 m) on the coupe's fitted edge 0, seen head-on from 8 m by
// a LiDAR 2 m up: the departure it states.
double face_departure(const std::vector<double>& along) {
  const CorrectionConfig config;
  LidarGeometry lidar;
  lidar.position = Eigen::Vector3d(0.5, -8.0, 2.0);
  std::vector<Eigen::Vector3d> points;
  for (const double x : along)
    points.emplace_back(x, 0.0, 0.5);
  return informative_face(points, ranks_of(points, lidar), lidar, config, 0.78, 0.02, coupe_fit(), 0,
                          {4.5, 1.9, 1.25})
      .departure_m;
}

// Returns bunched at both ends of a run shorter than a short face spread as far as an evenly spread face
// longer than one (spread_length): the face is still short (it may lie on a rounded corner or in a wheel
// arch) and departs as one. Evenly over 1.2 m, it is not.
TEST(InformativeFace, ReturnsBunchedAtTheEndsOfAShortRunAreAShortFace) {
  const CorrectionConfig config;
  const std::vector<double> bunched{0.0, 0.05, 0.1, 0.8, 0.85, 0.9};
  double mean = 0.0, sum_sq = 0.0;
  for (const double x : bunched)
    mean += x / static_cast<double>(bunched.size());
  for (const double x : bunched)
    sum_sq += (x - mean) * (x - mean);
  ASSERT_GT(std::sqrt(12.0 * sum_sq / static_cast<double>(bunched.size())), config.short_face_m);
  EXPECT_GE(face_departure(bunched), config.short_face_tilt_m);
  EXPECT_LT(face_departure({0.0, 0.2, 0.4, 0.6, 0.8, 1.0, 1.2}), config.short_face_tilt_m);
}

// A face of fewer returns than the lower body's outline needs (min_lower_body_points): each one alone turns
// its line (one on a rounded corner, in a wheel arch), so it departs as a short face does, however far they
// spread (five over 1.1 m, no gap wider than a short face). As many as that, evenly over 1.5 m, do not.
TEST(InformativeFace, AFaceOfAFewReturnsDepartsAsAShortFace) {
  const CorrectionConfig config;
  const std::vector<double> few{0.0, 0.05, 0.1, 0.6, 1.1};
  ASSERT_LT(few.size(), config.min_lower_body_points);
  EXPECT_GE(face_departure(few), config.short_face_tilt_m);
  std::vector<double> even;
  for (std::size_t i = 0; i < config.min_lower_body_points; ++i)
    even.push_back(1.5 * static_cast<double>(i) / static_cast<double>(config.min_lower_body_points - 1));
  EXPECT_LT(face_departure(even), config.short_face_tilt_m);
}

// One laser's straight trace (a vertical surface in plan) through the middle of a fitted edge along x from
// 0 to 4.5 m at `angle` to it, every 0.12 m, seen by a laser 9 deg down from 6 m up, 34 m away; `step`: the
// trace's second half lies this far farther inside the box (a laser leaving the side onto a higher surface).
double chord_sigma(double angle, double step) {
  const CorrectionConfig config;
  const RectangleFit fit = coupe_fit();
  LidarGeometry lidar;
  lidar.position = Eigen::Vector3d(2.25, -34.0, 6.0);
  lidar.elevations_rad = {deg_to_rad(-11.0), deg_to_rad(-9.0), deg_to_rad(-7.0)};
  std::vector<Eigen::Vector3d> points;
  const Eigen::Vector2d direction(std::cos(angle), std::sin(angle));
  for (double t = -2.2; t <= 2.2 + 1e-9; t += 0.12) {
    Eigen::Vector2d xy = Eigen::Vector2d(2.25, 0.0) + t * direction;
    if (t > 0.0)
      xy.y() += step;
    if (xy.x() < 0.0 || xy.x() > 4.5)
      continue;
    const double run = (xy - lidar.xy()).norm();
    points.emplace_back(xy.x(), xy.y(), 6.0 + run * std::tan(deg_to_rad(-9.0)));
  }
  FixEvidence e;
  e.range_m = 34.0;
  e.seen_faces[0] =
      informative_face(points, ranks_of(points, lidar), lidar, config, 0.69, 0.03, fit, 0, {4.5, 1.9, 1.25});
  return 1.0 / std::sqrt(face_yaw_information(e, config.covariance));
}

// A fitted edge that a laser's straight trace crosses holds only the trace's returns where it crosses its
// support band: its direction is the trace's, and the stated sigma covers the angle between them. A trace
// along the edge, or one leaving it onto a surface farther in (not one straight line), states no more. (On
// this clean, evenly sampled chord the band's own spread already states 14 and 30 deg at 15 and 25 deg
// without crossing_trace_departure; the coupe's sparse, noisy one did not: VehicleFixGeometry's
// FaceThatIsAChordOfATrace.)
TEST(InformativeFace, ChordOfAStraightTraceStatesTheTracesAngle) {
  // At 8 deg half the trace lies in the band: a face of it, its spread about the edge its departure.
  EXPECT_GE(3.0 * chord_sigma(deg_to_rad(8.0), 0.0), deg_to_rad(8.0));
  for (const double angle_deg : {15.0, 25.0}) {
    const double sigma = chord_sigma(deg_to_rad(angle_deg), 0.0);
    EXPECT_GE(sigma, 0.9 * deg_to_rad(angle_deg)) << angle_deg;
    EXPECT_LE(sigma, 2.0 * deg_to_rad(angle_deg)) << angle_deg;
  }
  const double along = chord_sigma(0.0, 0.0);
  EXPECT_LT(along, deg_to_rad(1.0));
  EXPECT_LT(chord_sigma(0.0, 0.5), deg_to_rad(2.0));
}

// Seen from a mast 6 m up, 28-32 m from a fitted edge along x from 0 to 4.5 m (a coupe's side, 1.25 m
// high, its bonnet up to 0.69 m): lasers' traces over its upper body, given in plan (each point's laser and
// xy; its height is where that laser meets it). laser_through(s): the elevation of a laser meeting the
// edge 1 m up at s along it.
const Eigen::Vector3d kMast(-20.0, -20.0, 6.0);

double laser_through(double s) {
  return std::atan((1.0 - kMast.z()) / (Eigen::Vector2d(s, 0.0) - kMast.head<2>()).norm());
}

struct MastTrace {
  std::size_t laser;
  Eigen::Vector2d xy;
};

FaceEvidence mast_face(const std::vector<MastTrace>& trace, const std::vector<double>& elevations_rad) {
  const CorrectionConfig config;
  const RectangleFit fit = coupe_fit();
  LidarGeometry lidar;
  lidar.position = kMast;
  lidar.elevations_rad = elevations_rad;
  std::vector<Eigen::Vector3d> points;
  for (const MastTrace& m : trace) {
    const double run = (m.xy - lidar.xy()).norm();
    points.emplace_back(m.xy.x(), m.xy.y(), kMast.z() + run * std::tan(elevations_rad[m.laser]));
    EXPECT_GT(points.back().z(), 0.69);  // above the bonnet
  }
  return informative_face(points, ranks_of(points, lidar), lidar, config, 0.69, 0.03, fit, 0,
                          {4.5, 1.9, 1.25});
}

double yaw_sigma_of(const FaceEvidence& face) {
  FixEvidence e;
  e.range_m = 30.0;
  e.seen_faces[0] = face;
  return 1.0 / std::sqrt(face_yaw_information(e, CorrectionConfig{}.covariance));
}

// Two lasers' runs along the edge above the bonnet, one over 0.3-1.8 m and one over 2.7-4.2 m, each turned
// `tilt` from it in opposite senses (within its support band): sloped glass and a roof's edge, not surfaces
// parallel to the footprint. Neither is the footprint's direction, and a fit through both lies between
// them: the face states the runs' tilt (informative_face.cpp, run_tilt_departure). Runs along the edge add
// nothing to the upper body's departure. A HDL-32E 6 m up saw a coupe 9 m away with four lasers over its
// roof, glass and bonnet, none on its doors: the face through them was 15 deg off stating 2.7 deg (a third
// pilot matrix, kept out of the repository).
TEST(InformativeFace, UpperBodyRunsTiltedFromTheFaceStateTheirTilt) {
  const std::vector<double> elevations = {laser_through(1.05), laser_through(3.45)};
  const auto runs = [](double tilt) {
    std::vector<MastTrace> trace;
    for (double s = 0.3; s <= 1.8 + 1e-9; s += 0.05)
      trace.push_back({0, {s, std::tan(tilt) * (s - 1.05)}});
    for (double s = 2.7; s <= 4.2 + 1e-9; s += 0.05)
      trace.push_back({1, {s, -std::tan(tilt) * (s - 3.45)}});
    return trace;
  };
  EXPECT_DOUBLE_EQ(mast_face(runs(0.0), elevations).departure_m, CorrectionConfig{}.upper_face_tilt_m);
  // The footprint may run along either: an error of the tilt is a 1-sigma one (with the upper body's fixed
  // departure alone the face stated 3.3 and 4.3 deg).
  for (const double tilt_deg : {4.0, 8.0}) {
    const double sigma = yaw_sigma_of(mast_face(runs(deg_to_rad(tilt_deg)), elevations));
    EXPECT_GE(sigma, 0.9 * deg_to_rad(tilt_deg)) << tilt_deg;
    EXPECT_LE(sigma, deg_to_rad(2.0 * tilt_deg)) << tilt_deg;
  }
}

// One laser's trace crossing the edge above the bonnet five times, with one or two returns in its support
// band each time: where it crosses, not a surface along it; the face holds no direction from them (their
// ranges spread: without the rule they were its informative points). Two lasers' traces along the edge
// are its points. A HDL-32E 4.5 m up saw a coupe 40 m away with one laser along its side and across its
// windscreen's foot; the fitted face held its returns where the trace crossed it, 26 deg off stating 5 deg
// (a third pilot matrix).
TEST(InformativeFace, TracesCrossingTheFaceAreNotOnIt) {
  std::vector<MastTrace> crossing;
  for (const double s : {0.6, 1.3, 2.0, 2.7, 3.4}) {
    for (double n = -0.65; n <= 0.65; n += 0.25)  // in the band (0.15 m) at -0.15 and 0.1
      crossing.push_back({0, {s + 0.3 * n, n}});
  }
  EXPECT_EQ(mast_face(crossing, {laser_through(2.0)}).points, 0U);
  std::vector<MastTrace> along;  // two lasers' (one alone states its depression: the single-trace rule)
  for (double s = 0.5; s <= 4.0 + 1e-9; s += 0.1)
    along.push_back({s < 2.25 ? 0U : 1U, {s, 0.02 * std::sin(7.0 * s)}});
  const FaceEvidence face = mast_face(along, {laser_through(1.4), laser_through(3.1)});
  EXPECT_EQ(face.points, along.size());
  EXPECT_DOUBLE_EQ(face.departure_m, CorrectionConfig{}.upper_face_tilt_m);
}

CorrectedPose correct_scan(const TrueBox& box, const Eigen::Vector2d& lidar, double step_deg,
                           std::uint64_t seed, const CorrectionConfig& config = {}) {
  std::mt19937_64 rng(seed);
  const auto pts = test::scan_box(box, lidar, deg_to_rad(step_deg), 0.02, rng);
  const RectangleFit fit = fit_rectangle(pts, lidar);
  EXPECT_TRUE(fit.ok());
  return test::correct_flat(fit, pts, {box.length, box.width}, lidar, std::nullopt, config);
}

TEST(FixCovariance, EndToEndFewerPointsFartherAndOneFaceAreLessCertain) {
  const TrueBox box{{0.0, 0.0}, 0.2, 4.89, 1.92};
  const Eigen::Vector2d diagonal = -(box.u() * std::cos(0.6) + box.v() * std::sin(0.6));  // sees an L

  const CorrectedPose near_dense = correct_scan(box, 12.0 * diagonal, 0.1, 1);
  const CorrectedPose near_sparse = correct_scan(box, 12.0 * diagonal, 0.6, 1);
  const CorrectedPose far_dense = correct_scan(box, 35.0 * diagonal, 0.1, 1);
  for (const auto* r : {&near_dense, &near_sparse, &far_dense})
    ASSERT_TRUE(r->ok());

  EXPECT_GT(near_sparse.covariance.trace(), near_dense.covariance.trace());
  EXPECT_GT(near_sparse.covariance(2, 2), near_dense.covariance(2, 2));
  EXPECT_GT(far_dense.covariance(0, 0) + far_dense.covariance(1, 1),
            near_dense.covariance(0, 0) + near_dense.covariance(1, 1));
  // The faces are seen more obliquely from near than from far on the same diagonal (the grazing term of
  // the yaw); with that term off, the noise alone makes the far fix's yaw less certain.
  CorrectionConfig no_grazing;
  no_grazing.covariance.min_incidence_sin = 1.0;
  EXPECT_GT(correct_scan(box, 35.0 * diagonal, 0.1, 1, no_grazing).covariance(2, 2),
            correct_scan(box, 12.0 * diagonal, 0.1, 1, no_grazing).covariance(2, 2));

  // From straight ahead only the front shows: less certain across the car (along the front face).
  const CorrectedPose front = correct_scan(box, 12.0 * box.u(), 0.1, 1);
  ASSERT_TRUE(front.ok());
  EXPECT_GT(variance_along(front.covariance, box.v()), variance_along(near_dense.covariance, box.v()));
  EXPECT_GT(front.covariance(2, 2), near_dense.covariance(2, 2));
  // ... and its uncertainty is larger across the car than along it.
  EXPECT_GT(variance_along(front.covariance, box.v()), variance_along(front.covariance, box.u()));
}

// One laser's trace (16.7 deg down from 8 m up, seen from (-10, -15)) along a fitted edge on y = 0 from x =
// 0.2 to x_end, every 0.1 m, its returns above `step_height` `step` farther inside the box (+y).
std::vector<Eigen::Vector3d> side_trace(double x_end, double step_height, double step) {
  std::vector<Eigen::Vector3d> points;
  for (double x = 0.2; x <= x_end + 1e-9; x += 0.1) {
    const double z = 8.0 - 0.3 * std::hypot(x + 10.0, 15.0);
    points.emplace_back(x, z > step_height ? step : 0.0, z);
  }
  return points;
}

// A side's returns above the bonnet (1.0 m) count as the lower body up to its height (here 1.76 m) where
// they lie on one vertical surface, and not where the upper half of them steps in (glass above a belt
// line), nor on an edge that may be an end, nor on a vehicle whose lower body ends below the bonnet.
TEST(FaceLowerHeight, ASideUpToTheLowerBodyWhereItsReturnsLieOnOneSurface) {
  const CorrectionConfig config;
  const VehicleSize size{7.0, 2.4, 3.2};
  LidarGeometry lidar;
  lidar.position = Eigen::Vector3d(-10.0, -15.0, 8.0);
  const auto box_fit = [](double length) {
    RectangleFit fit;
    fit.status = FitStatus::ok;
    fit.corners = {Eigen::Vector2d(0.0, 0.0), Eigen::Vector2d(length, 0.0), Eigen::Vector2d(length, 2.4),
                   Eigen::Vector2d(0.0, 2.4)};
    fit.edges[0].seen = true;
    return fit;
  };
  const RectangleFit side = box_fit(7.0);
  // The trace's heights: 2.56 m at x = 0.2, 1.24 m at 6.8; those up to 1.76 m span x = 4.3-6.8.
  const std::vector<Eigen::Vector3d> flat = side_trace(6.8, 9.0, 0.0);
  EXPECT_NEAR(flat.front().z(), 2.56, 0.01);
  EXPECT_NEAR(flat.back().z(), 1.24, 0.01);
  EXPECT_EQ(face_lower_height(flat, lidar, config, 1.0, 1.76, side, 0, size), 1.76);
  // Glass 5 cm in above 1.5 m: a step; 2 cm (the simulator's box body's cab): none.
  EXPECT_EQ(face_lower_height(side_trace(6.8, 1.5, 0.05), lidar, config, 1.0, 1.76, side, 0, size), 1.0);
  EXPECT_EQ(face_lower_height(side_trace(6.8, 1.5, -0.05), lidar, config, 1.0, 1.76, side, 0, size), 1.0);
  EXPECT_EQ(face_lower_height(side_trace(6.8, 1.5, 0.02), lidar, config, 1.0, 1.76, side, 0, size), 1.76);
  // An edge no longer than the width + half the length's excess (2.4 + 2.3 m) may be an end.
  const std::vector<Eigen::Vector3d> short_trace = side_trace(4.6, 9.0, 0.0);
  EXPECT_EQ(face_lower_height(short_trace, lidar, config, 1.0, 1.76, box_fit(4.6), 0, size), 1.0);
  // A lower body ending below the bonnet; too few returns up to it (a trace ending at x = 4.6: 1.79 m).
  EXPECT_EQ(face_lower_height(flat, lidar, config, 1.0, 0.9, side, 0, size), 1.0);
  EXPECT_EQ(face_lower_height(short_trace, lidar, config, 1.0, 1.76, side, 0, size), 1.0);
}

}  // namespace
}  // namespace rsu::perception
