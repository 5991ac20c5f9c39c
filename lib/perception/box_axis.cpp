// SPDX-License-Identifier: Apache-2.0
#include "perception/box_axis.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <vector>

#include "perception/face_envelope.h"
#include "perception/size_correction.h"

namespace rsu::perception {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

struct Extremes {
  double lo = kInf, hi = -kInf;              // over every point
  double lower_lo = kInf, lower_hi = -kInf;  // over the lower-body points
  double plan_lo = kInf, plan_hi = -kInf;  // at the sides, up to the full plan's height (BoxPoint::side_body)
  std::size_t lo_point = 0, hi_point = 0;  // which points are the extremes
};

// Whether p can be on the footprint's outline at the sides of axis a: the lower body (or, with full_plan,
// up to the full plan's height: BoxPoint::side_body) across the length, below the bonnet at the front and
// back (BoxPoint).
bool on_footprint_outline(const AxisContext& ctx, const BoxPoint& p, int a, bool full_plan = false) {
  if (a == ctx.length_axis)
    return p.end_body;
  return full_plan ? p.side_body : p.lower_body;
}

// Both axes' extremes, in one pass over the points.
std::array<Extremes, 2> extremes(const AxisContext& ctx) {
  const std::span<const BoxPoint> points = ctx.points;
  std::array<Extremes, 2> out;
  for (std::size_t i = 0; i < points.size(); ++i) {
    for (int a = 0; a < 2; ++a) {
      Extremes& e = out[static_cast<std::size_t>(a)];
      const double t = points[i].local[a];
      if (t < e.lo) {
        e.lo = t;
        e.lo_point = i;
      }
      if (t > e.hi) {
        e.hi = t;
        e.hi_point = i;
      }
      if (on_footprint_outline(ctx, points[i], a)) {
        e.lower_lo = std::min(e.lower_lo, t);
        e.lower_hi = std::max(e.lower_hi, t);
      }
      if (a != ctx.length_axis && points[i].side_body) {  // face_anchor: not at the front and back
        e.plan_lo = std::min(e.plan_lo, t);
        e.plan_hi = std::max(e.plan_hi, t);
      }
    }
  }
  return out;
}

// The side of the other axis that the LiDAR sees (sign: -1 low, +1 high, 0 none) and its lower body's
// line: an end's returns within a corner's radius of it lie on the rounded corner or the side itself.
struct SeenSide {
  double sign = 0.0;
  double line = 0.0;
};

SeenSide seen_side(const AxisContext& ctx, int a, const Extremes& other) {
  const int b = 1 - a;
  if (a != ctx.length_axis)
    return {};
  if (ctx.lidar_local[b] > other.hi && std::isfinite(other.lower_hi))
    return {1.0, other.lower_hi};
  if (ctx.lidar_local[b] < other.lo && std::isfinite(other.lower_lo))
    return {-1.0, other.lower_lo};
  return {};
}

// The lower-body face (with full_plan: up to the full plan's height) on side `sign` (-1 low, +1 high) of
// axis a, if the points make one there: their outward coordinates (sign * t) within the support band of
// the outline's extreme, spread along the other axis; off_corner: how many of them lie farther than a
// corner's radius from the seen side (all of them where none is seen).
std::vector<double> face_points(const AxisContext& ctx, int a, double sign, double extreme, bool full_plan,
                                const SeenSide& side, const CorrectionConfig& config, double& along_mean,
                                double& along_span, double& lowest, std::size_t& off_corner) {
  const int b = 1 - a;
  std::vector<double> s;
  double along_min = kInf, along_max = -kInf, along_sum = 0.0;
  lowest = kInf;
  off_corner = 0;
  for (const BoxPoint& p : ctx.points) {
    if (!on_footprint_outline(ctx, p, a, full_plan) ||
        sign * (extreme - p.local[a]) > config.fit.edge_support_m)
      continue;
    if (side.sign == 0.0 || side.sign * (side.line - p.local[b]) >= config.corner_radius_m)
      ++off_corner;
    s.push_back(sign * p.local[a]);
    along_min = std::min(along_min, p.local[b]);
    along_max = std::max(along_max, p.local[b]);
    along_sum += p.local[b];
    lowest = std::min(lowest, p.height);
  }
  if (s.size() < config.fit.min_face_points || along_max - along_min < config.fit.min_face_length_m)
    s.clear();
  along_mean = s.empty() ? 0.0 : along_sum / static_cast<double>(s.size());
  along_span = s.empty() ? 0.0 : along_max - along_min;
  return s;
}

// Could the LiDAR have seen the body continue beyond the extreme point on side `sign`? Not if the side
// faces away from it and the face along the other axis that would show the continuation is hidden too
// (self-occlusion), nor where no laser reaches a body there (field of view).
bool observable_beyond(const AxisContext& ctx, int a, double sign, const Extremes& e, const Extremes& other,
                       const LidarGeometry& lidar, const CorrectionConfig& config) {
  const int b = 1 - a;
  const double extreme = sign > 0 ? e.hi : e.lo;
  const bool side_faces_lidar = sign * (ctx.lidar_local[a] - extreme) > 0.0;
  // The face along this axis shows its own continuation only if the LiDAR sees it at an angle the frame's
  // direction is sure of (a face seen at grazing incidence, or maybe not at all, shows nothing).
  const double beyond = std::max(other.lo - ctx.lidar_local[b], ctx.lidar_local[b] - other.hi);
  const double sin_view = beyond / std::max(ctx.lidar_local.norm(), 1e-9);
  const bool other_face_visible =
      beyond > 0.0 &&
      sin_view >= std::max(config.min_incidence_cos, std::sin(std::min(2.0 * ctx.yaw_sigma, 1.5)));
  if (!side_faces_lidar && !other_face_visible)
    return false;
  const BoxPoint& p = ctx.points[sign > 0 ? e.hi_point : e.lo_point];
  Eigen::Vector2d probe = p.local;
  probe[a] += sign * config.observation_probe_m;
  const double range = (probe - ctx.lidar_local).norm();
  // Towards the front or back the body may go on only bonnet high (a laser passing above the bonnet
  // sees nothing of it): only a laser meeting it below that would have seen it. A car's or MPV's bonnet
  // may lie under its lower body's share, down to min_bonnet_height_m.
  const double top = a == ctx.length_axis
                         ? std::min(surely_bonnet_high(ctx.end_height, config), ctx.vehicle_height)
                         : ctx.vehicle_height;
  return lidar.sees_surface(range, config.lowest_body_m, top);
}

// How far apart along axis a a laser's returns lie on the face along it near p: range x azimuth step
// across the line of sight, farther along a face seen at grazing incidence.
double spacing_along(const AxisContext& ctx, int a, const BoxPoint& p, const LidarGeometry& lidar,
                     const CorrectionConfig& config) {
  const Eigen::Vector2d sight = p.local - ctx.lidar_local;
  const double sin_incidence = std::abs(sight[1 - a]) / std::max(sight.norm(), 1e-9);
  return p.range * lidar.azimuth_step_rad / std::max(sin_incidence, config.min_incidence_cos);
}

// The highest of the body's points at the extreme's place along axis a: within a laser column's spread
// along the axis there (range x azimuth step over the sine of the incidence on the face along the axis,
// at least end_tolerance_m). A side seen at grazing incidence returns each column's lasers at one place
// along the axis, one above the other: those above the extreme met the body there and passed above nothing
// (a van's side 40 m along a 128-ring sensor's line of sight, its lowest return the trace's end: the
// shadow put its front 1.2 m short, a fix 0.98 m off at NEES 20.6).
double highest_at_extreme(const AxisContext& ctx, int a, const BoxPoint& extreme, const LidarGeometry& lidar,
                          const CorrectionConfig& config) {
  const double spread = std::max(config.end_tolerance_m, spacing_along(ctx, a, extreme, lidar, config));
  double top = extreme.height;
  for (const BoxPoint& q : ctx.points) {
    if (std::abs(q.local[a] - extreme.local[a]) <= spread)
      top = std::max(top, q.height);
  }
  return top;
}

// Beyond an extreme on the side facing away from the LiDAR the body hides what lies behind it, but not
// for ever: a laser that passes above the extreme point descends and meets any body at least
// lowest_body_m tall that goes on behind it, and returns from there. The nearest such laser bounds how far
// the body can go on along the axis (the shadow), + the azimuth step and, as for an end, end_allowance_m.
// Infinite if no laser passes above.
double shadow_allowance(const AxisContext& ctx, int a, const BoxPoint& extreme, const LidarGeometry& lidar,
                        const CorrectionConfig& config) {
  const double h = lidar.height_above_ground();
  const double top = highest_at_extreme(ctx, a, extreme, lidar, config);
  double nearest = kInf;
  for (const double e : lidar.elevations_rad) {
    const double down = std::tan(-e);
    // Rising, or meeting the body at or before the extreme point (the lasers that saw it or the body
    // above it there among them).
    if (!(down > 0.0) || h - extreme.range * down < top + config.end_tolerance_m)
      continue;
    // Under lowest_body_m already at the extreme (which lies lower still): the body ends there, but for the
    // rounded corner (end_allowance_m, below), which a negative reach ate: a minivan's sill at 0.25 m, 0.36 m
    // short of its front, gave 0.15 m and a fix 0.42 m off stating 0.15 m.
    nearest = std::min(nearest, std::max(0.0, (h - config.lowest_body_m) / down - extreme.range));
  }
  if (!std::isfinite(nearest))
    return kInf;
  // The body's rounded corners, as for an end: a laser passing just above an extreme point at the
  // corner's start (a small car's side seen at grazing incidence, 5 m from a VLP-16 2 m up) hugs the
  // rounding and misses it; the shadow alone put the far end 0.33 m short while stating 0.07 m.
  const Eigen::Vector2d sight = extreme.local - ctx.lidar_local;
  const double along_axis = std::abs(sight[a]) / std::max(sight.norm(), 1e-9);
  return (nearest + extreme.range * lidar.azimuth_step_rad) / std::max(along_axis, config.min_incidence_cos) +
         config.end_allowance_m;
}

// Horizontal range from the LiDAR to the point of a face at coordinate `face` on axis a and `along` on the
// other axis.
double face_range(const AxisContext& ctx, int a, double face, double along) {
  Eigen::Vector2d p;
  p[a] = face;
  p[1 - a] = along;
  return (p - ctx.lidar_local).norm();
}

// Whether something nearer in the line of sight lies just beyond the extreme point of side `sign` of axis
// a: its shadow, not the body, ends the points there.
bool shadowed_beyond(const AxisContext& ctx, int a, double sign, const Extremes& e,
                     const LidarGeometry& lidar, const CorrectionConfig& config) {
  Eigen::Vector2d probe = ctx.points[sign > 0 ? e.hi_point : e.lo_point].local;
  probe[a] += sign * config.observation_probe_m;
  return lidar.occluded(ctx.origin + probe[0] * ctx.e0 + probe[1] * ctx.e1, config.observation_probe_m);
}

// A lower-body face on the side of axis a that faces the LiDAR (at most one side of an axis can), placed
// at its points' outer envelope; none if the points make no face there, or a short one (under
// short_face_m along it) that ends in another object's shadow (a van behind a truck, its front's far half
// seen: the shadow's edge, a column of points 0.36 m along it, was taken for its near side, 1.15 m off
// at NEES 79, `rsu-corridor placement` on the traffic street). Longer faces stand: the shadow test is in
// the plane, and from a mast it took faces seen over low objects for shadowed (the corridor at 6 m: the
// VLP-16's fixes 34 -> 19; 29 with this rule, one live run each).
std::optional<AxisEstimate> face_on_outline(const AxisContext& ctx, int a, const Extremes& e,
                                            const Extremes& other, bool full_plan, const LidarGeometry& lidar,
                                            const CorrectionConfig& config) {
  const double dim = ctx.dims[a];
  const double tolerance = config.containment_sigmas * ctx.noise_sigma;
  for (const double sign : {-1.0, 1.0}) {
    const double lower_extreme =
        full_plan ? (sign > 0 ? e.plan_hi : e.plan_lo) : (sign > 0 ? e.lower_hi : e.lower_lo);
    const double extreme = sign > 0 ? e.hi : e.lo;
    if (!std::isfinite(lower_extreme) || sign * (ctx.lidar_local[a] - extreme) <= 0.0 ||
        sign * (extreme - lower_extreme) > config.end_tolerance_m)
      continue;
    double along_mean = 0.0, along_span = 0.0, lowest = 0.0;
    std::size_t off_corner = 0;
    const std::vector<double> s =
        face_points(ctx, a, sign, lower_extreme, full_plan, seen_side(ctx, a, other), config, along_mean,
                    along_span, lowest, off_corner);
    if (s.empty() || (along_span < config.short_face_m && shadowed_beyond(ctx, a, sign, e, lidar, config)))
      continue;
    // Above the lower body a laser may land on the belt line's ledge, up to a window's inset d inside the
    // side, if it passes the side within d tan(depression) above it: from a mast that is a band of lasers
    // (a 128-ring sensor 4 m up, a small car 7 m away: most of the points, and the side was placed on them,
    // 0.1 m in), at a shallow depression a sliver within the points' noise, and the outer envelope stands.
    if (full_plan && (lidar.height_above_ground() - lowest) * config.mid_height_inset_width_m >
                         ctx.noise_sigma * face_range(ctx, a, lower_extreme, along_mean))
      continue;
    const FaceEnvelope env = ctx.envelopes != nullptr
                                 ? (*ctx.envelopes)(s, ctx.noise_sigma, config.envelope_band_m)
                                 : outer_envelope(s, ctx.noise_sigma, config.envelope_band_m);
    // A face seen only above the height to which every vehicle's body keeps its full plan may be set back
    // (a bus's windscreen above its low front; a small car's side seen only above 55 % of its height, on
    // its doors or maybe the belt line's ledge) - unless a laser passing below it, at the face, would have
    // hit the body had it reached farther out there: up to mid_height_inset_m (low_bonnet_inset_m at the ends
    // of a car or MPV, whose bonnet may lie under 55 % of its height), the middle of that with its spread.
    const double lower_body = config.lower_body_fraction * ctx.vehicle_height;
    const bool car_or_mpv = lower_body < config.max_end_body_height_m;
    const bool car_end = a == ctx.length_axis && car_or_mpv;
    const bool seen_lower = lidar.sees_surface(face_range(ctx, a, sign * env.position, along_mean) + 0.1,
                                               config.ground_clearance_m, lowest - 0.05);
    const bool seen_below = lowest <= std::min(config.full_plan_height_m, lower_body) || seen_lower;
    const double end_setback = car_end ? config.low_bonnet_inset_m : config.mid_height_inset_m;
    const double setback =
        seen_below ? 0.0 : (a == ctx.length_axis ? end_setback : config.mid_height_inset_width_m);
    const double face = sign * (env.position + setback / 2.0);
    // Such an end seen lowest between min_bonnet_height_m and the full plan's height may be the front
    // itself or the windscreen above a low bonnet, its lowest return up the screen's rake from its base:
    // it stays, 3 sigma reaching the bonnet's front. Such a side may be the glasshouse above a low belt
    // line, a window's inset inside the doors: it stays, 3 sigma reaching the doors.
    const bool over_low_body =
        car_or_mpv && seen_below && !seen_lower && lowest > std::min(config.min_bonnet_height_m, lower_body);
    const double up_the_screen =
        std::max(0.0, lowest - config.min_bonnet_height_m) * config.windscreen_run_per_rise;
    const double low_body = !over_low_body         ? 0.0
                            : a == ctx.length_axis ? (config.low_bonnet_inset_m + up_the_screen) / 3.0
                                                   : config.mid_height_inset_width_m / 3.0;
    // An end with fewer than a face's points away from the rounded corner by the seen side (the rest on
    // the corner or the side itself) may lie up to the corner's radius beyond them: the envelope of such
    // 3-4 returns stated 0.02 m and was 0.14-0.15 m off (HDL-32E 6-7 m up, a minibus at 30 m and an
    // estate at 33 m, seen broadside a little from one end: the second and third pilot matrices).
    const double corner = off_corner < config.fit.min_face_points ? config.corner_radius_m / 2.0 : 0.0;
    const double sigma =
        std::sqrt(env.sigma * env.sigma + setback * setback / 12.0 + corner * corner + low_body * low_body);
    AxisEstimate out;
    out.centre = face - sign * dim / 2.0;
    out.across = along_mean;
    out.evidence = {AxisAnchor::face, static_cast<std::size_t>(std::lround(env.face_points)), sigma, 0.0};
    out.contained = e.lo >= out.centre - dim / 2.0 - tolerance - config.inconsistent_outside_m &&
                    e.hi <= out.centre + dim / 2.0 + tolerance + config.inconsistent_outside_m;
    return out;
  }
  return std::nullopt;
}

// The face anchoring axis a: on the lower body's points, or, at a side whose lower body makes no face
// there, on its points up to the full plan's height seen at a shallow depression (side_body_height; 22-24 m
// from a VLP-16 2 m up only the -3 deg laser meets a small car, on its doors at 0.78-0.90 m, above 55 % of
// its 1.48 m; the box sat in the 1.6 m interval containment leaves across it, 0.5-0.8 m off).
std::optional<AxisEstimate> face_anchor(const AxisContext& ctx, int a, const Extremes& e,
                                        const Extremes& other, const LidarGeometry& lidar,
                                        const CorrectionConfig& config) {
  if (auto face = face_on_outline(ctx, a, e, other, false, lidar, config))
    return face;
  if (a == ctx.length_axis)
    return std::nullopt;
  return face_on_outline(ctx, a, e, other, true, lidar, config);
}

// How far beyond its extreme point a side of the box may lie, and whether that extreme is an end of the
// body.
struct Side {
  double allowance = kInf;
  bool end = false;
};

Side side_bound(const AxisContext& ctx, int a, double sign, const Extremes& e, const Extremes& other,
                const LidarGeometry& lidar, const CorrectionConfig& config) {
  const BoxPoint& p = ctx.points[sign > 0 ? e.hi_point : e.lo_point];
  // Packets lost near the vehicle, or another object's shadow beyond the extreme: nothing bounds that side
  // but containment.
  if (!lidar.complete_sweep || shadowed_beyond(ctx, a, sign, e, lidar, config))
    return Side{};
  const double extreme = sign > 0 ? e.hi : e.lo;
  const double lower_extreme = sign > 0 ? e.lower_hi : e.lower_lo;
  if (observable_beyond(ctx, a, sign, e, other, lidar, config) && std::isfinite(lower_extreme) &&
      sign * (extreme - lower_extreme) <= config.end_tolerance_m) {
    // A laser's returns along a face lie range x azimuth step apart across the line of sight, farther
    // along a face seen at grazing incidence: the body may go on that far without a return.
    const double spacing = spacing_along(ctx, a, p, lidar, config);
    if (spacing <= config.max_end_spacing_m)
      return Side{config.end_allowance_m + spacing, true};
  }
  // Not seen beyond, or higher up (glasshouse, roof, bonnet: a laser's trace leaves a roof through
  // whichever edge it meets): only containment and, facing away, the shadow bound that side.
  const bool faces_away = sign * (ctx.lidar_local[a] - extreme) < 0.0;
  return Side{faces_away && !lidar.elevations_rad.empty() ? shadow_allowance(ctx, a, p, lidar, config) : kInf,
              false};
}

// Axis a (0 or 1) of the box, from both axes' extremes (extremes(ctx)).
AxisEstimate estimate_axis(const AxisContext& ctx, int a, const Extremes& e, const Extremes& other,
                           const LidarGeometry& lidar, const CorrectionConfig& config) {
  AxisEstimate out;
  const double dim = ctx.dims[a];
  if (const auto face = face_anchor(ctx, a, e, other, lidar, config))
    return *face;
  const Side low = side_bound(ctx, a, -1.0, e, other, lidar, config);
  const Side high = side_bound(ctx, a, 1.0, e, other, lidar, config);

  // Both ends of the lower body seen and spanning the known size: the middle. Rounded corners cut both
  // ends alike only seen square on: on a diagonal the line of sight leaves the far corner early (an SUV
  // 4 m from a VLP-32C 2 m up: 0.28 m short at one end, 0.15 m off stating 0.04 m), so the shortfall,
  // over which the centre may lie, goes into the covariance (fix_covariance.cpp).
  if (low.end && high.end && std::abs((e.hi - e.lo) - dim) <= config.full_face_tolerance_m) {
    out.centre = 0.5 * (e.lo + e.hi);
    out.across = 0.5 * (ctx.points[e.lo_point].local[1 - a] + ctx.points[e.hi_point].local[1 - a]);
    out.evidence = {AxisAnchor::midpoint, 0, -1.0, std::abs(dim - (e.hi - e.lo))};
    return out;
  }

  // The interval containment and the sides leave. If the sides contradict the known size (the points
  // span less than it although both ends look like the body's ends), one of them is not an end (a
  // neighbour or a hedge hides the rest): containment alone bounds the box then.
  const double tolerance = config.containment_sigmas * ctx.noise_sigma;
  const double contain_lo = e.hi - dim / 2.0 - tolerance;
  const double contain_hi = e.lo + dim / 2.0 + tolerance;
  double lo = std::max(contain_lo, e.lo - low.allowance + dim / 2.0);
  double hi = std::min(contain_hi, e.hi + high.allowance - dim / 2.0);
  if (lo > hi) {
    lo = contain_lo;
    hi = contain_hi;
  }
  out.contained = lo <= hi + config.inconsistent_outside_m;
  out.centre = lo <= hi ? 0.5 * (lo + hi) : 0.5 * (e.lo + e.hi);
  double centroid = 0.0;
  for (const BoxPoint& p : ctx.points)
    centroid += p.local[1 - a];
  out.across = centroid / static_cast<double>(ctx.points.size());
  out.evidence = {AxisAnchor::interval, 0, -1.0, std::max(0.0, hi - lo)};
  return out;
}

}  // namespace

std::array<AxisEstimate, 2> estimate_axes(const AxisContext& ctx, const LidarGeometry& lidar,
                                          const CorrectionConfig& config) {
  std::array<AxisEstimate, 2> out;
  if (ctx.points.empty()) {  // nothing bounds it: anywhere within a box's size of the frame's origin
    for (int a = 0; a < 2; ++a)
      out[static_cast<std::size_t>(a)].evidence = {AxisAnchor::interval, 0, -1.0, ctx.dims[a]};
    return out;
  }
  const std::array<Extremes, 2> e = extremes(ctx);
  out[0] = estimate_axis(ctx, 0, e[0], e[1], lidar, config);
  out[1] = estimate_axis(ctx, 1, e[1], e[0], lidar, config);
  return out;
}

}  // namespace rsu::perception
