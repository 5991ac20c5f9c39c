// SPDX-License-Identifier: Apache-2.0
#include "perception/informative_face.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <utility>
#include <vector>

#include "perception/face_traces.h"
#include "perception/size_correction.h"

namespace rsu::perception {
namespace {

// A face's informative points' run: its evenly spread length (spread_length) and how far its points reach
// from first to last.
struct FaceRun {
  double length = 0.0;
  double extent = 0.0;
};

// The longest run of points without a gap wider than `max_gap` (a face is known over it): points on either
// side of such a gap need not lie on one surface (a bumper's corner 4 m from a side's few points, on the line
// a sparse fit drew between them, made a 4.9 m "face" 18 deg off while stating 3 deg: `rsu-pilot matrix`, an
// SUV 33 m from a VLP-32C 6 m up).
FaceRun effective_face_run(std::vector<double> along, double max_gap) {
  std::sort(along.begin(), along.end());
  FaceRun longest;
  std::size_t begin = 0;
  for (std::size_t i = 1; i <= along.size(); ++i) {
    if (i == along.size() || along[i] - along[i - 1] > max_gap) {
      const double length = spread_length(std::span<const double>(along).subspan(begin, i - begin));
      if (length > longest.length)
        longest = {length, along[i - 1] - along[begin]};
      begin = i;
    }
  }
  return longest;
}

// Whether a face's direction is known no better than a short face's (CorrectionConfig::short_face_m): short
// by either measure, its evenly spread length or how far its returns reach from first to last. Four returns
// within 0.87 m at one end of a sports car's side, one of them 0.28 m in (a wheel arch), spread as if evenly
// over 1.17 m and stated 5.1 deg, 21 deg off (a VLP-16 5.5 m up, 31 m away; a fourth pilot matrix, kept out
// of the repository). And a face of fewer returns than the outline needs (min_lower_body_points), however
// far they spread: each one alone turns its line. A hatchback's rear 16 m from a 32-ring sensor 7.5 m up
// showed four below its lower body, three at one end and one on the far corner 0.2 m in: 9 deg off stating
// 2.8 deg (the same matrix).
bool short_face(double length, const FaceRun& run, std::size_t informative, const CorrectionConfig& config) {
  return std::min(length, run.extent) < config.short_face_m || informative < config.min_lower_body_points;
}

// Whether one laser's points (their horizontal ranges from the LiDAR) spread in range by `tolerance`: a
// level surface cut by one laser is an arc at one range.
bool spreads_in_range(std::vector<double> ranges, double tolerance) {
  if (ranges.size() < 2)
    return false;
  std::sort(ranges.begin(), ranges.end());
  const auto at = [&](double q) {
    return ranges[static_cast<std::size_t>(q * static_cast<double>(ranges.size() - 1))];
  };
  return at(0.9) - at(0.1) >= tolerance;
}

// How well a face seen mostly above the bonnet tells the footprint's direction (rad), or a negative value
// where its points do not show it: the upper body departs from the footprint's direction more than the
// lower body does (sloped glass, tumblehome; then upper_face_tilt_m stands). Where the face's points below
// the bonnet are a face (spread over short_face_m along it), the least-squares directions of the points
// above and below it and the fitted edge's are compared: if they agree within the direction the lower body's
// own departure from a plane leaves (2 face_tilt_sigma_m / their length), the face is as good as that.
// Glass set back from the lower body's plane turns no direction; what turns it is a
// surface not parallel to the footprint's edge (one laser's trace across sloped glass, turned by up to its
// depression; a rounded corner). A bus's front seen end-on from a VLP-16 2 m up, 13-22 m away, has more of
// its points above 1 m than below: its direction stated 3.9 deg (its error 0.05 deg), so the vehicle's own
// heading, 10 deg off, was fused in and turned the box 1.5 deg about its front, its centre 6 m behind:
// 0.12-0.16 m off (`rsu-pilot matrix`).
double upper_body_direction_sigma(std::span<const double> lower_along, std::span<const double> lower_across,
                                  std::span<const double> upper_along, std::span<const double> upper_across,
                                  const CorrectionConfig& config) {
  if (lower_along.size() < config.fit.min_face_points || upper_along.size() < config.fit.min_face_points)
    return -1.0;
  const double lower_length =
      effective_face_run({lower_along.begin(), lower_along.end()}, config.short_face_m).length;
  if (lower_length < config.short_face_m)
    return -1.0;
  const double upper = std::atan(least_squares_slope(upper_along, upper_across));
  const double lower = std::atan(least_squares_slope(lower_along, lower_across));
  const double turn = std::max({std::abs(upper - lower), std::abs(upper), std::abs(lower)});
  const double lower_sigma = 2.0 * config.covariance.face_tilt_sigma_m / lower_length;
  return turn <= lower_sigma ? lower_sigma : -1.0;
}

// A face's points above the bonnet: their heights, horizontal ranges from the LiDAR, lasers and places
// along the face.
struct UpperPoints {
  // Point p, at s along the face, of the laser ranked `rank` by `lookup` (-1 for LaserLookup::kNone).
  void add(const Eigen::Vector3d& p, double s, const Eigen::Vector2d& lidar_xy, const LaserLookup& lookup,
           std::size_t rank) {
    heights.push_back(p.z());
    ranges.push_back((p.head<2>() - lidar_xy).norm());
    along.push_back(s);
    lasers.push_back(rank == LaserLookup::kNone ? -1 : lookup.laser(rank));
  }

