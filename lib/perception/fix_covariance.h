// SPDX-License-Identifier: Apache-2.0
// The covariance of a size-corrected fix (x, y, yaw), from what the LiDAR saw (docs/design.md §3: every
// estimate carries its uncertainty).
//
// Model. Per-point noise across a face: sigma_n^2 = sigma_range^2 + (R sigma_angle)^2 at range R; the
// vehicle's departure from a box (bumpers, mirrors, rounded corners) adds sigma_shape, which does not
// average out over points. Point spacing along a face is s = R * azimuth resolution.
//  - Yaw: each seen face with n points over length l constrains the direction like a line fit,
//    information n l^2 / (12 sigma_n^2) (slope variance of least squares with evenly spread points),
//    limited by the body's departure from a plane, which does not average out: it tilts the face's
//    direction by about 2 tilt / l, so a face's direction variance is 12 sigma_n^2 / (n l^2) +
//    4 tilt^2 / l^2; faces add information. Plus the search's quantisation (step^2 / 12). No face seen:
//    max_yaw_sigma. A yaw fused with the vehicle's own estimate adds that estimate's information. The tilt is
//    face_tilt_sigma (a car's usual departure seen head-on) combined with the departure measured on this face
//    (the points' robust spread about their line beyond what sigma_n explains: a cabin seen by one ring, a
//    roof edge), and grows as 1 / sin(incidence) (capped at min_incidence_sin): at grazing incidence the
//    bulges nearest the LiDAR (mirrors, wheel arches, a rounded bumper) hide the rest of the face and make
//    its visible outline. Why: with a fixed 3 cm departure whatever the view, 1.8 % of a VLP-16's fixes over
//    the pilot's 6-36 m were beyond 3 stated sigma in yaw (the handover: 3.7 deg off at 21 m while stating
//    0.78 deg); with these terms 0.5 %, at a mean stated sigma 10 % larger
//    (tests/eval/fix_consistency_test.cpp; `rsu-pilot` prints the figures).
//  - Position along each box axis, by how the centre coordinate on that axis was found:
//      face      (a seen face perpendicular to the axis + half the known size): sigma_n^2 / n + shape^2;
//      midpoint  (both ends of a face seen whole, no perpendicular face): each end lies inside the true
//                end by U(0, s), so the midpoint errs by their half difference: s^2 / 24 + sigma_n^2 / 2
//                + shape^2;
//      one end   (only one, resolution-limited end): E[U(0,s)^2] = s^2 / 3, + sigma_n^2 + shape^2;
//      interval  (the points leave the centre anywhere in an interval of width w, box_axis.h): a uniform
//                error over it, w^2 / 12, + sigma_n^2 + shape^2 (its ends are then 1.7 sigma away).
//    So one seen face gives the larger variance along that face (the unseen direction's position comes
//    from face ends), fewer points and longer range give larger variances.
//  - The centre is anchor + R(yaw) * offset, so a yaw error moves it by yaw_error x lever; this adds
//    var_yaw * J J^T with J = d(centre)/d(yaw) = (-lever_y, lever_x), and the x-yaw covariance; and,
//    as the centre is itself uncertain along each axis, var_yaw times that variance across it.
//    Where the box was placed again at yaw +- a probe (yaw_probe_shift), J is measured too: the centre's
//    shift per radian at each probe, var_yaw * (J+ J+^T + J- J-^T) / 2 (their mean is the x-yaw
//    covariance), used where it says more than the lever (its trace the larger). One anchor point is not
//    where a placement's evidence lies when it is bounded by several points (containment by the far end, a
//    side seen at the near end): with the prior's yaw (10 deg) such fixes were 0.3-0.6 m off while their
//    lever carried a few cm (`rsu-pilot matrix`, a bus 6-8 m below a VLP-16); and a placement whose anchor
//    changes within the yaw's uncertainty (a face no longer seen as one) shows that as a large shift.
//  - A length/width assignment that is right only with probability c: the fix is the chosen hypothesis,
//    the other is (1 - c) likely, so (1 - c) d d^T is added (d = other centre - chosen centre) and
//    (1 - c) (pi/2)^2 to the yaw variance (the mean square error about the reported fix).
#pragma once

#include <array>
#include <cstddef>

#include <Eigen/Core>

#include "common/angles.h"
#include "perception/rectangle_fit.h"

