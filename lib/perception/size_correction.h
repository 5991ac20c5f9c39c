// SPDX-License-Identifier: Apache-2.0
// Size correction (paper Sec. 3.2): the connected vehicle announces its footprint size; the RSU aligns
// a box of that size with the fitted rectangle and reports the box's centre and yaw.
//
//  - correct_algorithm1: Algorithm 1 exactly as the paper writes it. P = the fitted corner nearest the
//    LiDAR (the "alignment point"), Pl, Pr its neighbours, L, R the unit vectors to them; the shorter
//    fitted edge takes the vehicle's width and the longer its length (the paper's <width, height> is the
//    footprint's width and length). Off by 90 deg when the LiDAR saw only the front or back (then the
//    fitted box's longer edge is the vehicle's width).
//  - correct_improved: the box of the announced size placed by what the points and the LiDAR's view
//    decide (issue 12: from 2 m to 8 m mounts, small car to bus):
//    * Which part of the body a point is on, from its height: below lower_body_fraction of the announced
//      height it is on the lower body, whose outline is the footprint (doors, bumpers); above it may be
//      the glasshouse or roof, narrower and shorter than the footprint. The rectangle is fitted to the
//      lower body's points where there are enough.
//    * Yaw: a seen face tells the vehicle's direction only if it is a vertical surface of the body: below
//      the bonnet (max_end_body_height_m; a van's bonnet top lies within its lower body), or spanning
//      several heights. A single laser's trace across a roof or a bonnet is
//      a line too (across the line of sight, whatever the car's heading) and tells nothing. The faces'
//      yaw is fused with the vehicle's own (announced, predicted to the sweep) by their information;
//      with no informative face the yaw is the vehicle's own, with its uncertainty.
//    * Which fitted axis is the length: the yaw prior when decisive, else the box (of both assignments)
//      most consistent with the points (box_consistency.h).
//    * Position along each axis: a lower-body face's outer envelope (at the front and back: below the
//      bonnet) (face_envelope.h: the footprint's
//      edge is the outer envelope of the body's points, not their median), or the middle of both ends,
//      or the interval the points and the LiDAR's view leave (box_axis.h) with its spread in the
//      covariance. Before that, the fit's orientation is refined by least squares on the seen faces
//      (face_refinement.h).
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
#include "perception/lidar_geometry.h"
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
  // (improved correction) no seen face tells the vehicle's direction (only a roof, one laser's trace)
  // and the vehicle announced no heading
  yaw_unobserved,
  // (improved correction) the points leave the position open over more than max_position_sigma_m
  position_unbounded,
};

enum class AmbiguityResolution {
  edge_lengths,  // Algorithm 1: the longer fitted edge is the length
  prior,         // the vehicle's yaw prior was decisive
  geometry,      // the point-consistency test was decisive
  unresolved,    // neither was; the more consistent assignment is reported with its low confidence
};

std::string_view to_string(CorrectionStatus status);
// Length and width finite and positive (the height is not used by every correction).
bool valid_size(const VehicleSize& size);
std::string_view to_string(AmbiguityResolution resolution);

struct CorrectedPose {
  CorrectionStatus status = CorrectionStatus::no_fit;
  Pose2 pose;                                            // footprint centre; yaw of the length axis
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();  // (x, y, yaw), see fix_covariance.h
  AmbiguityResolution resolution = AmbiguityResolution::unresolved;
  double confidence = 0.0;  // probability the length/width assignment is right; 1 for Algorithm 1
  bool heading_from_prior = false;
  // Share of the yaw's information that is the vehicle's own announced heading (0: the RSU measured it;
  // 1: the points told nothing about it and the fix carries the vehicle's own yaw back).
  double yaw_prior_share = 0.0;
  Eigen::Vector2d alignment_point = Eigen::Vector2d::Zero();  // the point the box was anchored at
  // (improved correction) How the centre was placed along the length axis (box_axis.h): for an interval,
  // the centre is its middle and interval_m its width (the widest of the yaw probes'). Kept, with the
  // pose, for a fix refused as position_unbounded: what rsud's footprint track combines over rotations
  // (core/footprint_track.h).
  AxisEvidence length_axis;

  bool ok() const { return status == CorrectionStatus::ok; }
};

