// SPDX-License-Identifier: Apache-2.0
#include "eval/pilot/pilot_summary.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace rsu::eval {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

double percentile(std::vector<double> v, double q) {
  if (v.empty())
    return kNaN;
  std::sort(v.begin(), v.end());
  const double pos = q * static_cast<double>(v.size() - 1);
  const auto lo = static_cast<std::size_t>(std::floor(pos));
  const auto hi = std::min(lo + 1, v.size() - 1);
  return v[lo] + (v[hi] - v[lo]) * (pos - static_cast<double>(lo));
}

std::string number(double v) {
  if (!std::isfinite(v))
    return "null";
  std::ostringstream out;
  out.precision(6);
  out << v;
  return out.str();
}

bool in_claim_range(const PilotCell& c) {
  return c.distance_m >= kClaimFromM - 1e-9 && c.distance_m <= kClaimToM + 1e-9;
}

bool has_covariance(const MethodCell& m) {
  return m.fixed() && std::isfinite(m.position_nees) && std::isfinite(m.yaw_sigma_deg);
}

bool position_beyond(const MethodCell& m) {
  return m.position_nees > kChi2TwoDof3Sigma;
}
bool yaw_beyond(const MethodCell& m) {
  return m.yaw_err_deg > 3.0 * m.yaw_sigma_deg;
}
bool hazardously_misleading(const MethodCell& m) {
  return position_beyond(m) && m.center_err_m > kHmiErrorM;
}

template <typename Keep>
ConsistencySummary consistency_of(const PilotResult& result, PilotMethod method, Keep keep) {
  ConsistencySummary s;
  int yaw_count = 0, position_count = 0;
  for (const PilotCell& c : result.cells) {
    const MethodCell& m = c.of(method);
    if (!keep(c) || !has_covariance(m))
      continue;
    ++s.fixes;
    s.mean_yaw_sigma_deg += m.yaw_sigma_deg;
    s.mean_position_sigma_m += m.sigma_m;
    yaw_count += yaw_beyond(m);
    position_count += position_beyond(m);
    s.hmi_fixes += hazardously_misleading(m);
  }
  if (s.fixes == 0) {
    s.mean_yaw_sigma_deg = s.mean_position_sigma_m = s.yaw_beyond_3sigma = s.position_beyond_3sigma = kNaN;
    return s;
  }
  const double n = s.fixes;
  s.mean_yaw_sigma_deg /= n;
  s.mean_position_sigma_m /= n;
  s.yaw_beyond_3sigma = yaw_count / n;
  s.position_beyond_3sigma = position_count / n;
  return s;
}

std::string consistency_json(const ConsistencySummary& k) {
  std::ostringstream out;
  out << "{\"fixes\": " << k.fixes << ", \"mean_yaw_sigma_deg\": " << number(k.mean_yaw_sigma_deg)
      << ", \"yaw_beyond_3sigma\": " << number(k.yaw_beyond_3sigma)
      << ", \"mean_position_sigma_m\": " << number(k.mean_position_sigma_m)
      << ", \"position_beyond_3sigma\": " << number(k.position_beyond_3sigma)
      << ", \"hmi_fixes\": " << k.hmi_fixes << "}";
  return out.str();
}

std::string method_json(const MethodSummary& s) {
  std::ostringstream out;
  out << "{\"share_below_0p10_6_36m\": " << number(s.share_below_0p10_6_36m)
      << ", \"cells_6_36m\": " << s.cells_6_36m
      << ", \"share_below_0p10_6_36m_30pts\": " << number(s.share_below_0p10_6_36m_30pts)
      << ", \"cells_6_36m_30pts\": " << s.cells_6_36m_30pts
      << ", \"withheld_6_36m_30pts\": " << number(s.withheld_6_36m_30pts)
      << ", \"outline_seen_6_36m_30pts\": " << number(s.outline_seen_6_36m_30pts)
      << ", \"share_below_0p10_outline_seen\": " << number(s.share_below_0p10_outline_seen)
      << ", \"off_by_90_cells\": " << s.off_by_90_cells
      << ", \"median_error_m\": " << number(s.median_error_m)
      << ", \"p95_error_m\": " << number(s.p95_error_m)
      << ", \"p95_error_6_36m\": " << number(s.p95_error_6_36m) << ", \"no_fit_cells\": " << s.no_fit_cells
      << ", \"fixes_6_36m\": " << s.fixes_6_36m
      << ", \"beyond_3sigma_position\": " << number(s.beyond_3sigma_position)
      << ", \"beyond_3sigma_yaw\": " << number(s.beyond_3sigma_yaw)
      << ", \"mean_sigma_m\": " << number(s.mean_sigma_m)
      << ", \"mean_yaw_sigma_deg\": " << number(s.mean_yaw_sigma_deg) << ", \"hmi_fixes\": " << s.hmi_fixes
      << "}";
  return out.str();
}

}  // namespace

