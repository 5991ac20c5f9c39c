// The improved size correction (see size_correction.h): prior-decided or geometry-decided length/width
// assignment, known-size box hypotheses, and per-axis anchoring on seen faces.
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <vector>

#include "perception/face_refinement.h"
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

// The fitted rectangle's own frame: origin at its centre, axes e1 (axis 0) and e2 (axis 1). Its edges
// perpendicular to axis a are, on the low side, edge kLowEdge[a], on the high side kHighEdge[a].
constexpr std::array<std::size_t, 2> kLowEdge = {3, 0};
constexpr std::array<std::size_t, 2> kHighEdge = {1, 2};

struct Frame {
  Eigen::Vector2d origin;
  Eigen::Vector2d e1;
  Eigen::Vector2d e2;
  Eigen::Vector2d local(const Eigen::Vector2d& p) const {
    return {(p - origin).dot(e1), (p - origin).dot(e2)};
  }
  Eigen::Vector2d map(const Eigen::Vector2d& c) const { return origin + c.x() * e1 + c.y() * e2; }
};

struct AxisOption {
  double centre = 0.0;  // centre coordinate on this axis
  double anchor = 0.0;  // the coordinate the centre was derived from
  AxisEvidence evidence;
  bool alternative = false;  // an end anchor offered against a seen face
};

struct Hypothesis {
  int length_axis = 0;                               // 0: the vehicle's length lies along e1; 1: along e2
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();  // local
  Eigen::Vector2d half = Eigen::Vector2d::Zero();    // half sizes along e1, e2
  Eigen::Vector2d anchor = Eigen::Vector2d::Zero();  // local
  std::array<AxisEvidence, 2> evidence{};            // along e1, e2
  double score = 0.0;                                // lower is better
  bool alternative = false;  // anchored at a points' end although a face was seen on that axis
};