namespace rsu::perception {

struct CovarianceModelConfig {
  double range_sigma_m = 0.02;     // docs/design.md §2 (simulator default)
  double angle_sigma_rad = 0.001;  // docs/design.md §2
  double shape_sigma_m = 0.03;     // vehicle vs box
  // The azimuth spacing of the points along a laser's trace: the LiDAR's step (VLP at 600 rpm: docs/design.md
  // §2), k steps where fix_vehicle thinned the cluster to every k-th column (azimuth_thinning.h).
  double azimuth_resolution_rad = deg_to_rad(0.2);
  double search_resolution_rad = deg_to_rad(0.02);  // the orientation search's final step
  double max_yaw_sigma_rad = 0.5;
  // The body's departure from a plane that tilts a face's fitted direction, seen head-on (smaller than
  // shape_sigma_m: much of a car's departure is symmetric along the face and does not tilt it), and the
  // cap of its growth at grazing incidence (at most 10x).
  double face_tilt_sigma_m = 0.02;
  double min_incidence_sin = 0.1;
};

enum class AxisAnchor { face, midpoint, one_end, interval };

struct AxisEvidence {
  AxisAnchor anchor = AxisAnchor::one_end;
  std::size_t face_points = 0;  // points of the anchoring face (anchor == face)
  // face: the standard error of the face's position when estimated from its points (face_envelope.h);
  // negative: from the point noise and face_points.
  double envelope_sigma_m = -1.0;
  // interval: the width of the interval the centre lies in (box_axis.h); midpoint: how far the two ends'
  // span falls short of (or beyond) the known size, over which the centre may lie (one end cut, not both)
  double interval_m = 0.0;
};

struct FaceEvidence {
  std::size_t points = 0;
  double length_m = 0.0;
  // Sine of the angle between the LiDAR's line of sight (to the face's midpoint) and the face: 1 when
  // the face is seen head-on, near 0 at grazing incidence.
  double incidence_sin = 1.0;
  // Robust spread (1.4826 MAD) of the face's points about their line, when measured (0: not measured).
  double residual_spread_m = 0.0;
  // A known departure of the surface the face was seen on from the footprint's direction (the upper
  // body's sloped glass and tumblehome), combined with the tilt terms (0: a lower-body face).
  double departure_m = 0.0;
};

struct FixEvidence {
  double range_m = 0.0;                             // LiDAR to the fix
  double yaw = 0.0;                                 // direction of the length axis
  Eigen::Vector2d lever = Eigen::Vector2d::Zero();  // centre - anchor point, map frame
  AxisEvidence length_axis;                         // centre coordinate along the length axis
  AxisEvidence width_axis;                          // and along the width axis
  std::array<FaceEvidence, 2> seen_faces{};         // unused entries have points = 0
  // How far the faces' direction moved when they were refit again on the refit's support bands
  // (face_refinement.h, refit_unsettled_rad): a direction the faces do not settle on is known no better.
  double faces_unsettled_rad = 0.0;
  double assignment_confidence = 1.0;
  Eigen::Vector2d alternative_offset = Eigen::Vector2d::Zero();  // other assignment's centre - centre
  // 1 / sigma^2 of the vehicle's own yaw estimate when the fix's yaw was fused with it (0: not used).
  double prior_yaw_information = 0.0;
  // The centre's shift when the box is placed again at yaw + yaw_probe_rad[i] (map; a probe of 0: not
  // placed, the lever stands for it).
  std::array<Eigen::Vector2d, 2> yaw_probe_shift{Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero()};
  std::array<double, 2> yaw_probe_rad{};
};

// Information (1 / variance, rad^-2) the seen faces give about the yaw (no prior, no quantisation).
double face_yaw_information(const FixEvidence& evidence, const CovarianceModelConfig& config = {});

// Variance of a point's position across a surface at horizontal range range_m (range and angle noise); a
// negative range counts as 0, an unknown (non-finite) one gives an infinite variance.
double point_noise_variance(double range_m, const CovarianceModelConfig& config);

// The evidence of fitted edge `edge` (0..3) of `fit` as seen from the LiDAR at lidar_xy.
FaceEvidence face_evidence(const RectangleFit& fit, std::size_t edge, const Eigen::Vector2d& lidar_xy);

Eigen::Matrix3d fix_covariance(const FixEvidence& evidence, const CovarianceModelConfig& config = {});

}  // namespace rsu::perception