MethodSummary summarize(const PilotResult& result, PilotMethod method) {
  MethodSummary s;
  std::vector<double> errors, errors_claim;
  int below = 0, below_dense = 0, withheld_dense = 0, seen_dense = 0, below_seen = 0;
  for (const PilotCell& c : result.cells) {
    const MethodCell& m = c.of(method);
    const bool fixed = m.fixed() && std::isfinite(m.center_err_m);
    if (fixed) {
      errors.push_back(m.center_err_m);
    } else {
      ++s.no_fit_cells;
    }
    if (fixed && m.yaw_err_deg > 45.0)
      ++s.off_by_90_cells;
    if (!in_claim_range(c))
      continue;
    const bool good = fixed && m.center_err_m < 0.10;
    ++s.cells_6_36m;
    below += good;
    if (fixed)
      errors_claim.push_back(m.center_err_m);
    if (c.points >= kDensePoints) {
      ++s.cells_6_36m_30pts;
      below_dense += good;
      withheld_dense += !fixed;
      seen_dense += c.outline_seen;
      below_seen += c.outline_seen && good;
    }
  }
  s.share_below_0p10_6_36m = s.cells_6_36m > 0 ? static_cast<double>(below) / s.cells_6_36m : kNaN;
  s.share_below_0p10_6_36m_30pts =
      s.cells_6_36m_30pts > 0 ? static_cast<double>(below_dense) / s.cells_6_36m_30pts : kNaN;
  s.withheld_6_36m_30pts =
      s.cells_6_36m_30pts > 0 ? static_cast<double>(withheld_dense) / s.cells_6_36m_30pts : kNaN;
  s.outline_seen_6_36m_30pts =
      s.cells_6_36m_30pts > 0 ? static_cast<double>(seen_dense) / s.cells_6_36m_30pts : kNaN;
  s.share_below_0p10_outline_seen = seen_dense > 0 ? static_cast<double>(below_seen) / seen_dense : kNaN;
  s.median_error_m = percentile(errors, 0.5);
  s.p95_error_m = percentile(errors, 0.95);
  s.p95_error_6_36m = percentile(errors_claim, 0.95);

  const ConsistencySummary claim = consistency_of(result, method, in_claim_range);
  const ConsistencySummary all = consistency_of(result, method, [](const PilotCell&) { return true; });
  s.fixes_6_36m = claim.fixes;
  s.beyond_3sigma_position = claim.position_beyond_3sigma;
  s.beyond_3sigma_yaw = claim.yaw_beyond_3sigma;
  s.mean_sigma_m = claim.mean_position_sigma_m;
  s.mean_yaw_sigma_deg = claim.mean_yaw_sigma_deg;
  s.hmi_fixes = all.hmi_fixes;
  return s;
}

ConsistencySummary summarize_consistency(const PilotResult& result, PilotMethod method) {
  return consistency_of(result, method, [](const PilotCell&) { return true; });
}

std::vector<BandConsistency> consistency_bands(const PilotResult& result, PilotMethod method, double band_m) {
  std::vector<BandConsistency> bands;
  if (result.distances.empty() || !(band_m > 0))
    return bands;
  const double first = std::floor(result.distances.front() / band_m) * band_m;
  for (double from = first; from <= result.distances.back() + 1e-9; from += band_m) {
    BandConsistency b;
    b.from_m = from;
    b.to_m = from + band_m;
    b.consistency = consistency_of(result, method, [&](const PilotCell& c) {
      return c.distance_m >= b.from_m - 1e-9 && c.distance_m < b.to_m - 1e-9;
    });
    bands.push_back(b);
  }
  return bands;
}