double median(std::vector<double>& v) {
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

class Corrector {
 public:
  Corrector(const RectangleFit& fit, std::span<const Eigen::Vector2d> cluster_xy,
            const Eigen::Vector2d& lidar_xy, const CorrectionConfig& config)
      : fit_(fit), config_(config), frame_{fit.center, fit.axis0(), fit.axis1()} {
    for (const auto& p : cluster_xy) {
      if (p.allFinite()) {
        pts_.push_back(frame_.local(p));
      }
    }
    lidar_ = frame_.local(lidar_xy);
    half_extent_ = {fit.length0 / 2.0, fit.length1 / 2.0};
    assign_points_to_seen_faces();
    const double range = (lidar_xy - fit.center).norm();
    cover_radius_ = std::max(config.cover_radius_m, range * config.covariance.azimuth_resolution_rad);
  }

  // Every known-size box worth considering, for both assignments.
  std::vector<Hypothesis> hypotheses(const VehicleSize& size) const {
    std::vector<Hypothesis> all;
    for (int length_axis = 0; length_axis < 2; ++length_axis) {
      const std::array<double, 2> dims = length_axis == 0 ? std::array<double, 2>{size.length, size.width}
                                                          : std::array<double, 2>{size.width, size.length};
      const auto along0 = axis_options(0, dims[0]);
      const auto along1 = axis_options(1, dims[1]);
      for (const auto& o0 : along0) {
        for (const auto& o1 : along1) {
          Hypothesis h;
          h.length_axis = length_axis;
          h.centre = {o0.centre, o1.centre};
          h.half = {dims[0] / 2.0, dims[1] / 2.0};
          h.anchor = {o0.anchor, o1.anchor};
          h.evidence = {o0.evidence, o1.evidence};
          h.alternative = o0.alternative || o1.alternative;
          h.score = score(h);
          all.push_back(h);
        }
      }
    }
    return all;
  }

  // The most consistent box per assignment, of the boxes anchored on seen faces where there are any
  // (the alternatives only test the chosen box, below).
  static std::array<Hypothesis, 2> best_per_assignment(const std::vector<Hypothesis>& all) {
    std::array<Hypothesis, 2> best;
    std::array<bool, 2> found{false, false};
    for (const Hypothesis& h : all) {
      if (h.alternative) {
        continue;
      }
      const auto a = static_cast<std::size_t>(h.length_axis);
      if (!found[a] || h.score < best[a].score) {
        best[a] = h;
        found[a] = true;
      }
    }
    return best;
  }

  const Frame& frame() const { return frame_; }

  // Fraction of the points farther than `tolerance` outside the hypothesis box.
  double outside_fraction(const Hypothesis& h, double tolerance) const {
    if (pts_.empty()) {
      return 0.0;
    }
    const auto outside = std::count_if(pts_.begin(), pts_.end(), [&](const Eigen::Vector2d& p) {
      return ((p - h.centre).cwiseAbs() - h.half).maxCoeff() > tolerance;
    });
    return static_cast<double>(outside) / static_cast<double>(pts_.size());
  }

  // Spread of the points assigned to fitted edge `edge` about their median line: how far the body's
  // outline along that face departs from a straight face (0 when fewer than 3 points).
  double face_residual(std::size_t edge) const {
    const int a = (edge == kLowEdge[0] || edge == kHighEdge[0]) ? 0 : 1;
    std::vector<double> v;
    for (std::size_t i = 0; i < pts_.size(); ++i) {
      if (face_of_point_[i] == static_cast<int>(edge)) {
        v.push_back(pts_[i][a]);
      }
    }
    if (v.size() < 3) {
      return 0.0;
    }
    // Robust scale (1.4826 x the median absolute deviation): the corner points of the perpendicular face
    // that fall within the support distance must not pass for a bulging body.
    const double centre = median(v);
    for (double& x : v) {
      x = std::abs(x - centre);
    }
    return 1.4826 * median(v);
  }

 private:
  // Where the known-size box can sit along axis a (dimension `dim` on that axis).
  std::vector<AxisOption> axis_options(int a, double dim) const {
    const auto ua = static_cast<std::size_t>(a);
    const RectangleEdge& low = fit_.edges[kLowEdge[ua]];
    const RectangleEdge& high = fit_.edges[kHighEdge[ua]];
    const double lo = -half_extent_[a];
    const double hi = half_extent_[a];
    if (low.seen || high.seen) {
      // A box seen from outside shows at most one of two opposite faces; prefer the better supported.
      const bool use_low = low.seen && (!high.seen || low.support_points >= high.support_points);
      const double face = face_position(a, use_low);
      const std::size_t n = use_low ? low.support_points : high.support_points;
      const double centre = use_low ? face + dim / 2.0 : face - dim / 2.0;
      // The face may not be an outer face of the vehicle: at long range a few points of the cabin or
      // an occlusion edge look like one. The boxes anchored at either end of the points' extent compete
      // with it on consistency (score), and their distance makes the fix's covariance honest.
      std::vector<AxisOption> options{{centre, face, {AxisAnchor::face, n}}};
      if (config_.strict_consistency_checks && hi - lo < dim - config_.full_face_tolerance_m) {
        options.push_back({lo + dim / 2.0, lo, {AxisAnchor::one_end, 0}, true});
        options.push_back({hi - dim / 2.0, hi, {AxisAnchor::one_end, 0}, true});
      }
      return options;
    }
    if (std::abs((hi - lo) - dim) <= config_.full_face_tolerance_m) {
      return {{0.5 * (lo + hi), 0.5 * (lo + hi), {AxisAnchor::midpoint, 0}}};
    }
    // Only face ends fix this axis and the points do not span the known size: either end may be the
    // real one. The end nearer the LiDAR goes first (ties keep it), after Algorithm 1's reasoning.
    AxisOption from_low{lo + dim / 2.0, lo, {AxisAnchor::one_end, 0}};
    AxisOption from_high{hi - dim / 2.0, hi, {AxisAnchor::one_end, 0}};
    if (std::abs(lidar_[a] - hi) < std::abs(lidar_[a] - lo)) {
      std::swap(from_low, from_high);
    }
    return {from_low, from_high};
  }

  // Each point belongs to the nearest seen face within the support distance, if any (-1 otherwise), so
  // that an L's corner points locate the face they lie on and not the perpendicular one as well.
  void assign_points_to_seen_faces() {
    const double d = config_.fit.edge_support_m;
    face_of_point_.assign(pts_.size(), -1);
    for (std::size_t i = 0; i < pts_.size(); ++i) {
      double nearest = d;
      for (int a = 0; a < 2; ++a) {
        const int b = 1 - a;
        if (std::abs(pts_[i][b]) > half_extent_[b] + d) {
          continue;  // beyond the ends of both faces perpendicular to axis a
        }
        for (const std::size_t edge :
             {kLowEdge[static_cast<std::size_t>(a)], kHighEdge[static_cast<std::size_t>(a)]}) {
          const double bound =
              edge == kLowEdge[static_cast<std::size_t>(a)] ? -half_extent_[a] : half_extent_[a];
          const double dist = std::abs(pts_[i][a] - bound);
          if (fit_.edges[edge].seen && dist <= nearest) {
            nearest = dist;
            face_of_point_[i] = static_cast<int>(edge);
          }
        }
      }
    }
  }

  // Median coordinate on axis a of the points on the face at the low or high bound: robust to the
  // outward bias of the extreme point that bounds the fitted rectangle.
  double face_position(int a, bool low) const {
    const std::size_t edge =
        low ? kLowEdge[static_cast<std::size_t>(a)] : kHighEdge[static_cast<std::size_t>(a)];
    std::vector<double> v;
    for (std::size_t i = 0; i < pts_.size(); ++i) {
      if (face_of_point_[i] == static_cast<int>(edge)) {
        v.push_back(pts_[i][a]);
      }
    }
    return v.empty() ? (low ? -half_extent_[a] : half_extent_[a]) : median(v);
  }

  // Inconsistency of a hypothesis box with the points, in [0, 2]: the fraction of points outside it
  // plus the fraction (weighted by the cosine of incidence) of its LiDAR-facing outline without points.
  double score(const Hypothesis& h) const {
    std::size_t outside = 0;
    for (const auto& p : pts_) {
      const Eigen::Vector2d q = (p - h.centre).cwiseAbs() - h.half;
      if (q.maxCoeff() > config_.outside_tolerance_m) {
        ++outside;
      }
    }
    const double outside_fraction =
        pts_.empty() ? 0.0 : static_cast<double>(outside) / static_cast<double>(pts_.size());

    double expected = 0.0;
    double missing = 0.0;
    for (int a = 0; a < 2; ++a) {
      for (const double side : {-1.0, 1.0}) {
        const double face = h.centre[a] + side * h.half[a];
        const double towards = side * (lidar_[a] - face);
        if (towards <= 0.0) {
          continue;  // faces away from the LiDAR
        }
        face_coverage(h, a, face, towards, expected, missing);
      }
    }
    const double uncovered_fraction = expected > 0.0 ? missing / expected : 1.0;
    return outside_fraction + uncovered_fraction;
  }

  void face_coverage(const Hypothesis& h, int a, double face, double towards, double& expected,
                     double& missing) const {
    const int b = 1 - a;
    const double from = h.centre[b] - h.half[b];
    const double length = 2.0 * h.half[b];
    const auto bins = static_cast<std::size_t>(std::max(1.0, std::ceil(length / config_.face_bin_m)));
    const double bin = length / static_cast<double>(bins);
    std::vector<bool> covered(bins, false);
    for (const auto& p : pts_) {
      if (std::abs(p[a] - face) > cover_radius_) {
        continue;
      }
      const double t0 = (p[b] - cover_radius_ - from) / bin;
      const double t1 = (p[b] + cover_radius_ - from) / bin;
      if (t1 < 0.0 || t0 >= static_cast<double>(bins)) {
        continue;
      }
      const auto j0 = static_cast<std::size_t>(std::max(0.0, std::floor(t0)));
      const auto j1 = std::min(bins - 1, static_cast<std::size_t>(std::floor(t1)));
      for (std::size_t j = j0; j <= j1; ++j) {
        covered[j] = true;
      }
    }
    for (std::size_t j = 0; j < bins; ++j) {
      const double t = from + (static_cast<double>(j) + 0.5) * bin;
      const double along = lidar_[b] - t;
      const double cos_incidence = towards / std::sqrt(towards * towards + along * along);
      if (cos_incidence < config_.min_incidence_cos) {
        continue;
      }
      expected += cos_incidence;
      if (!covered[j]) {
        missing += cos_incidence;
      }
    }
  }

  const RectangleFit& fit_;
  const CorrectionConfig& config_;
  Frame frame_;
  std::vector<Eigen::Vector2d> pts_;  // local
  std::vector<int> face_of_point_;    // seen edge each point lies on, -1 for none
  Eigen::Vector2d lidar_;             // local
  Eigen::Vector2d half_extent_;       // of the fitted rectangle
  double cover_radius_;
};

}  // namespace

