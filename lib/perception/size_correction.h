// Size correction (paper Sec. 3.2): the connected vehicle announces its footprint size; the RSU aligns
// a box of that size with the fitted rectangle and reports the box's centre and yaw.
//
//  - correct_algorithm1: Algorithm 1 exactly as the paper writes it. P = the fitted corner nearest the
//    LiDAR (the "alignment point"), Pl, Pr its neighbours, L, R the unit vectors to them; the shorter
//    fitted edge takes the vehicle's width and the longer its length (the paper's <width, height> is the
//    footprint's width and length). Off by 90 deg when the LiDAR saw only the front or back (then the
//    fitted box's longer edge is the vehicle's width).
//  - correct_improved: decides which fitted edge is the length (a) by the vehicle's own yaw prior, when
//    it is decisive, else (b) by building the known-size box for both assignments (and, where the
//    position along an axis is not fixed by a seen face, anchored at either end) and keeping the box
//    most consistent with the points: no points outside it, and its faces that face the LiDAR covered by
//    points (a face the LiDAR should have seen but did not speaks against the box). Along each axis the
//    centre comes from the seen face perpendicular to it (its median position, + half the known size),
//    or, when the points span the whole known size without such a face, from the middle of their extent.
//    Before that, the fit's orientation is refined by least squares on the seen faces (face_refinement.h).
//
// Yaw is the direction of the length axis. A box has no front: without a prior, yaw is reported mod pi in
// (-pi/2, pi/2]; with a prior, the one of yaw and yaw + pi nearer the prior (heading_from_prior = true).
#pragma once

#include <optional>
#include <span>
#include <string_view>

#include <Eigen/Core>

#include "common/pose.h"
#include "perception/face_refinement.h"
#include "perception/fix_covariance.h"
#include "perception/l_shape_fitting.h"
#include "perception/rectangle_fit.h"

namespace rsu::perception {

// The vehicle's box as it announces it (proto/v2i.proto VehicleAnnouncement): footprint length and
// width, and height above the ground. Defaults: the Lexus RX450h of the paper's experiments.
struct VehicleSize {
  double length = 4.89;
  double width = 1.92;
  double height = 1.70;
};

// The vehicle's own yaw estimate (map frame, counter-clockwise from +x) and its standard deviation.
struct YawPrior {
  double yaw = 0.0;
  double sigma = deg_to_rad(10.0);
};

enum class CorrectionStatus {
  ok,
  no_fit,         // the rectangle fit failed (see its status)
  invalid_size,   // size not finite and positive
  invalid_input,  // LiDAR position or prior not finite
  // (improved correction) the best known-size box leaves too many points outside it: the points are
  // not this vehicle seen whole (a fragment beside another object, two objects, a wrong size); or
  // its yaw contradicts a confident yaw prior
  inconsistent_box,
  // (improved correction) boxes of the chosen assignment metres apart fit the points about equally
  // well (e.g. an occlusion edge that may or may not be the vehicle's side): no fix
  ambiguous_position,
};

enum class AmbiguityResolution {
  edge_lengths,  // Algorithm 1: the longer fitted edge is the length
  prior,         // the vehicle's yaw prior was decisive
  geometry,      // the point-consistency test was decisive
  unresolved,    // neither was; the more consistent assignment is reported with its low confidence
};

std::string_view to_string(CorrectionStatus status);
std::string_view to_string(AmbiguityResolution resolution);

struct CorrectedPose {
  CorrectionStatus status = CorrectionStatus::no_fit;
  Pose2 pose;                                            // footprint centre; yaw of the length axis
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();  // (x, y, yaw), see fix_covariance.h
  AmbiguityResolution resolution = AmbiguityResolution::unresolved;
  double confidence = 0.0;  // probability the length/width assignment is right; 1 for Algorithm 1
  bool heading_from_prior = false;
  Eigen::Vector2d alignment_point = Eigen::Vector2d::Zero();  // the point the box was anchored at

  bool ok() const { return status == CorrectionStatus::ok; }
};

struct CorrectionConfig {
  double outside_tolerance_m = 0.15;   // a point farther outside a hypothesis box than this counts against it
  double cover_radius_m = 0.15;        // a point covers a face within this (at least the point spacing)
  double face_bin_m = 0.1;             // faces are checked for coverage in bins of this length
  double min_incidence_cos = 0.1;      // faces seen more obliquely than ~84 deg are not expected to show
  double full_face_tolerance_m = 0.3;  // points spanning the known size within this: both ends seen
  double geometry_scale = 0.05;        // score difference per unit of log-odds between the assignments
  double min_confidence = 0.9;         // resolved only above this; a prior this decisive is trusted
  bool refine_on_faces = true;         // re-fit the orientation to the seen faces first (face_refinement.h)
  // The chosen known-size box must hold the points: more than max_outside_fraction of them farther
  // outside it than inconsistent_outside_m (well beyond range noise and the box's rounded corners)
  // rejects the fix (CorrectionStatus::inconsistent_box) instead of reporting a confident wrong pose.
  double inconsistent_outside_m = 0.3;
  double max_outside_fraction = 0.1;
  // ... and (with strict_consistency_checks, below) with a yaw prior, its yaw must agree with the prior
  // within this many combined sigmas (never tighter than the angle below: the prior may be somewhat
  // overconfident).
  double max_prior_disagreement_sigmas = 4.0;
  double min_prior_disagreement_rad = deg_to_rad(5.0);
  // Where a seen face anchors an axis, boxes anchored at the ends of the points instead (the face may
  // be an occlusion edge or the cabin) are alternatives when farther than position_ambiguity_min_m from
  // the chosen box: one more likely than max_position_ambiguity (same log-odds scale as the
  // assignment, geometry_scale) refuses the fix, less likely
  // ones add their spread to the covariance.
  // On: a far, fragmented vehicle's one-fragment "faces" gave confident fixes a metre off. (Before the
  // pilot and rsud shared one fix function, the pilot measured without these checks.)
  bool strict_consistency_checks = true;
  double position_ambiguity_min_m = 0.2;
  double max_position_ambiguity = 0.1;
  LShapeFitConfig fit;  // face support and 'seen' rules (the pipeline passes its own)
  FaceRefinementConfig refinement;
  CovarianceModelConfig covariance;
};

CorrectedPose correct_algorithm1(const RectangleFit& fit, const VehicleSize& size,
                                 const Eigen::Vector2d& lidar_xy,
                                 const CovarianceModelConfig& covariance = {});

// cluster_xy: the cluster's footprint points (the ones the fit was made from); non-finite ones ignored.
CorrectedPose correct_improved(const RectangleFit& fit, std::span<const Eigen::Vector2d> cluster_xy,
                               const VehicleSize& size, const Eigen::Vector2d& lidar_xy,
                               const std::optional<YawPrior>& prior, const CorrectionConfig& config = {});

}  // namespace rsu::perception
