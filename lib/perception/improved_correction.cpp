// SPDX-License-Identifier: Apache-2.0
// The improved size correction (size_correction.h): which faces tell the yaw, the yaw fused with the
// vehicle's own, the length/width assignment, and the box placed along each axis (box_axis.h).
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <vector>

#include <Eigen/Core>

#include "perception/box_axis.h"
#include "perception/box_consistency.h"
#include "perception/face_envelope.h"
#include "perception/face_refinement.h"
#include "perception/informative_face.h"
#include "perception/lidar_geometry.h"
#include "perception/size_correction.h"

namespace rsu::perception {
namespace {

constexpr double kPi = std::numbers::pi;

double fold_half_turn(double a) {
  a = std::remainder(a, kPi);
  return a <= -kPi / 2.0 ? a + kPi : a;
}

double logistic(double x) {
  return 1.0 / (1.0 + std::exp(-std::clamp(x, -50.0, 50.0)));
}

struct Frame {
  Eigen::Vector2d origin;
  Eigen::Vector2d e0;
  Eigen::Vector2d e1;
  Eigen::Vector2d local(const Eigen::Vector2d& p) const {
    return {(p - origin).dot(e0), (p - origin).dot(e1)};
  }
  Eigen::Vector2d map(const Eigen::Vector2d& c) const { return origin + c.x() * e0 + c.y() * e1; }
};

Frame frame_at(const Eigen::Vector2d& origin, double yaw) {
  return {origin, {std::cos(yaw), std::sin(yaw)}, {-std::sin(yaw), std::cos(yaw)}};
}

// What the correction knows about the vehicle and the view, shared by its steps.
struct View {
  std::span<const Eigen::Vector3d> points;
  const LidarGeometry& lidar;
  const CorrectionConfig& config;
  double lower_height = 0.0;  // above the road: the lower body
  double side_height = 0.0;   // ... the sides where the lower body makes no face (BoxPoint::side_body)
  double end_height = 0.0;    // ... and the footprint's ends (BoxPoint::end_body)
  double vehicle_height = 0.0;
  double noise_sigma = 0.0;
  // The points as BoxPoints without their place in a frame (what does not depend on it), and the faces'
  // envelopes estimated so far: the box is placed in several frames (box_axis.h).
  std::vector<BoxPoint> body = {};
  std::vector<std::size_t> ranks = {};  // the points' lasers (LaserLookup::ranks), for the faces' evidence
  FaceEnvelopeMemo* envelopes = nullptr;