// The position sigma a fix states: the larger axis of its x, y covariance (m). Also kept for a fix
// refused as position_unbounded: what it would have stated (rsud tells the vehicle how far off it was).
double position_sigma_m(const CorrectedPose& fix);

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
  // Faces whose yaw lies farther than this many combined sigmas from the prior's (but within the above)
  // are taken for a wrong face fit: the box goes along the prior's yaw with its sigma, the faces' unused.
  double prior_fallback_sigmas = 3.0;
  // On: a far, fragmented vehicle's one-fragment "faces" gave confident fixes a metre off.
  bool strict_consistency_checks = true;
  // Which part of the body a point can be on (see above): below this share of the announced height the
  // footprint's outline (every road vehicle's lower half is its full plan: bumpers, doors, sills).
  double lower_body_fraction = 0.55;
  // ... but at the front and back only up to the bonnet: a van's belt line lies below half its height
  // (1.2 of 2.45 m) and above it the windscreen stands a bonnet's length back (0.7-0.8 m); points on it
  // taken for the footprint's end put the fix 0.6 m off while stating 0.1 m (`rsu-pilot matrix`: 94 of a
  // VLP-16's fixes of the van at 2 m beyond 35 m, 62 of a VLP-32C's at 6 m). Up to this height the ends
  // of every road vehicle are its footprint's (bumpers, a bus's or a lorry's flat front).
  double max_end_body_height_m = 1.0;
  // Up to this height (and the lower body) the plan is full on any road vehicle (bumpers and doors; a
  // bus's windows start at about a third of its height, above it); a face seen only higher up, but
  // within the lower body's share, may be set back by up to mid_height_inset_m or low_bonnet_inset_m
  // (below; box_axis.h).
  double full_plan_height_m = 0.9;
  // At the front and back of a vehicle taller than max_end_body_height_m / lower_body_fraction (1.82 m:
  // vans, buses, lorries, their bonnets at 1 m or above): a bus's windscreen above its low front.
  double mid_height_inset_m = 0.3;
  // ... of a lower one (cars, MPVs), whose bonnet may lie under 55 % of its height: the windscreen's base
  // behind it, up to the bonnet's length. 0.3 m left a kei car (bonnet 0.45 m long at 0.95 m, 53 % of its
  // 1.78 m) 0.32-0.35 m off stating 0.09 m, and an MPV (0.80 m at 0.92 m, 51 % of 1.80 m) 0.7 m off (HMI; a
  // fifth pilot matrix and an MPV of our own, README). 0.8 m moved none of the paper's pilot's cells (the
  // SUV's bonnet is at 1 m); for a van it would widen fixes whose ends are truly seen (its bonnet at 1.2 m).
  double low_bonnet_inset_m = 0.8;
  // ... and their bonnets may lie lower than full_plan_height_m: a minivan's at 0.86 m (49 % of its 1.76
  // m, README "A minivan's windscreen base"), whose windscreen's base, one laser's trace over the bonnet
  // seen from a mast, was taken for the front (0.8 m off stating 0.05-0.1 m: 109 HMI fixes over 9 pilot
  // cells). An end of such a vehicle seen lowest between this height and the full plan's (but within
  // its lower body) may be that base or the front itself (an SUV's bumper and grille up to 1 m, seen
  // there from 2 m up): the face stays where it is seen, its sigma grown by low_bonnet_inset_m / 3.
  // Placed in the middle of the two instead, the SUV's fixes moved (the VLP-16 2 m up: 97.9 -> 93.5 %
  // under 0.10 m); grown, they stay and are stated honestly. Nor is such an end's body seen to stop where a
  // laser's trace leaves it above this height (box_axis.cpp, observable_beyond): one trace along a minivan's
  // glasshouse at 0.95 m left it over the bonnet and was taken for the front, 0.8-1.0 m off (HMI).
  // Nor does one laser's arc at one range above this height tell the end's direction (informative_face.h):
  // across a minivan's bonnet at 0.82-0.89 m it was taken for the front's face, 17-18 deg off (HMI).
  // Its belt line may lie as low: a side seen lowest between this height and the full plan's may be the
  // glasshouse a window's inset inside the doors, and its sigma grows by mid_height_inset_width_m / 3
  // (box_axis.cpp; the minivan's glasshouse at 0.89 m taken for its doors: 0.43 m off, NEES 15-16, HMI);
  // and returns there tell the direction as the upper body's (informative_face.cpp).
  double min_bonnet_height_m = 0.8;
  // ... and such a face's lowest return may lie up the windscreen from its base, this much farther back per
  // metre of rise (a screen raked 27 deg from the horizontal): the minivan's front seen 0.87 m up, 0.81 m
  // behind the front, stated 3 sigma = 0.80 m before (HMI, two pilot cells).
  double windscreen_run_per_rise = 2.0;
  double mid_height_inset_width_m = 0.1;  // at the sides (windows nearly flush)
  double ground_clearance_m = 0.15;  // the lowest a vehicle's body comes (a laser below it sees the road)
  std::size_t min_lower_body_points = 6;  // the rectangle is fitted to the lower body from this many
  // A face of points above the lower body tells the yaw only if they span this much height (several
  // lasers on a vertical surface); one laser's trace on a roof does not.
  double min_vertical_spread_m = 0.15;
  // ... or if their horizontal ranges spread this much (not one laser's arc across a level surface);
  // such faces' direction departs from the footprint's by about upper_face_tilt_m over their length.
  double min_range_spread_m = 0.1;
  // The faces' yaw is fused with the vehicle's own only when they know it less well than this (rad^-2;
  // 1 / (3 deg)^2), and the vehicle's sigma is taken as at least min_prior_sigma_rad.
  double fuse_prior_below_information = 1.0 / (deg_to_rad(3.0) * deg_to_rad(3.0));
  double min_prior_sigma_rad = deg_to_rad(2.0);
  // A fix whose position sigma (larger axis) exceeds this is withheld (position_unbounded): the points
  // leave the vehicle's place open over metres (a few returns of a roof below a mast, a vehicle cut by
  // lost packets or a neighbour). rsud: perception.max_position_sigma_m. 1 m was measured (README "The
  // cap at 1 m, an operator's choice"): from a mast 4-8 m up it sends most of what 0.5 m withholds, none
  // beyond 3 sigma, but those fixes are coarse (a median 0.6 m off) and at 2 m they are the far head-on
  // views that take the corridor's VLP-32C from 0.04 to 0.20 m MAE within 50 m; so 0.5 m by default.
  double max_position_sigma_m = 0.5;
  double upper_face_tilt_m = 0.08;
  // A face whose informative points span less than this (an evenly spread face's length, fix_covariance.h,
  // or from first to last where that is shorter: a few bunched at both ends of a short run) may lie on a
  // rounded corner of the body (0.2-0.35 m radii) or in a wheel arch, whose direction is anything between
  // the sides' and the ends': its direction departs from the footprint's by about short_face_tilt_m over it.
  // So does a face of fewer informative points than min_lower_body_points: each one alone turns its line.
  // Without it one ring's 4-11 points over 0.4-0.7 m stated 4-7 deg and were 15-27 deg off (`rsu-pilot
  // matrix`, 11 of the 26 HMI fixes left after the faces' spread rule).
  double short_face_m = 1.0;
  double short_face_tilt_m = 0.08;
  // A face shorter than corner_face_max_m may be turned by a rounded corner at its end
  // (informative_face.cpp): a car's corners' radius in plan (the simulator's 0.2-0.35 m). A longer face
  // keeps 1.4 m or more of its middle when its direction is refit without corner_exclusion_m at each end
  // (face_refinement.h), and giving it the corner's turn as well made the stated yaw sigma of the paper's SUV
  // 2 m below a VLP-32C 4.1 times its error's RMS (FixConsistency: at most 4), no fix beyond 3 sigma gained
  // in the pilot matrix.
  double corner_radius_m = 0.3;
  double corner_face_max_m = 2.0;
  // A face above the bonnet whose points are one laser's trace, give or take a few of others, counts as that
  // trace (informative_face.cpp): a HDL-32E 3 m up saw a sedan 3 m away with its lowest laser alone over
  // roof and bonnet, 85 of the near face's 89 points (4 of another laser), none on the doors, which no laser
  // reached; the "side" was 11 deg off while stating 3.6 deg, the fix 0.38 m off at NEES 12.8 (HMI).
  double single_trace_share = 0.9;
  // One laser's trace is one straight line in plan (a vertical surface) when its returns lie within this of
  // one (median distance): judged whole for the lower body (vehicle_fix.cpp); a face that is a chord of such
  // a trace (three quarters of the laser's returns within the face's span lie off its band, within
  // crossing_depth_m across it) is tilted from it by the trace's slope (informative_face.cpp).
  double trace_straightness_m = 0.1;
  double crossing_depth_m = 1.0;
  // A side's returns above the bonnet count as the lower body, up to lower_body_fraction of the height,
  // where the upper half of them lies within this of the lower half's line (informative_face.h): a van's
  // glass is 5 cm in, a box body's flat.
  double side_step_m = 0.03;
  // Sides of the box along an axis (box_axis.h): the lower body's extreme within end_tolerance_m of all
  // points' is an end, the body ends within end_allowance_m (+ the azimuth step) beyond it; a higher
  // extreme bounds nothing but containment; a side counts as observed if a laser would hit a body
  // between lowest_body_m
  // and the announced height observation_probe_m beyond it. Containment allows containment_sigmas of
  // point noise; face envelopes consider points within envelope_band_m inside the face.
  double end_tolerance_m = 0.1;
  double end_allowance_m = 0.4;
  // ... but only where the trace's returns lie at most this far apart along the axis: farther apart (a
  // face seen at grazing incidence), the next return of a body going on, over a wheel arch, can lie
  // beyond the segmentation's tolerance (0.7 m) and be dropped with a few others as a cluster too small:
  // rsud's VLP-32C 6 m up kept a side trace's returns 0.68 m apart up to 1 m short of the front wheel
  // (the next two, on the tyre, 0.98 m on, were another cluster) and took the last for the car's front:
  // 1.61 m off at NEES 12.6 (the corridor at 6 m).
  double max_end_spacing_m = 0.35;
  double lowest_body_m = 0.5;
  double observation_probe_m = 0.3;
  double containment_sigmas = 3.0;
  double envelope_band_m = 0.3;
  LShapeFitConfig fit;  // face support and 'seen' rules (the pipeline passes its own)
  FaceRefinementConfig refinement;
  CovarianceModelConfig covariance;
};