  std::vector<double> heights, ranges, along;
  std::vector<int> lasers;
};

// A face's returns within its support band: how far across it each lies, and where along and across it
// those below the bonnet (end_height; on a car or MPV, surely_bonnet_high of it) and above it lie. Above
// the bonnet, a laser's few returns in the band where its trace crosses the face (`crossing`,
// face_traces.h) say nothing of its direction: a HDL-32E 4.5 m up saw a coupe 40 m away with one laser
// along its side and across its windscreen's foot, and a face through the crossings was 26 deg off stating
// 5 deg (a third pilot matrix, kept out of the repository). Below it they are the footprint's outline.
struct BandPoints {
  std::vector<double> across;
  std::vector<double> lower_along, lower_across, upper_across;
  UpperPoints upper;
};

BandPoints band_points(std::span<const Eigen::Vector3d> points, const LidarGeometry& lidar,
                       const LaserLookup& lookup, std::span<const std::size_t> ranks, const FaceLine& line,
                       double end_height, const std::vector<bool>& crossing, const CorrectionConfig& config,
                       double noise_sigma) {
  const double bonnet_from = surely_bonnet_high(end_height, config);
  const double arc_tolerance = std::max(config.min_range_spread_m, 4.0 * noise_sigma);
  BandPoints band;
  struct Mid {
    int laser;
    double range, s, n;
    std::size_t index;
  };
  std::vector<Mid> mid;  // below end_height, above bonnet_from
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3d& p = points[i];
    const Eigen::Vector2d r = p.head<2>() - line.a;
    const double s = r.dot(line.t);
    const double n = r.x() * line.t.y() - r.y() * line.t.x();
    if (s < -line.band || s > line.length + line.band || std::abs(n) > line.band)
      continue;
    band.across.push_back(n);
    const double z = p.z() - lidar.ground_z;
    if (z <= end_height && z > bonnet_from && ranks[i] != LaserLookup::kNone) {
      mid.push_back({lookup.laser(ranks[i]), (p.head<2>() - lidar.xy()).norm(), s, n, i});
    } else if (z <= end_height) {
      band.lower_along.push_back(s);
      band.lower_across.push_back(n);
    } else if (!crossing[i]) {
      band.upper_across.push_back(n);
      band.upper.add(p, s, lidar.xy(), lookup, ranks[i]);
    }
  }
  // Between bonnet_from and end_height, one laser's arc at one range may be a level bonnet's or boot lid's
  // trace (across the line of sight whatever the heading), not the front's: it tells no direction. The
  // rest may be the glasshouse over a belt line that low, a window's inset inside the doors: the upper
  // body's, whose direction counts as far as it runs with the lower body's (a minivan's side, one laser's
  // trace across its 0.86 m belt line 36 m from a VLP-16 6.5 m up, was turned 3-5 deg by that step while
  // stating 0.7-1.4 deg as the doors'). One trace's step cannot be told from a turn: its height falls
  // steadily along the side (a line plus a step fitted to that trace found none at 4 sigma).
  std::sort(mid.begin(), mid.end(), [](const Mid& x, const Mid& y) { return x.laser < y.laser; });
  for (std::size_t begin = 0; begin < mid.size();) {
    std::size_t end = begin;
    std::vector<double> ranges;
    for (; end < mid.size() && mid[end].laser == mid[begin].laser; ++end)
      ranges.push_back(mid[end].range);
    const bool level_arc = ranges.size() >= 3 && !spreads_in_range(std::move(ranges), arc_tolerance);
    for (std::size_t k = begin; k < end && !level_arc; ++k) {
      if (crossing[mid[k].index])
        continue;
      band.upper_across.push_back(mid[k].n);
      band.upper.add(points[mid[k].index], mid[k].s, lidar.xy(), lookup, ranks[mid[k].index]);
    }
    begin = end;
  }
  return band;
}

// Which of them tell the face's direction, and where along it they lie.
struct UpperInformation {
  std::size_t points = 0;
  std::vector<double> along;
  // The depression of the laser whose trace they are (0: several lasers', or rising, or unknown), give or
  // take a few points of others (CorrectionConfig::single_trace_share).
  double single_trace_depression = 0.0;
};

// Above the lower body a face tells the direction if it is not a laser's trace on a level surface: it
// rises (several heights), or one laser's points' horizontal ranges vary (a level surface cut by one laser
// is an arc at one range, across the line of sight whatever the vehicle's heading). Judged per laser:
// several lasers' arcs across a roof lie at several ranges.
UpperInformation informative_upper(const UpperPoints& upper, const LidarGeometry& lidar,
                                   const CorrectionConfig& config, double noise_sigma) {
  UpperInformation out;
  if (upper.heights.size() < 3)
    return out;
  const double top = *std::max_element(upper.heights.begin(), upper.heights.end());
  const double arc_tolerance = std::max(config.min_range_spread_m, 4.0 * noise_sigma);
  std::vector<int> lasers = upper.lasers;
  std::sort(lasers.begin(), lasers.end());
  lasers.erase(std::unique(lasers.begin(), lasers.end()), lasers.end());
  // Of the lasers whose trace is not an arc, the one holding most of the points, and how many.
  std::size_t most = 0;
  int holding_most = -1;
  for (const int laser : lasers) {
    std::vector<double> ranges, along;
    for (std::size_t i = 0; i < upper.lasers.size(); ++i) {
      if (upper.lasers[i] == laser) {
        ranges.push_back(upper.ranges[i]);
        along.push_back(upper.along[i]);
      }
    }
    if (spreads_in_range(std::move(ranges), arc_tolerance)) {
      if (along.size() > most) {
        most = along.size();
        holding_most = laser;
      }
      out.along.insert(out.along.end(), along.begin(), along.end());
    }
  }
  if (out.along.size() >= 3) {
    out.points = out.along.size();
    if (holding_most >= 0 &&
        static_cast<double>(most) >= config.single_trace_share * static_cast<double>(out.along.size()))
      out.single_trace_depression = std::abs(lidar.elevations_rad[static_cast<std::size_t>(holding_most)]);
    return out;
  }
  out.along.clear();
  for (std::size_t i = 0; i < upper.heights.size(); ++i) {
    if (upper.heights[i] <= top - config.min_vertical_spread_m)
      out.along.push_back(upper.along[i]);
  }
  if (out.along.size() < 3)
    out.along.clear();
  out.points = out.along.size();
  return out;
}

// The departure a rounded corner at one end of a face of `length` (its points at `along`) gives its
// least-squares direction (fix_covariance.h: the tilt over the face). Where the face meets a corner of radius
// r, the corner's returns within the face's support band d lie about d / 2 off its line over its last r: on a
// face of n points evenly over l they turn the line by about (n r / l) ((l - r) / 2) (d / 2) / (n l^2 / 12) =
// 3 r d (l - r) / l^3 rad, a departure of 1.5 r d (l - r) / l^2 over it (within 10-50 % above the turn a
// least-squares fit takes for radii 0.2-0.35 m: InformativeFace.RoundedCornerTurnIsCovered). Where the face's
// points span its whole side or end (the announced length or width within full_face_tolerance_m) the two
// corners turn it in opposite senses and cancel but for how many returns each corner's band happens to hold:
// the share sqrt(l / (n r)) of it. Without it, a sparse end of a small car beyond 30 m (20-40 returns,
// 1.0-1.7 m of them on one face) was 6-13 deg off while stating 2-3 deg: 0.33-0.65 % of the fixes in the
// worst 5 m band of 11 of the pilot matrices' 120 cells, none in 9 of them now (README, the pilot matrix).
double rounded_corner_departure(std::span<const double> along, double length, const VehicleSize& size,
                                const CorrectionConfig& config) {
  const double r = config.corner_radius_m;
  if (along.size() < 2 || !(length > r) || length >= config.corner_face_max_m)
    return 0.0;
  const auto [first, last] = std::minmax_element(along.begin(), along.end());
  const double extent = *last - *first;
  const double tolerance = config.full_face_tolerance_m;
  const bool whole =
      extent <= size.width + tolerance ? extent >= size.width - tolerance : extent >= size.length - tolerance;
  const double n = static_cast<double>(along.size());
  const double share = whole ? std::min(1.0, std::sqrt(length / (n * r))) : 1.0;
  return share * 1.5 * r * config.fit.edge_support_m * (length - r) / (length * length);
}

}  // namespace