  std::vector<BoxPoint> in_frame(const Frame& f) const {
    std::vector<BoxPoint> out = body;
    for (std::size_t i = 0; i < out.size(); ++i)
      out[i].local = f.local(points[i].head<2>());
    return out;
  }
};

struct Placement {
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();  // local
  // The point the evidence of both axes lies at (local): axis 1's evidence's place along axis 0, axis 0's
  // along axis 1.
  Eigen::Vector2d anchor = Eigen::Vector2d::Zero();
  std::array<AxisEvidence, 2> evidence{};
  bool contained = true;
};

Placement place_box(const View& view, const Frame& frame, const std::vector<BoxPoint>& points,
                    const Eigen::Vector2d& dims, int length_axis, double yaw_sigma) {
  AxisContext ctx;
  ctx.points = points;
  ctx.lidar_local = frame.local(view.lidar.xy());
  ctx.origin = frame.origin;
  ctx.e0 = frame.e0;
  ctx.e1 = frame.e1;
  ctx.dims = dims;
  ctx.length_axis = length_axis;
  ctx.vehicle_height = view.vehicle_height;
  ctx.end_height = view.end_height;
  ctx.noise_sigma = view.noise_sigma;
  ctx.yaw_sigma = yaw_sigma;
  ctx.envelopes = view.envelopes;
  Placement out;
  const std::array<AxisEstimate, 2> axes = estimate_axes(ctx, view.lidar, view.config);
  for (int a = 0; a < 2; ++a) {
    const AxisEstimate& e = axes[static_cast<std::size_t>(a)];
    out.centre[a] = e.centre;
    out.anchor[1 - a] = e.across;  // the point a yaw error turns the box about (fix_covariance.h lever)
    out.evidence[static_cast<std::size_t>(a)] = e.evidence;
    out.contained = out.contained && e.contained;
  }
  return out;
}

// Information of the vehicle's yaw prior, its sigma no smaller than the correction trusts a vehicle's.
double prior_information(const YawPrior& prior, const CorrectionConfig& config) {
  const double sigma = std::max(prior.sigma, config.min_prior_sigma_rad);
  return 1.0 / (sigma * sigma);
}

struct YawDecision {
  double yaw = 0.0;
  double confidence = 1.0;
  AmbiguityResolution resolution = AmbiguityResolution::prior;
  double prior_information = 0.0;
  double prior_share = 0.0;
  Eigen::Vector2d alternative_offset = Eigen::Vector2d::Zero();  // map
  bool contradicts_prior = false;
  // The faces' yaw lies farther from the vehicle's own than both their uncertainties allow
  // (CorrectionConfig::prior_fallback_sigmas): the face fit is wrong; the box goes along the vehicle's own.
  bool faces_inconsistent = false;
};

// Which fitted axis is the length (the prior when decisive, else the box more consistent with the points),
// and the faces' yaw fused with the prior by information.
YawDecision decide_yaw(const View& view, const RectangleFit& fit, const VehicleSize& size,
                       double face_information, std::span<const Eigen::Vector2d> outline,
                       const std::optional<YawPrior>& prior) {
  const CorrectionConfig& config = view.config;
  const Frame frame{fit.center, fit.axis0(), fit.axis1()};
  const std::vector<BoxPoint> points = view.in_frame(frame);
  std::vector<Eigen::Vector2d> outline_local;
  outline_local.reserve(outline.size());
  for (const auto& p : outline) {
    if (p.allFinite())
      outline_local.push_back(frame.local(p));
  }
  const Eigen::Vector2d lidar_local = frame.local(view.lidar.xy());
  // At least the points' spacing along a laser's trace (the covariance's azimuth resolution: the LiDAR's
  // step, times k where the fix was given every k-th column).
  const double cover_radius = std::max(config.cover_radius_m, (view.lidar.xy() - fit.center).norm() *
                                                                  config.covariance.azimuth_resolution_rad);
  std::array<Placement, 2> boxes;
  std::array<double, 2> score{};
  for (int j = 0; j < 2; ++j) {
    const Eigen::Vector2d dims =
        j == 0 ? Eigen::Vector2d(size.length, size.width) : Eigen::Vector2d(size.width, size.length);
    boxes[static_cast<std::size_t>(j)] =
        place_box(view, frame, points, dims, j, 1.0 / std::sqrt(face_information));
    score[static_cast<std::size_t>(j)] =
        box_inconsistency(outline_local, lidar_local, boxes[static_cast<std::size_t>(j)].centre, dims / 2.0,
                          cover_radius, config);
  }

  // Log-odds that the length lies along e0 rather than e1.
  const double geometry_log_odds = (score[1] - score[0]) / config.geometry_scale;
  double prior_log_odds = 0.0;
  if (prior) {
    // Angular distance (mod pi) of the prior from e0; e1 is pi/2 minus it.
    const double d0 = std::abs(fold_half_turn(prior->yaw - fit.yaw));
    const double d1 = kPi / 2.0 - d0;
    prior_log_odds = (d1 * d1 - d0 * d0) / (2.0 * prior->sigma * prior->sigma);
  }
  const bool prior_decisive = prior && logistic(std::abs(prior_log_odds)) >= config.min_confidence;
  const double log_odds = prior_decisive ? prior_log_odds : geometry_log_odds + prior_log_odds;
  int chosen = log_odds > 0.0 ? 0 : 1;
  if (log_odds == 0.0)  // a perfect tie: Algorithm 1's rule (the longer edge is the length)
    chosen = fit.length0 >= fit.length1 ? 0 : 1;

  YawDecision out;
  out.confidence = logistic(std::abs(log_odds));
  out.resolution = prior_decisive                            ? AmbiguityResolution::prior
                   : out.confidence >= config.min_confidence ? AmbiguityResolution::geometry
                                                             : AmbiguityResolution::unresolved;
  out.alternative_offset = frame.map(boxes[static_cast<std::size_t>(1 - chosen)].centre) -
                           frame.map(boxes[static_cast<std::size_t>(chosen)].centre);
  const double faces_yaw = fit.yaw + (chosen == 0 ? 0.0 : kPi / 2.0);
  out.yaw = faces_yaw;
  if (prior) {
    const double d = fold_half_turn(prior->yaw - faces_yaw);
    const double sigma = std::sqrt(prior->sigma * prior->sigma + 1.0 / face_information);
    out.contradicts_prior = std::abs(d) > std::max(config.max_prior_disagreement_sigmas * sigma,
                                                   config.min_prior_disagreement_rad);
    out.faces_inconsistent = std::abs(d) > config.prior_fallback_sigmas * sigma;
    // The vehicle's own heading steps in only where the faces' is weak (size_correction.h): a fix that
    // hands the vehicle its own estimate back, as if measured, would be counted twice by its filter.
    if (face_information < config.fuse_prior_below_information) {
      out.prior_information = prior_information(*prior, config);
      out.prior_share = out.prior_information / (out.prior_information + face_information);
      out.yaw = faces_yaw + out.prior_share * d;
    }
  }
  return out;
}

CorrectedPose refused(CorrectionStatus status) {
  CorrectedPose out;
  out.status = status;
  return out;
}

// Why the inputs cannot be corrected, or ok.
CorrectionStatus input_status(const RectangleFit& fit, const VehicleSize& size, const LidarGeometry& lidar,
                              const std::optional<YawPrior>& prior) {
  if (!fit.ok())
    return CorrectionStatus::no_fit;
  if (!valid_size(size))
    return CorrectionStatus::invalid_size;
  if (!lidar.position.allFinite() || !std::isfinite(lidar.ground_z) ||
      (prior && !(std::isfinite(prior->yaw) && std::isfinite(prior->sigma) && prior->sigma > 0.0)))
    return CorrectionStatus::invalid_input;
  return CorrectionStatus::ok;
}

std::vector<Eigen::Vector3d> finite_points(std::span<const Eigen::Vector3d> points) {
  std::vector<Eigen::Vector3d> finite;
  finite.reserve(points.size());
  for (const auto& p : points) {
    if (p.allFinite())
      finite.push_back(p);
  }
  return finite;
}

View view_of(std::span<const Eigen::Vector3d> finite, const RectangleFit& fit, const VehicleSize& size,
             const LidarGeometry& lidar, const CorrectionConfig& config, FaceEnvelopeMemo& envelopes) {
  const double range = (fit.center - lidar.xy()).norm();
  // Without a usable announced height every point counts as the lower body (the footprint's outline).
  const bool height_known = std::isfinite(size.height) && size.height > 0.0;
  View view{finite,
            lidar,
            config,
            lower_body_height(size, config),
            side_body_height(size, config),
            end_body_height(size, config),
            height_known ? size.height : 1e9,
            std::sqrt(point_noise_variance(range, config.covariance) +
                      config.covariance.face_tilt_sigma_m * config.covariance.face_tilt_sigma_m)};
  view.body.reserve(finite.size());
  for (const Eigen::Vector3d& p : finite) {
    const double height = p.z() - lidar.ground_z;
    view.body.push_back({Eigen::Vector2d::Zero(), height, height <= view.lower_height,
                         height <= view.side_height, height <= view.end_height,
                         (p.head<2>() - lidar.xy()).norm()});
  }
  view.ranks = LaserLookup(lidar.elevations_rad).ranks(finite, lidar.position);
  view.envelopes = &envelopes;
  return view;
}

// The yaw evidence: the (at most two) seen faces, each counting only its points on vertical surfaces of
// the body; the range is the fit's.
FixEvidence yaw_evidence(const View& view, const RectangleFit& fit, const VehicleSize& size) {
  FixEvidence evidence;
  evidence.range_m = (fit.center - view.lidar.xy()).norm();
  std::size_t f = 0;
  for (std::size_t i = 0; i < 4 && f < 2; ++i) {
    if (!fit.edges[i].seen)
      continue;
    const double lower = face_lower_height(view.points, view.lidar, view.config, view.end_height,
                                           view.lower_height, fit, i, size);
    evidence.seen_faces[f++] = informative_face(view.points, view.ranks, view.lidar, view.config, lower,
                                                view.noise_sigma, fit, i, size);
  }
  return evidence;
}

// The yaw the box is placed along: the faces' (decide_yaw), or the vehicle's own where nothing seen tells
// the direction; `refusal` says why there is none (ok when there is one).
struct ChosenYaw {
  YawDecision decision;
  CorrectionStatus refusal = CorrectionStatus::ok;
};

ChosenYaw choose_yaw(const View& view, const RectangleFit& fit, const VehicleSize& size,
                     double face_information, std::span<const Eigen::Vector2d> outline,
                     const std::optional<YawPrior>& prior) {
  ChosenYaw out;
  if (face_information > 0.0) {
    out.decision = decide_yaw(view, fit, size, face_information, outline, prior);
    if (out.decision.contradicts_prior && view.config.strict_consistency_checks) {
      out.refusal = CorrectionStatus::inconsistent_box;
    } else if (out.decision.faces_inconsistent) {
      // The faces contradict the vehicle's own heading: they are not the footprint's (a rounded corner,
      // a few points of different rings); its own, with its uncertainty, and none of theirs.
      out.decision.yaw = prior->yaw;
      out.decision.prior_information = prior_information(*prior, view.config);
      out.decision.prior_share = 1.0;
    }
  } else if (prior) {
    // Nothing seen tells the direction: the vehicle's own, with its uncertainty.
    out.decision.yaw = prior->yaw;
    out.decision.prior_information = prior_information(*prior, view.config);
    out.decision.prior_share = 1.0;
  } else {
    out.refusal = CorrectionStatus::yaw_unobserved;
  }
  return out;
}

// The known-size box along `frame` (axis 0 the length), or nothing when it does not hold the points.
std::optional<Placement> place_known_box(const View& view, const Frame& frame, const VehicleSize& size,
                                         double yaw_information) {
  const CorrectionConfig& config = view.config;
  const std::vector<BoxPoint> in_frame = view.in_frame(frame);
  const Placement box =
      place_box(view, frame, in_frame, {size.length, size.width}, 0, 1.0 / std::sqrt(yaw_information));
  std::vector<Eigen::Vector2d> local;
  local.reserve(in_frame.size());
  for (const BoxPoint& p : in_frame)
    local.push_back(p.local);
  if (!box.contained || outside_fraction(local, box.centre, {size.length / 2.0, size.width / 2.0},
                                         config.inconsistent_outside_m) > config.max_outside_fraction)
    return std::nullopt;
  return box;
}

// How the box's place depends on its yaw (fix_covariance.h): placed again at the yaw +- sqrt(3) of its
// sigma (a Gaussian's sigma points), or nearer (sigma, sigma / 2) where the box turned that far no longer
// holds the points; the farthest probe's shift of the centre goes into the evidence. The points are placed
// about the same origin, so only the yaw differs. An axis whose centre lies in an interval (box_axis.h)
// gets the widest of the intervals of every probe that holds the points: turned off the true heading, a
// long box's points spread across it and containment squeezes the interval (a bus 18 m from a VLP-16 8 m
// up, 8 deg off: 0.09 m wide, the centre 0.59 m off; 1.3 m wide at the true heading), and the probes
// beyond the true heading squeeze it too: a bus 9 m from a VLP-16 6 m up, the vehicle's heading 9.6 deg
// off, had 0.36 m at its yaw and 0.25 m at the one probe that held (17 deg the other way), 1.3 m at the
// true heading, which the sigma / 2 and sigma probes come near; the centre was 0.57 m off.
void probe_yaw(const View& view, const Frame& frame, const CorrectedPose& fix, const VehicleSize& size,
               double yaw_information, Placement& placed, FixEvidence& evidence) {
  constexpr double kMaxProbeRad = 0.5;
  const double yaw = std::atan2(frame.e0.y(), frame.e0.x());
  const double sigma = 1.0 / std::sqrt(std::max(yaw_information, 1e-12));
  const Eigen::Vector2d centre(fix.pose.x, fix.pose.y);
  // The nearer probes are placed only for an interval's width.
  const bool interval =
      placed.evidence[0].anchor == AxisAnchor::interval || placed.evidence[1].anchor == AxisAnchor::interval;
  for (std::size_t i = 0; i < 2; ++i) {
    for (const double sigmas : {std::sqrt(3.0), 1.0, 0.5}) {
      if (evidence.yaw_probe_rad[i] != 0.0 && !interval)
        break;
      const double step = (i == 0 ? 1.0 : -1.0) * std::min(sigmas * sigma, kMaxProbeRad);
      const Frame turned = frame_at(frame.origin, yaw + step);
      const std::optional<Placement> box = place_known_box(view, turned, size, yaw_information);
      if (!box)
        continue;
      if (evidence.yaw_probe_rad[i] == 0.0) {
        evidence.yaw_probe_shift[i] = turned.map(box->centre) - centre;
        evidence.yaw_probe_rad[i] = step;
      }
      for (std::size_t a = 0; a < 2; ++a) {
        AxisEvidence& axis = placed.evidence[a];
        if (axis.anchor == AxisAnchor::interval && box->evidence[a].anchor == AxisAnchor::interval)
          axis.interval_m = std::max(axis.interval_m, box->evidence[a].interval_m);
      }
    }
  }
}

// The yaw as sent: the direction nearest the vehicle's own heading when it announced one, else folded
// to a half turn (the points alone cannot tell front from back).
double reported_yaw(double yaw, const std::optional<YawPrior>& prior) {
  if (!prior)
    return fold_half_turn(yaw);
  return angle_distance(yaw, prior->yaw) <= kPi / 2.0 ? wrap_angle(yaw) : wrap_angle(yaw + kPi);
}

CorrectedPose corrected_pose(const Frame& frame, const Placement& box, const YawDecision& yaw,
                             const std::optional<YawPrior>& prior) {
  CorrectedPose out;
  const Eigen::Vector2d centre = frame.map(box.centre);
  out.status = CorrectionStatus::ok;
  out.pose = {centre.x(), centre.y(), reported_yaw(yaw.yaw, prior)};
  out.heading_from_prior = prior.has_value();
  out.alignment_point = frame.map(box.anchor);
  out.resolution = yaw.resolution;
  out.confidence = yaw.confidence;
  out.yaw_prior_share = yaw.prior_share;
  return out;
}

// The fix's covariance (fix_covariance.h): the faces' evidence completed with what placing the box and
// deciding the yaw showed, at the point the box was anchored at.
Eigen::Matrix3d covariance_of(const CorrectedPose& fix, FixEvidence evidence, const Placement& box,
                              const YawDecision& yaw, const LidarGeometry& lidar,
                              const CorrectionConfig& config) {
  evidence.range_m = (fix.alignment_point - lidar.xy()).norm();
  evidence.yaw = fix.pose.yaw;
  evidence.lever = Eigen::Vector2d(fix.pose.x, fix.pose.y) - fix.alignment_point;
  evidence.length_axis = box.evidence[0];
  evidence.width_axis = box.evidence[1];
  evidence.assignment_confidence = yaw.confidence;
  evidence.alternative_offset = yaw.alternative_offset;
  evidence.prior_yaw_information = yaw.prior_information;
  return fix_covariance(evidence, config.covariance);
}

}  // namespace

CorrectedPose correct_improved(const RectangleFit& fit, std::span<const Eigen::Vector2d> outline,
                               std::span<const Eigen::Vector3d> points, const VehicleSize& size,
                               const LidarGeometry& lidar, const std::optional<YawPrior>& prior,
                               const CorrectionConfig& config) {
  if (const CorrectionStatus invalid = input_status(fit, size, lidar, prior); invalid != CorrectionStatus::ok)
    return refused(invalid);
  // The fitted rectangle re-fit to its seen faces (face_refinement.h).
  const RectangleFit refined =
      config.refine_on_faces ? refine_on_faces(fit, outline, lidar.xy(), config.fit, config.refinement) : fit;
  const std::vector<Eigen::Vector3d> finite = finite_points(points);
  FaceEnvelopeMemo envelopes;
  const View view = view_of(finite, refined, size, lidar, config, envelopes);
  // Yaw: what the seen faces tell, the length/width assignment, the vehicle's own heading where they
  // tell little.
  FixEvidence evidence = yaw_evidence(view, refined, size);
  if (config.refine_on_faces)
    evidence.faces_unsettled_rad =
        refit_unsettled_rad(refined, outline, lidar.xy(), config.fit, config.refinement);
  const double face_information = face_yaw_information(evidence, config.covariance);
  const ChosenYaw yaw = choose_yaw(view, refined, size, face_information, outline, prior);
  if (yaw.refusal != CorrectionStatus::ok)
    return refused(yaw.refusal);
  // The faces' evidence, unless they were found to contradict the vehicle's own heading.
  FixEvidence yaw_basis = evidence;
  if (yaw.decision.faces_inconsistent)
    yaw_basis.seen_faces = {};
  const double yaw_information =
      (yaw.decision.faces_inconsistent ? 0.0 : face_information) + yaw.decision.prior_information;
  // The known-size box along the final axes, placed axis by axis (box_axis.h).
  const Frame frame = frame_at(refined.center, yaw.decision.yaw);
  std::optional<Placement> box = place_known_box(view, frame, size, yaw_information);
  if (!box)
    return refused(CorrectionStatus::inconsistent_box);
  // The fix and how far it can be trusted.
  CorrectedPose out = corrected_pose(frame, *box, yaw.decision, prior);
  probe_yaw(view, frame, out, size, yaw_information, *box, yaw_basis);
  out.covariance = covariance_of(out, yaw_basis, *box, yaw.decision, lidar, config);
  out.length_axis = box->evidence[0];
  // Refused, with the pose and covariance it would have stated (position_sigma_m): how far from a fix
  // it was, and the interval its centre was confined to (length_axis).
  if (position_sigma_m(out) > max_position_sigma_m(lidar.complete_sweep, config))
    out.status = CorrectionStatus::position_unbounded;
  return out;
}

}  // namespace rsu::perception