PilotResult up_to(const PilotResult& result, double distance_max_m) {
  PilotResult out = result;
  out.cells.clear();
  for (const PilotCell& c : result.cells) {
    if (c.distance_m <= distance_max_m + 1e-9)
      out.cells.push_back(c);
  }
  return out;
}

void write_cells_csv(const PilotResult& result, const std::string& path, bool append) {
  std::ofstream out(path, append ? std::ios::app : std::ios::trunc);
  if (!out)
    throw std::runtime_error("cannot write " + path);
  const auto prefix = [](PilotMethod m) {
    return m == PilotMethod::algorithm1 ? std::string("alg1") : std::string(to_string(m));
  };
  if (!append) {
    out << "model,lidar_height_m,vehicle,distance_m,frame,yaw_deg,sweep_ns,points,fit_ok,area_err_m2";
    for (const PilotMethod m : kPilotMethods) {
      const std::string p = prefix(m);
      out << ',' << p << "_center_err_m," << p << "_yaw_err_deg," << p << "_sigma_m," << p
          << "_yaw_sigma_deg," << p << "_position_nees," << p << "_status";
    }
    out << ",improved_resolution,outline_seen\n";
  }
  for (const PilotCell& c : result.cells) {
    out << result.config.model_name << ',' << result.config.lidar_height_m << ','
        << result.config.vehicle_name << ',' << c.distance_m << ',' << c.frame_in_turn << ','
        << number(c.yaw_deg) << ',' << c.sweep_ns << ',' << c.points << ',' << (c.fit_ok ? 1 : 0) << ','
        << number(c.area_err_m2);
    for (const PilotMethod m : kPilotMethods) {
      const MethodCell& r = c.of(m);
      out << ',' << number(r.center_err_m) << ',' << number(r.yaw_err_deg) << ',' << number(r.sigma_m) << ','
          << number(r.yaw_sigma_deg) << ',' << number(r.position_nees) << ',' << r.status;
    }
    out << ',' << c.improved_resolution << ',' << (c.outline_seen ? 1 : 0) << '\n';
  }
}

std::string summary_json_entry(const PilotResult& result) {
  std::ostringstream out;
  out << "{\"lidar_height_m\": " << number(result.config.lidar_height_m) << ", \"vehicle\": \""
      << result.config.vehicle_name << "\", \"vehicle_size_m\": [" << number(result.config.vehicle.length)
      << ", " << number(result.config.vehicle.width) << ", " << number(result.config.vehicle.height) << "]";
  for (const PilotMethod m : kPilotMethods)
    out << ", \"" << to_string(m) << "\": " << method_json(summarize(result, m));
  out << ", \"consistency\": " << consistency_json(summarize_consistency(result));
  out << ", \"bands\": {";
  bool first_method = true;
  for (const PilotMethod m : {PilotMethod::algorithm1, PilotMethod::improved}) {
    out << (first_method ? "" : ", ") << '"' << to_string(m) << "\": [";
    first_method = false;
    bool first = true;
    for (const BandConsistency& b : consistency_bands(result, m)) {
      out << (first ? "" : ", ") << "{\"from_m\": " << number(b.from_m) << ", \"to_m\": " << number(b.to_m)
          << ", \"consistency\": " << consistency_json(b.consistency) << "}";
      first = false;
    }
    out << "]";
  }
  out << "}, \"skipped_distances_m\": [";
  for (std::size_t i = 0; i < result.skipped_distances.size(); ++i)
    out << (i ? ", " : "") << number(result.skipped_distances[i]);
  out << "], \"cells\": " << result.cells.size() << ", \"frames_per_turn\": " << result.frames_per_turn
      << ", \"rays_cast\": " << result.rays_cast << ", \"wall_seconds\": " << number(result.wall_seconds)
      << "}";
  return out.str();
}

}  // namespace rsu::eval
