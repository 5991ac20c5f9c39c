// SPDX-License-Identifier: Apache-2.0
#include "eval/pilot/pilot_matrix.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace rsu::eval {
namespace {

std::string folder_name(const std::string& model, double mount_m, const std::string& vehicle) {
  char mount[32];
  std::snprintf(mount, sizeof mount, "%gm", mount_m);
  return model + "_" + mount + "_" + vehicle;
}

MatrixRow summarize_row(const PilotResult& result, const std::string& folder) {
  MatrixRow row;
  row.model = result.config.model_name;
  row.mount_m = result.config.lidar_height_m;
  row.vehicle = result.config.vehicle_name;
  row.folder = folder;
  row.improved = summarize(result, PilotMethod::improved);
  for (const BandConsistency& b : consistency_bands(result, PilotMethod::improved)) {
    if (b.consistency.fixes < 20)
      continue;
    row.worst_band_position = std::max(row.worst_band_position, b.consistency.position_beyond_3sigma);
    row.worst_band_yaw = std::max(row.worst_band_yaw, b.consistency.yaw_beyond_3sigma);
  }
  double points = 0;
  int n = 0;
  for (const PilotCell& c : result.cells) {
    if (c.distance_m >= kClaimFromM - 1e-9 && c.distance_m <= kClaimToM + 1e-9) {
      points += static_cast<double>(c.points);
      ++n;
    }
  }
  row.mean_points_6_36m = n > 0 ? points / n : 0.0;
  row.wall_seconds = result.wall_seconds;
  return row;
}

std::string percent(double share) {
  if (!std::isfinite(share))
    return "-";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f %%", 100.0 * share);
  return buf;
}

std::string metres(double v) {
  if (!std::isfinite(v))
    return "-";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3f", v);
  return buf;
}

}  // namespace

std::vector<MatrixRow> run_matrix(const MatrixConfig& config, const std::string& out,
                                  const std::function<void(const MatrixRow&)>& progress) {
  if (config.mounts_m.empty() || config.models.empty() || config.vehicles.empty())
    throw std::invalid_argument("pilot matrix: need at least one mount, one LiDAR model and one vehicle");
  std::vector<MatrixRow> rows;
  for (const std::string& model : config.models) {
    for (const double mount : config.mounts_m) {
      for (const sim::NamedVehicleShape& vehicle : config.vehicles) {
        PilotConfig c = config.base;
        c.model_name = model;
        c.lidar_height_m = mount;
        c.vehicle = vehicle.shape;
        c.vehicle_name = vehicle.name;
        const PilotResult result = run_pilot(c);
        const std::string folder = folder_name(model, mount, vehicle.name);
        const std::filesystem::path dir = std::filesystem::path(out) / folder;
        std::filesystem::create_directories(dir);
        write_cells_csv(result, (dir / "cells.csv").string(), false);
        std::ofstream((dir / "summary.json").string())
            << "{\n  \"" << model << "\": " << summary_json_entry(result) << "\n}\n";
        rows.push_back(summarize_row(result, folder));
        if (progress)
          progress(rows.back());
      }
    }
  }
  return rows;
}

std::string matrix_markdown(const std::vector<MatrixRow>& rows) {
  std::ostringstream out;
  out << "| LiDAR | mount | vehicle | mean points 6-36 m | < 0.10 m, 6-36 m | < 0.10 m, >= 30 points | p95 "
         "6-36 m "
         "| off-by-90 | no fix | withheld, >= 30 points | beyond 3 sigma position / yaw | worst 5 m band "
         "position / yaw | HMI | outline seen, >= 30 points | < 0.10 m where seen |\n";
  out << "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const MatrixRow& r : rows) {
    const MethodSummary& s = r.improved;
    char mount[32];
    std::snprintf(mount, sizeof mount, "%g m", r.mount_m);
    out << "| " << r.model << " | " << mount << " | " << r.vehicle << " | "
        << std::lround(r.mean_points_6_36m) << " | " << percent(s.share_below_0p10_6_36m) << " | "
        << percent(s.share_below_0p10_6_36m_30pts) << " | " << metres(s.p95_error_6_36m) << " | "
        << s.off_by_90_cells << " | " << s.no_fit_cells << " | " << percent(s.withheld_6_36m_30pts) << " | "
        << percent(s.beyond_3sigma_position) << " / " << percent(s.beyond_3sigma_yaw) << " | "
        << percent(r.worst_band_position) << " / " << percent(r.worst_band_yaw) << " | " << s.hmi_fixes
        << " | " << percent(s.outline_seen_6_36m_30pts) << " | " << percent(s.share_below_0p10_outline_seen)
        << " |\n";
  }
  return out.str();
}

void write_matrix_csv(const std::vector<MatrixRow>& rows, const std::string& path) {
  std::ofstream out(path);
  if (!out)
    throw std::runtime_error("cannot write " + path);
  out << "model,mount_m,vehicle,folder,mean_points_6_36m,cells_6_36m,share_below_0p10_6_36m,cells_6_36m_"
         "30pts,"
         "share_below_0p10_6_36m_30pts,p95_error_6_36m,off_by_90_cells,no_fit_cells,withheld_6_36m_30pts,"
         "fixes_6_36m,beyond_3sigma_position,beyond_3sigma_yaw,worst_band_position,worst_band_yaw,hmi_fixes,"
         "outline_seen_6_36m_30pts,share_below_0p10_outline_seen,wall_seconds\n";
  for (const MatrixRow& r : rows) {
    const MethodSummary& s = r.improved;
    out << r.model << ',' << r.mount_m << ',' << r.vehicle << ',' << r.folder << ',' << r.mean_points_6_36m
        << ',' << s.cells_6_36m << ',' << s.share_below_0p10_6_36m << ',' << s.cells_6_36m_30pts << ','
        << s.share_below_0p10_6_36m_30pts << ',' << s.p95_error_6_36m << ',' << s.off_by_90_cells << ','
        << s.no_fit_cells << ',' << s.withheld_6_36m_30pts << ',' << s.fixes_6_36m << ','
        << s.beyond_3sigma_position << ',' << s.beyond_3sigma_yaw << ',' << r.worst_band_position << ','
        << r.worst_band_yaw << ',' << s.hmi_fixes << ',' << s.outline_seen_6_36m_30pts << ','
        << s.share_below_0p10_outline_seen << ',' << r.wall_seconds << '\n';
  }
}

}  // namespace rsu::eval