CorrectedPose correct_improved(const RectangleFit& fit, std::span<const Eigen::Vector2d> cluster_xy,
                               const VehicleSize& size, const Eigen::Vector2d& lidar_xy,
                               const std::optional<YawPrior>& prior, const CorrectionConfig& config) {
  CorrectedPose out;
  if (!fit.ok()) {
    out.status = CorrectionStatus::no_fit;
    return out;
  }
  if (!(std::isfinite(size.length) && std::isfinite(size.width) && size.length > 0.0 && size.width > 0.0)) {
    out.status = CorrectionStatus::invalid_size;
    return out;
  }
  if (!lidar_xy.allFinite() ||
      (prior && !(std::isfinite(prior->yaw) && std::isfinite(prior->sigma) && prior->sigma > 0.0))) {
    out.status = CorrectionStatus::invalid_input;
    return out;
  }

  const RectangleFit refined = config.refine_on_faces
                                   ? refine_on_faces(fit, cluster_xy, lidar_xy, config.fit, config.refinement)
                                   : fit;
  const Corrector corrector(refined, cluster_xy, lidar_xy, config);
  const std::vector<Hypothesis> all = corrector.hypotheses(size);
  const std::array<Hypothesis, 2> best = Corrector::best_per_assignment(all);

  // Log-odds that the length lies along e1 rather than e2.
  const double geometry_log_odds = (best[1].score - best[0].score) / config.geometry_scale;
  double prior_log_odds = 0.0;
  if (prior) {
    // Angular distance (mod pi) of the prior from e1; e2 is pi/2 minus it.
    const double d0 = std::abs(fold_half_turn(prior->yaw - refined.yaw));
    const double d1 = kPi / 2.0 - d0;
    prior_log_odds = (d1 * d1 - d0 * d0) / (2.0 * prior->sigma * prior->sigma);
  }
  const bool prior_decisive = prior && logistic(std::abs(prior_log_odds)) >= config.min_confidence;
  const double log_odds = prior_decisive ? prior_log_odds : geometry_log_odds + prior_log_odds;
  int chosen = log_odds > 0.0 ? 0 : 1;
  if (log_odds == 0.0) {  // a perfect tie: fall back on Algorithm 1's rule (the longer edge is the length)
    chosen = refined.length0 >= refined.length1 ? 0 : 1;
  }
  const Hypothesis& h = best[static_cast<std::size_t>(chosen)];
  const Hypothesis& other = best[static_cast<std::size_t>(1 - chosen)];
  out.confidence = logistic(std::abs(log_odds));
  if (prior_decisive) {
    out.resolution = AmbiguityResolution::prior;
  } else {
    out.resolution = out.confidence >= config.min_confidence ? AmbiguityResolution::geometry
                                                             : AmbiguityResolution::unresolved;
  }

  if (corrector.outside_fraction(h, config.inconsistent_outside_m) > config.max_outside_fraction) {
    out.status = CorrectionStatus::inconsistent_box;
    return out;
  }

  const Frame& frame = corrector.frame();
  const Eigen::Vector2d centre = frame.map(h.centre);
  double yaw = refined.yaw + (chosen == 0 ? 0.0 : kPi / 2.0);
  if (prior) {
    yaw = angle_distance(yaw, prior->yaw) <= kPi / 2.0 ? wrap_angle(yaw) : wrap_angle(yaw + kPi);
    out.heading_from_prior = true;
  } else {
    yaw = fold_half_turn(yaw);
  }
  out.status = CorrectionStatus::ok;
  out.pose = {centre.x(), centre.y(), yaw};
  out.alignment_point = frame.map(h.anchor);

  FixEvidence evidence;
  evidence.range_m = (out.alignment_point - lidar_xy).norm();
  evidence.yaw = yaw;
  evidence.lever = centre - out.alignment_point;
  evidence.length_axis = h.evidence[static_cast<std::size_t>(chosen)];
  evidence.width_axis = h.evidence[static_cast<std::size_t>(1 - chosen)];
  std::size_t f = 0;
  for (std::size_t i = 0; i < 4 && f < 2; ++i) {
    if (refined.edges[i].seen) {
      evidence.seen_faces[f] = face_evidence(refined, i, lidar_xy);
      evidence.seen_faces[f++].residual_spread_m = corrector.face_residual(i);
    }
  }
  evidence.assignment_confidence = out.confidence;
  evidence.alternative_offset = frame.map(other.centre) - centre;
  out.covariance = fix_covariance(evidence, config.covariance);

  // A yaw far outside both its own and the prior's uncertainty: the fitted faces are not the
  // vehicle's outline (a few points of a cabin, an occlusion edge), so the box built on them is not either.
  if (prior && config.strict_consistency_checks) {
    const double sigma = std::sqrt(prior->sigma * prior->sigma + out.covariance(2, 2));
    if (angle_distance(yaw, prior->yaw) >
        std::max(config.max_prior_disagreement_sigmas * sigma, config.min_prior_disagreement_rad)) {
      out = CorrectedPose{};
      out.status = CorrectionStatus::inconsistent_box;
      return out;
    }
  }

  // Where else the box of the chosen assignment could sit, and how likely (same log-odds scale as the
  // assignment): a position the points do not decide is either refused or reported with its spread.
  for (const Hypothesis& alt : all) {
    if (alt.length_axis != h.length_axis || !alt.alternative) {
      continue;
    }
    const Eigen::Vector2d offset = frame.map(alt.centre) - centre;
    if (offset.norm() < config.position_ambiguity_min_m) {
      continue;
    }
    const double p_alt = logistic(-(alt.score - h.score) / config.geometry_scale);
    if (p_alt > config.max_position_ambiguity) {
      out = CorrectedPose{};
      out.status = CorrectionStatus::ambiguous_position;
      return out;
    }
    out.covariance.topLeftCorner<2, 2>() += p_alt * offset * offset.transpose();
  }
  return out;
}

}  // namespace rsu::perception