// Up to which height above the road a point lies on the lower body (the footprint's outline):
// lower_body_fraction of the announced height; every point when the height is not a finite positive
// number. (Up to max(that, full_plan_height_m) measured better for a small car, 0.9 m doors at 1.48 m,
// but with more fixes beyond 3 sigma at 6-8 m mounts: `rsu-pilot matrix`, issue 12; the sides alone do
// not, side_body_height.)
double lower_body_height(const VehicleSize& size, const CorrectionConfig& config);
// Up to which height a point can be on the footprint's sides: the lower body, and up to full_plan_height_m
// on a vehicle whose lower body ends below it (a small car's doors reach 0.9 m, above 55 % of its 1.48 m).
// Whatever a laser meets there lies at most a cabin's inset inside the side (the belt line's ledge, a
// window), which a face seen only there allows for (box_axis.h, mid_height_inset_width_m); at the front
// and back it may be a bonnet's or boot lid's top, a bonnet's length behind the end (end_body_height).
// Every point when the height is unknown.
double side_body_height(const VehicleSize& size, const CorrectionConfig& config);
// Up to which height a point can be on the footprint's front or back: the lower body, at most
// max_end_body_height_m (every point, as for the lower body, when the height is unknown).
double end_body_height(const VehicleSize& size, const CorrectionConfig& config);
// How high the body surely reaches at the front and back, given end_body_height: all of it, but on a car or
// MPV (end_body_height under max_end_body_height_m) only min_bonnet_height_m, its bonnet maybe lower.
double surely_bonnet_high(double end_height, const CorrectionConfig& config);
// The largest position sigma a fix may state (position_unbounded beyond it): max_position_sigma_m, or
// tighter when packets were lost while the sweep passed the vehicle (LidarGeometry::complete_sweep false).
double max_position_sigma_m(bool complete_sweep, const CorrectionConfig& config);

CorrectedPose correct_algorithm1(const RectangleFit& fit, const VehicleSize& size,
                                 const Eigen::Vector2d& lidar_xy,
                                 const CovarianceModelConfig& covariance = {});

// outline: the xy of the points `fit` was made from; points: all of the vehicle's points (map frame).
// Non-finite ones are ignored.
CorrectedPose correct_improved(const RectangleFit& fit, std::span<const Eigen::Vector2d> outline,
                               std::span<const Eigen::Vector3d> points, const VehicleSize& size,
                               const LidarGeometry& lidar, const std::optional<YawPrior>& prior,
                               const CorrectionConfig& config = {});

}  // namespace rsu::perception