FaceEvidence informative_face(std::span<const Eigen::Vector3d> points, std::span<const std::size_t> ranks,
                              const LidarGeometry& lidar, const CorrectionConfig& config, double end_height,
                              double noise_sigma, const RectangleFit& fit, std::size_t edge,
                              const VehicleSize& size) {
  FaceEvidence face = face_evidence(fit, edge, lidar.xy());
  const Eigen::Vector2d a = fit.corners[edge % 4];
  const Eigen::Vector2d b = fit.corners[(edge + 1) % 4];
  const double len = (b - a).norm();
  const Eigen::Vector2d t = (b - a) / len;
  const double d = config.fit.edge_support_m;
  const LaserLookup lookup(lidar.elevations_rad);
  const FaceLine line{a, t, len, d};
  const std::vector<TracePoint> near = traces_near(points, ranks, line, config.crossing_depth_m);
  const TraceRuns runs = trace_runs(near, lookup.count(), line);
  BandPoints band = band_points(points, lidar, lookup, ranks, line, end_height,
                                crossing_returns(near, runs, points.size(), config.fit.min_face_points),
                                config, noise_sigma);
  const UpperPoints& upper = band.upper;
  const std::vector<double>& lower_along = band.lower_along;
  const UpperInformation informative_above = informative_upper(upper, lidar, config, noise_sigma);
  const std::size_t lower = lower_along.size();
  const std::size_t informative = lower + informative_above.points;
  // Where along the face its informative points lie (below the bonnet; above it those that count).
  std::vector<double> along = lower_along;
  along.insert(along.end(), informative_above.along.begin(), informative_above.along.end());
  face.points = informative;
  // The face's direction is as well known as its informative points' spread along it makes it, not the
  // fitted edge's length: a few points on a rounded bumper's corner made a 1.7 m "face" 24 deg off while
  // stating 2 deg (`rsu-pilot matrix`, a VLP-16 4 m up, an SUV at 25 m).
  // A gap wider than a short face, or than a few points' spacing along the face where that is wider,
  // splits it (a laser's returns lie R * azimuth step apart across the line of sight, farther at grazing
  // incidence; k steps where the fix was given every k-th: the covariance's azimuth resolution).
  const double spacing = (0.5 * (a + b) - lidar.xy()).norm() * config.covariance.azimuth_resolution_rad /
                         std::max(face.incidence_sin, config.covariance.min_incidence_sin);
  const FaceRun run = effective_face_run(along, std::max(config.short_face_m, 3.0 * spacing));
  face.length_m = std::min(face.length_m, run.length);
  // The upper body's faces are trusted less, unless they run parallel to the lower body's: then as well as
  // that over the face's length (a 12 m side whose lower body shows 1.5 m of it, a bus 5 m from a 128-ring
  // sensor 4 m up, no better than those 1.5 m: 1.6 deg off, it stated 0.5 deg without this).
  if (upper.heights.size() >= lower) {
    const double sigma =
        upper_body_direction_sigma(lower_along, band.lower_across, upper.along, band.upper_across, config);
    // Where the lower body does not vouch for them, they depart by upper_face_tilt_m, or by as much as
    // the lasers' runs along the face tilt from it: a HDL-32E 6 m up saw a coupe 9 m away with four lasers
    // over its roof, glass and bonnet and 13 returns of its doors at one end; the face through them was 15
    // deg off stating 2.7 deg, its runs 5-46 deg from it (a third pilot matrix).
    face.departure_m = sigma >= 0.0 ? std::min(config.upper_face_tilt_m, 0.5 * sigma * face.length_m)
                                    : std::max(config.upper_face_tilt_m,
                                               run_tilt_departure(near, runs, face.length_m, noise_sigma,
                                                                  config.fit.min_face_points));
  }
  if (short_face(face.length_m, run, informative, config))
    face.departure_m = std::max(face.departure_m, config.short_face_tilt_m);
  const double crossing = crossing_trace_departure(
      span_traces(near, lookup.count(), line, lidar.ground_z, side_body_height(size, config)), face.length_m,
      config.trace_straightness_m);
  face.departure_m =
      std::max({face.departure_m, rounded_corner_departure(along, face.length_m, size, config), crossing});
  // One laser's trace above the bonnet is not shown to lie on a vertical surface: across a sloped window
  // or the roof's rounded edge (height changing along the body at a rate m) the trace runs across the
  // gradient m u + tan(e) r of body and cone (u the body's axis, r the line of sight, e the laser's
  // depression), turned from the body's axis towards the line of sight's normal by up to about e (m ~ 1,
  // a windscreen's slope). Seen from 6-8 m up such traces (one VLP-16 or VLP-32C laser over an SUV's rear
  // window at 16-24 m) were 20-23 deg off while stating 4-6 deg; a departure of tan(e) over half the face
  // states about e.
  if (lower == 0 && informative_above.single_trace_depression > 0.0)
    face.departure_m =
        std::max(face.departure_m, 0.5 * face.length_m * std::tan(informative_above.single_trace_depression));
  if (band.across.size() >= 3 && informative > 0) {
    // Robust spread (1.4826 MAD) of the face's points about their median line: the body's departure.
    const double centre = median_in_place(band.across);
    for (double& x : band.across)
      x = std::abs(x - centre);
    face.residual_spread_m = 1.4826 * median_in_place(band.across);
  }
  return face;
}

double face_lower_height(std::span<const Eigen::Vector3d> points, const LidarGeometry& lidar,
                         const CorrectionConfig& config, double end_height, double lower_height,
                         const RectangleFit& fit, std::size_t edge, const VehicleSize& size) {
  const Eigen::Vector2d a = fit.corners[edge % 4];
  const Eigen::Vector2d b = fit.corners[(edge + 1) % 4];
  const double len = (b - a).norm();
  // Surely a side: longer than the width by half what the length exceeds it by (an end's fitted edge can
  // run long over a bonnet's or mirror's returns: a van's 2.0 m front was fitted 2.39 m).
  const double side_margin = std::max(config.full_face_tolerance_m, 0.5 * (size.length - size.width));
  if (lower_height <= end_height || !(len > size.width + side_margin))
    return end_height;
  const Eigen::Vector2d t = (b - a) / len;
  const double d = config.fit.edge_support_m;
  struct Return {
    double z, along, across;
  };
  std::vector<Return> below;  // the side's returns up to the lower body's height, by height
  for (const Eigen::Vector3d& p : points) {
    const Eigen::Vector2d r = p.head<2>() - a;
    const double s = r.dot(t);
    const double n = r.x() * t.y() - r.y() * t.x();
    if (s >= -d && s <= len + d && std::abs(n) <= d && p.z() - lidar.ground_z <= lower_height)
      below.push_back({p.z(), s, n});
  }
  if (below.size() < 2 * config.fit.min_face_points)
    return end_height;
  std::sort(below.begin(), below.end(), [](const Return& x, const Return& y) { return x.z < y.z; });
  const std::size_t half = below.size() / 2;
  std::vector<double> low_along, low_across, high_along;
  double low_along_sum = 0.0, low_across_sum = 0.0;
  for (std::size_t i = 0; i < below.size(); ++i) {
    if (i < half) {
      low_along.push_back(below[i].along);
      low_across.push_back(below[i].across);
      low_along_sum += below[i].along;
      low_across_sum += below[i].across;
    } else {
      high_along.push_back(below[i].along);
    }
  }
  if (spread_length(low_along) < config.short_face_m || spread_length(high_along) < config.short_face_m)
    return end_height;
  // The upper half's mean offset from the lower half's line.
  const double slope = least_squares_slope(low_along, low_across);
  const double intercept = (low_across_sum - slope * low_along_sum) / static_cast<double>(half);
  double step = 0.0;
  for (std::size_t i = half; i < below.size(); ++i)
    step += below[i].across - (intercept + slope * below[i].along);
  step /= static_cast<double>(below.size() - half);
  return std::abs(step) <= config.side_step_m ? lower_height : end_height;
}

}  // namespace rsu::perception
