// SPDX-License-Identifier: Apache-2.0
#include "eval/corridor/report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <limits>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "common/angles.h"
#include "eval/consistency.h"
#include "sim/trajectory.h"

namespace rsu::eval {
namespace {

// Where a file keeps the position covariance: the NDT and fused files name it sxx, syy (and sxy if
// correlated), the corrections file cxx, cxy, cyy.
struct CovarianceColumns {
  std::optional<std::size_t> xx, xy, yy;
};

// A CSV file with a header row, columns looked up by name.
struct CsvTable {
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;

  std::optional<std::size_t> find(const std::string& name) const {
    const auto it = std::find(header.begin(), header.end(), name);
    return it == header.end() ? std::nullopt : std::optional(static_cast<std::size_t>(it - header.begin()));
  }

  CovarianceColumns covariance() const {
    for (const char* prefix : {"s", "c"}) {
      const std::string p = prefix;
      if (find(p + "xx") && find(p + "yy"))
        return {find(p + "xx"), find(p + "xy"), find(p + "yy")};
    }
    return {};
  }

  std::size_t column(const std::string& name, const std::string& path) const {
    const auto it = std::find(header.begin(), header.end(), name);
    if (it == header.end())
      throw std::runtime_error(path + ": no column \"" + name + "\"");
    return static_cast<std::size_t>(it - header.begin());
  }
};

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream in(line);
  for (std::string cell; std::getline(in, cell, ',');)
    out.push_back(cell);
  return out;
}

CsvTable read_csv(const std::string& path) {
  std::ifstream in(path);
  if (!in)
    throw std::runtime_error(path + ": cannot open");
  CsvTable t;
  std::string line;
  if (!std::getline(in, line))
    throw std::runtime_error(path + ": empty file");
  t.header = split(line);
  while (std::getline(in, line)) {
    if (!line.empty() && line[0] != '#')
      t.rows.push_back(split(line));
  }
  return t;
}

double axis_error_deg(double a, double b) {
  const double d = std::fmod(std::abs(a - b), kPi);
  return rad_to_deg(std::min(d, kPi - d));
}

const sim::Vehicle& vehicle_of(const CorridorExperimentConfig& c) {
  for (const auto& v : c.scenario.scene.vehicles) {
    if (v.id == c.vehicle_id)
      return v;
  }
  throw std::runtime_error("no vehicle");
}

// The true distance from (x, y) to the nearest vehicle of the scenario other than `own` at time t (NaN
// when there is none): a fix nearer another vehicle than its own is that vehicle's.
double nearest_other_m(const sim::Scenario& scenario, std::uint32_t own, double x, double y, TimeNs t) {
  double best = std::numeric_limits<double>::quiet_NaN();
  for (const sim::Vehicle& v : scenario.scene.vehicles) {
    if (v.id == own)
      continue;
    const Pose2 p = sim::pose_at(v.trajectory, t);
    const double d = std::hypot(x - p.x, y - p.y);
    best = std::isnan(best) ? d : std::min(best, d);
  }
  return best;
}

constexpr double kHmiM = 0.30;  // an HMI fix: beyond 3 sigma and more than this off

// epoch_ns: subtracted from the file's times (processes that ran on the host clock, see run_experiment.sh).
std::vector<ScoredEstimate> score_file(const CorridorExperimentConfig& config, const std::string& path,
                                       bool box_yaw, TimeNs epoch_ns) {
  const CsvTable t = read_csv(path);
  const std::size_t ct = t.column("time_ns", path), cx = t.column("x", path), cy = t.column("y", path),
                    cyaw = t.column("yaw", path);
  const sim::Vehicle& vehicle = vehicle_of(config);
  const CovarianceColumns cov = t.covariance();
  // The fused output (rsu-vehicle) has a row after each NDT pose and after each correction: score the
  // ones at the NDT poses' times, so that fused and NDT are compared frame for frame.
  const auto source_it = std::find(t.header.begin(), t.header.end(), "source");
  const auto source_col = static_cast<std::size_t>(source_it - t.header.begin());
  std::vector<ScoredEstimate> out;
  for (const auto& row : t.rows) {
    if (row.size() <= std::max({ct, cx, cy, cyaw}))
      continue;
    if (source_it != t.header.end() && (row.size() <= source_col || row[source_col] != "ndt"))
      continue;
    ScoredEstimate e;
    e.time_ns = std::stoll(row[ct]) - epoch_ns;
    const Pose2 truth = sim::pose_at(vehicle.trajectory, e.time_ns);
    const double x = std::stod(row[cx]), y = std::stod(row[cy]), yaw = std::stod(row[cyaw]);
    e.along_road_m = truth.x - config.scenario.lidar.mount.x;
    e.error_m = std::hypot(x - truth.x, y - truth.y);
    e.yaw_error_deg = box_yaw ? axis_error_deg(yaw, truth.yaw) : rad_to_deg(angle_distance(yaw, truth.yaw));
    if (box_yaw)
      e.nearest_other_m = nearest_other_m(config.scenario, vehicle.id, x, y, e.time_ns);
    e.position_nees = std::numeric_limits<double>::quiet_NaN();
    const auto cell = [&](std::optional<std::size_t> c) {
      return c && *c < row.size() ? std::stod(row[*c]) : 0.0;
    };
    if (cov.xx && cov.yy) {
      Eigen::Matrix2d p;
      p << cell(cov.xx), cell(cov.xy), cell(cov.xy), cell(cov.yy);
      e.position_nees = position_nees(Eigen::Vector2d(x - truth.x, y - truth.y), p);
    }
    out.push_back(e);
  }
  return out;
}

const std::pair<const char*, double> kRanges[] = {{"pm36", 36.0}, {"pm50", 50.0}};

// Compared as the table prints them: live runs differ from one another in the fourth decimal.
bool no_worse_to_the_mm(double a_m, double b_m) {
  return std::round(a_m * 1000.0) <= std::round(b_m * 1000.0);
}

double range_half(const std::string& range) {
  for (const auto& [name, half] : kRanges) {
    if (range == name)
      return half;
  }
  return 0.0;
}

// The paper's Table 2 (mean absolute error, m) for -36..36 m and -50..50 m.
struct PaperRow {
  double ndt, vlp16, vlp32c;
};
constexpr PaperRow kPaper[] = {{0.1927, 0.1724, 0.124}, {0.1704, 0.4596, 0.1167}};

std::string fmt(double v, int precision = 4) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.*f", precision, v);
  return buf;
}

std::string json_number(double v) {
  return std::isfinite(v) ? fmt(v, 6) : std::string("null");
}

std::string percent(double share) {
  return std::isfinite(share) ? fmt(100.0 * share, 1) + " %" : std::string("-");
}

// "rsu_vlp16", "fused_vlp16", ... -> "vlp16", ... in order, once each.
std::vector<std::string> methods_rsu_models(const std::vector<std::string>& methods) {
  std::vector<std::string> models;
  for (const std::string& m : methods) {
    if (m.rfind("rsu_", 0) == 0)
      models.push_back(m.substr(4));
  }
  return models;
}

// The corrections rsu-fleet received for the other connected vehicles (live_rsu.py's format: "correction
// recv_ns vehicle named rsu seq sweep_ns x y yaw points error yaw_error other other_error sigmas"),
// scored against the scenario's truth here, by the same rule as the experiment vehicle's.
void score_fleet(const CorridorExperimentConfig& config, const std::string& path, TimeNs epoch_ns,
                 TrafficScores& traffic) {
  std::ifstream in(path);
  if (!in)
    throw std::runtime_error(path + ": cannot open (the traffic's connected vehicles' corrections)");
  std::vector<double> errors, nees;
  for (std::string line; std::getline(in, line);) {
    std::istringstream words(line);
    std::vector<std::string> w;
    for (std::string word; words >> word;)
      w.push_back(word);
    if (w.size() != 16 || w[0] != "correction")
      continue;
    const auto id = static_cast<std::uint32_t>(std::stoul(w[2]));
    const auto named = static_cast<std::uint32_t>(std::stoul(w[3]));
    const TimeNs t = std::stoll(w[6]) - epoch_ns;
    const double x = std::stod(w[7]), y = std::stod(w[8]), sigmas = std::stod(w[15]);
    const sim::Vehicle* own = nullptr;
    for (const sim::Vehicle& v : config.scenario.scene.vehicles)
      own = v.id == id ? &v : own;
    if (own == nullptr)
      throw std::runtime_error(path + ": a correction for vehicle " + w[2] + ", not in the scenario");
    const Pose2 truth = sim::pose_at(own->trajectory, t);
    const double error = std::hypot(x - truth.x, y - truth.y);
    ++traffic.fleet_corrections;
    traffic.fleet_wrong += named != id || nearest_other_m(config.scenario, id, x, y, t) < error ? 1 : 0;
    traffic.fleet_hmi += sigmas * sigmas > kChi2TwoDof3Sigma && error > kHmiM ? 1 : 0;
    if (std::abs(truth.x - config.scenario.lidar.mount.x) <= 50.0) {
      errors.push_back(error);
      nees.push_back(sigmas >= 0 ? sigmas * sigmas : std::numeric_limits<double>::quiet_NaN());
    }
  }
  traffic.fleet_pm50 = error_stats(errors, nees);
}

}  // namespace

ErrorStats error_stats(const std::vector<double>& errors, const std::vector<double>& nees) {
  ErrorStats s;
  s.count = errors.size();
  s.beyond_3sigma = std::numeric_limits<double>::quiet_NaN();
  if (errors.empty())
    return s;
  std::size_t stated = 0, beyond = 0;
  for (const double n : nees) {
    if (std::isfinite(n)) {
      ++stated;
      beyond += n > kChi2TwoDof3Sigma ? 1 : 0;
    }
  }
  if (stated > 0)
    s.beyond_3sigma = static_cast<double>(beyond) / static_cast<double>(stated);
  std::vector<double> sorted = errors;
  std::sort(sorted.begin(), sorted.end());
  double sum = 0, sum_sq = 0;
  for (double e : sorted) {
    sum += e;
    sum_sq += e * e;
  }
  s.mae_m = sum / static_cast<double>(s.count);
  s.rmse_m = std::sqrt(sum_sq / static_cast<double>(s.count));
  // Nearest-rank 95th percentile.
  const auto rank = static_cast<std::size_t>(std::ceil(0.95 * static_cast<double>(s.count)));
  s.p95_m = sorted[std::min(s.count, std::max<std::size_t>(rank, 1)) - 1];
  s.max_m = sorted.back();
  return s;
}

ExperimentScores score_experiment(const CorridorExperimentConfig& config, const std::string& dir) {
  ExperimentScores scores;
  scores.estimates["ndt"] = score_file(config, dir + "/ndt.csv", false, 0);
  for (const std::string& m : config.rsu_models) {
    // The live run of model m wrote the host-clock time of scenario time 0 into epoch_<m>.txt.
    TimeNs epoch = 0;
    std::ifstream(dir + "/epoch_" + m + ".txt") >> epoch;
    scores.estimates["rsu_" + m] = score_file(config, dir + "/corrections_" + m + ".csv", true, epoch);
    scores.estimates["fused_" + m] = score_file(config, dir + "/fused_" + m + ".csv", false, epoch);
    if (config.scenario.scene.vehicles.size() > 1) {
      TrafficScores& traffic = scores.traffic[m];
      for (const ScoredEstimate& e : scores.estimates["rsu_" + m]) {
        ++traffic.vehicle_corrections;
        traffic.vehicle_wrong += e.nearest_other_m < e.error_m ? 1 : 0;
        traffic.vehicle_hmi += e.position_nees > kChi2TwoDof3Sigma && e.error_m > kHmiM ? 1 : 0;
      }
      if (!config.traffic_connected.empty())
        score_fleet(config, dir + "/fleet_" + m + ".corrections", epoch, traffic);
    }
  }
  for (const auto& [method, estimates] : scores.estimates) {
    for (const auto& [range, half] : kRanges) {
      std::vector<double> errors, nees;
      for (const auto& e : estimates) {
        if (std::abs(e.along_road_m) <= half) {
          errors.push_back(e.error_m);
          nees.push_back(e.position_nees);
        }
      }
      scores.stats[method][range] = error_stats(errors, nees);
    }
  }
  for (const auto& [range, half] : kRanges) {
    std::size_t n = 0;
    for (const auto& e : scores.estimates["ndt"])
      n += std::abs(e.along_road_m) <= half ? 1 : 0;
    scores.frames_in_range[range] = n;
  }
  return scores;
}

// Millimetres: the live run's processes meet on the host clock, so which announcement is the newest when
// a sweep is processed (the correction's yaw prior) varies with scheduling and moves results in the
// fourth decimal; to the millimetre two runs agree.
std::string format_table(const ExperimentScores& scores, const std::vector<std::string>& methods) {
  std::ostringstream out;
  for (const auto& [range, half] : kRanges) {
    out << "range -" << half << " m to " << half << " m along the road (" << scores.frames_in_range.at(range)
        << " frames):\n";
    out << "  method          fixes      MAE m     RMSE m      p95 m      max m  beyond 3 sigma\n";
    for (const std::string& m : methods) {
      const auto it = scores.stats.find(m);
      if (it == scores.stats.end())
        continue;
      const ErrorStats& s = it->second.at(range);
      char line[160];
      std::snprintf(line, sizeof line, "  %-14s %6zu %10s %10s %10s %10s  %13s\n", m.c_str(), s.count,
                    fmt(s.mae_m, 3).c_str(), fmt(s.rmse_m, 3).c_str(), fmt(s.p95_m, 3).c_str(),
                    fmt(s.max_m, 3).c_str(), percent(s.beyond_3sigma).c_str());
      out << line;
    }
  }
  if (!scores.traffic.empty()) {
    out << "traffic: corrections rsud sent, to the WRONG vehicle (nearer another vehicle's truth, or naming "
           "another), HMI (beyond 3 sigma and > 0.30 m off):\n";
    for (const auto& [model, t] : scores.traffic) {
      char line[320];
      std::snprintf(
          line, sizeof line,
          "  %-7s experiment vehicle: %zu corrections, %zu wrong vehicle, %zu HMI; other connected "
          "vehicles: %zu corrections, %zu wrong vehicle, %zu HMI, within +-50 m MAE %s m, max %s m, "
          "beyond 3 sigma %s\n",
          model.c_str(), t.vehicle_corrections, t.vehicle_wrong, t.vehicle_hmi, t.fleet_corrections,
          t.fleet_wrong, t.fleet_hmi, fmt(t.fleet_pm50.mae_m, 3).c_str(), fmt(t.fleet_pm50.max_m, 3).c_str(),
          percent(t.fleet_pm50.beyond_3sigma).c_str());
      out << line;
    }
  }
  return out.str();
}

namespace {

double mean_of(const std::vector<double>& v) {
  double sum = 0;
  for (const double x : v)
    sum += x;
  return v.empty() ? 0.0 : sum / static_cast<double>(v.size());
}

const std::vector<ScoredEstimate>* estimates_of(const ExperimentScores& scores, const std::string& method) {
  const auto it = scores.estimates.find(method);
  return it == scores.estimates.end() ? nullptr : &it->second;
}

// One range cell of one RSU model, frame for frame (FusedGoals).
FusedGoals paired_cell(const std::vector<ScoredEstimate>& ndt, const std::vector<ScoredEstimate>& rsu,
                       const std::vector<ScoredEstimate>& fused, double half_m) {
  std::map<TimeNs, double> ndt_error;
  for (const ScoredEstimate& e : ndt)
    ndt_error[e.time_ns] = e.error_m;
  std::vector<ScoredEstimate> fixes = rsu;
  std::sort(fixes.begin(), fixes.end(), [](const auto& a, const auto& b) { return a.time_ns < b.time_ns; });
  std::vector<double> fused_in, ndt_in, rsu_in, fused_out, ndt_out, fused_all, ndt_all;
  std::optional<TimeNs> previous;
  for (const ScoredEstimate& frame : fused) {
    // The frame period ending at this frame: after the previous frame (the first frame: one period of
    // the next one's length before it, i.e. 100 ms at 10 Hz; taken as the period before the second).
    const TimeNs period_start =
        previous ? *previous : frame.time_ns - (fused.size() > 1 ? fused[1].time_ns - fused[0].time_ns : 0);
    previous = frame.time_ns;
    const auto ndt_it = ndt_error.find(frame.time_ns);
    if (ndt_it == ndt_error.end() || std::abs(frame.along_road_m) > half_m)
      continue;
    // The newest fix swept in (period_start, frame time].
    const auto after = std::upper_bound(fixes.begin(), fixes.end(), frame.time_ns,
                                        [](TimeNs t, const ScoredEstimate& f) { return t < f.time_ns; });
    const bool covered = after != fixes.begin() && std::prev(after)->time_ns > period_start;
    fused_all.push_back(frame.error_m);
    ndt_all.push_back(ndt_it->second);
    (covered ? fused_in : fused_out).push_back(frame.error_m);
    (covered ? ndt_in : ndt_out).push_back(ndt_it->second);
    if (covered)
      rsu_in.push_back(std::prev(after)->error_m);
  }
  FusedGoals g;
  g.covered_frames = fused_in.size();
  g.uncovered_frames = fused_out.size();
  g.fused_mae_m = mean_of(fused_in);
  g.ndt_mae_m = mean_of(ndt_in);
  g.rsu_mae_m = mean_of(rsu_in);
  g.best_mae_m = rsu_in.empty() ? g.ndt_mae_m : std::min(g.ndt_mae_m, g.rsu_mae_m);
  g.reduction_vs_ndt = g.ndt_mae_m > 0 ? 1.0 - g.fused_mae_m / g.ndt_mae_m : 0.0;
  g.fused_uncovered_mae_m = mean_of(fused_out);
  g.ndt_uncovered_mae_m = mean_of(ndt_out);
  g.reduction_vs_ndt_all_frames = mean_of(ndt_all) > 0 ? 1.0 - mean_of(fused_all) / mean_of(ndt_all) : 0.0;
  g.fused_all_mae_m = mean_of(fused_all);
  const auto all = static_cast<double>(std::max<std::size_t>(fused_all.size(), 1));
  g.better_all_mae_m = (static_cast<double>(g.covered_frames) * g.best_mae_m +
                        static_cast<double>(g.uncovered_frames) * g.ndt_uncovered_mae_m) /
                       all;
  return g;
}

}  // namespace

bool FusedGoals::below_ndt_met() const {
  return covered_frames == 0 || reduction_vs_ndt >= 0.8;
}

bool FusedGoals::no_worse_met() const {
  return fused_all_mae_m == 0.0 || no_worse_to_the_mm(fused_all_mae_m, better_all_mae_m);
}

bool FusedGoals::covered_no_worse() const {
  return covered_frames == 0 || no_worse_to_the_mm(fused_mae_m, best_mae_m);
}

bool FusedGoals::uncovered_no_worse() const {
  return uncovered_frames == 0 || no_worse_to_the_mm(fused_uncovered_mae_m, ndt_uncovered_mae_m);
}

std::vector<FusedGoals> fused_goals(const ExperimentScores& scores,
                                    const std::vector<std::string>& rsu_models) {
  std::vector<FusedGoals> out;
  const auto* ndt = estimates_of(scores, "ndt");
  for (const std::string& m : rsu_models) {
    const auto* fused = estimates_of(scores, "fused_" + m);
    const auto* rsu = estimates_of(scores, "rsu_" + m);
    if (fused == nullptr || rsu == nullptr || ndt == nullptr)
      continue;
    for (const auto& [range, half] : kRanges) {
      FusedGoals g = paired_cell(*ndt, *rsu, *fused, half);
      g.rsu_model = m;
      g.range = range;
      out.push_back(g);
    }
  }
  return out;
}

std::string format_paper_comparison(const ExperimentScores& scores,
                                    const std::vector<std::string>& rsu_models) {
  std::ostringstream out;
  out << "MAE (m), the paper's Table 2 beside this run (paper / here):\n";
  out << "  range            NDT self-loc.    RSU VLP-16       RSU VLP-32C      fused VLP-16  fused "
         "VLP-32C\n";
  const auto here = [&](const std::string& method, const char* range) {
    const auto it = scores.stats.find(method);
    return it == scores.stats.end() || it->second.at(range).count == 0 ? std::string("-")
                                                                       : fmt(it->second.at(range).mae_m, 3);
  };
  for (const auto& [range, half] : kRanges) {
    const PaperRow& p = range == std::string("pm36") ? kPaper[0] : kPaper[1];
    char line[200];
    std::snprintf(line, sizeof line,
                  "  -%.0f m to %.0f m   %6.3f / %-6s  %6.3f / %-6s  %6.3f / %-6s  %12s  %13s\n", half, half,
                  p.ndt, here("ndt", range).c_str(), p.vlp16, here("rsu_vlp16", range).c_str(), p.vlp32c,
                  here("rsu_vlp32c", range).c_str(), here("fused_vlp16", range).c_str(),
                  here("fused_vlp32c", range).c_str());
    out << line;
  }
  out << "The vehicle's fused pose against NDT and the RSU on the same frames (MAE; a frame is within the "
         "RSU's coverage when the RSU swept the vehicle in the frame period ending at it and sent a fix;\n"
         "there the RSU's fix of that sweep is compared with the fused pose and NDT at that frame; on the "
         "frames without a fix the better one is NDT):\n";
  for (const FusedGoals& g : fused_goals(scores, rsu_models)) {
    char line[400];
    std::snprintf(
        line, sizeof line,
        "  fused %-7s -%2.0f m to %2.0f m: %zu frames with a fix: %.3f m vs NDT %.3f m (%.1f %% %s, "
        "80 %%: %s), RSU %.3f m; ",
        g.rsu_model.c_str(), range_half(g.range), range_half(g.range), g.covered_frames, g.fused_mae_m,
        g.ndt_mae_m, 100.0 * std::abs(g.reduction_vs_ndt), g.reduction_vs_ndt >= 0 ? "below" : "ABOVE",
        g.below_ndt_met() ? "met" : "MISSED", g.rsu_mae_m);
    out << line;
    if (g.uncovered_frames == 0) {
      out << "no frame without one";
    } else {
      std::snprintf(line, sizeof line, "%zu without: %.3f m vs NDT %.3f m", g.uncovered_frames,
                    g.fused_uncovered_mae_m, g.ndt_uncovered_mae_m);
      out << line;
    }
    std::snprintf(line, sizeof line, "; every frame: %.3f m vs the better's %.3f m: %s\n", g.fused_all_mae_m,
                  g.better_all_mae_m, g.no_worse_met() ? "no worse" : "WORSE");
    out << line;
  }
  return out.str();
}

std::string summary_json(const ExperimentScores& scores, const std::vector<std::string>& methods) {
  std::ostringstream out;
  out << "{\n";
  const char* fields[] = {"mae_m", "rmse_m", "p95_m", "max_m", "count", "position_beyond_3sigma"};
  for (int f = 0; f < 6; ++f) {
    out << "  \"" << fields[f] << "\": {";
    bool first_method = true;
    for (const std::string& m : methods) {
      const auto it = scores.stats.find(m);
      if (it == scores.stats.end())
        continue;
      out << (first_method ? "" : ", ") << '"' << m << "\": {";
      first_method = false;
      bool first_range = true;
      for (const auto& [range, half] : kRanges) {
        const ErrorStats& s = it->second.at(range);
        const double v = f == 0   ? s.mae_m
                         : f == 1 ? s.rmse_m
                         : f == 2 ? s.p95_m
                         : f == 3 ? s.max_m
                         : f == 4 ? static_cast<double>(s.count)
                                  : s.beyond_3sigma;
        out << (first_range ? "" : ", ") << '"' << range << "\": " << (f == 4 ? fmt(v, 0) : json_number(v));
        first_range = false;
      }
      out << "}";
    }
    out << "},\n";
  }
  out << "  \"paper_mae_m\": {\"ndt\": {\"pm36\": " << kPaper[0].ndt << ", \"pm50\": " << kPaper[1].ndt
      << "}, \"rsu_vlp16\": {\"pm36\": " << kPaper[0].vlp16 << ", \"pm50\": " << kPaper[1].vlp16
      << "}, \"rsu_vlp32c\": {\"pm36\": " << kPaper[0].vlp32c << ", \"pm50\": " << kPaper[1].vlp32c
      << "}},\n";
  // Per RSU model and range: the fused pose against NDT and the RSU frame for frame (FusedGoals, report.h).
  out << "  \"fused_goals_definition\": \"frames are the NDT poses; covered: the RSU swept the vehicle in "
         "the "
         "frame period ending at the frame and sent a fix; on covered frames the fused, NDT and RSU (that "
         "fix) "
         "errors are averaged over the same frames: reduction_vs_ndt = 1 - fused / ndt (goal 0.8), "
         "better_of_ndt_and_rsu = min(ndt, rsu); on uncovered frames the better is NDT; "
         "no_worse_than_better_met: the fused MAE over all the range's frames against the better's over the "
         "same frames, to the millimetre\",\n";
  out << "  \"fused_goals\": {";
  std::string model;
  for (const FusedGoals& g : fused_goals(scores, methods_rsu_models(methods))) {
    if (g.rsu_model != model) {
      out << (model.empty() ? "" : "}, ") << "\"fused_" << g.rsu_model << "\": {";
      model = g.rsu_model;
    } else {
      out << ", ";
    }
    out << '"' << g.range << "\": {\"covered_frames\": " << g.covered_frames
        << ", \"fused_mae_m\": " << json_number(g.fused_mae_m)
        << ", \"ndt_mae_m\": " << json_number(g.ndt_mae_m) << ", \"rsu_mae_m\": " << json_number(g.rsu_mae_m)
        << ", \"reduction_vs_ndt\": " << json_number(g.reduction_vs_ndt)
        << ", \"better_of_ndt_and_rsu_mae_m\": " << json_number(g.best_mae_m)
        << ", \"uncovered_frames\": " << g.uncovered_frames
        << ", \"fused_uncovered_mae_m\": " << json_number(g.fused_uncovered_mae_m)
        << ", \"ndt_uncovered_mae_m\": " << json_number(g.ndt_uncovered_mae_m)
        << ", \"reduction_vs_ndt_all_frames\": " << json_number(g.reduction_vs_ndt_all_frames)
        << ", \"fused_all_frames_mae_m\": " << json_number(g.fused_all_mae_m)
        << ", \"better_all_frames_mae_m\": " << json_number(g.better_all_mae_m)
        << ", \"below_ndt_met\": " << (g.below_ndt_met() ? "true" : "false")
        << ", \"no_worse_than_better_met\": " << (g.no_worse_met() ? "true" : "false")
        << ", \"no_worse_on_frames_with_fix\": " << (g.covered_no_worse() ? "true" : "false")
        << ", \"no_worse_than_ndt_without_fix\": " << (g.uncovered_no_worse() ? "true" : "false") << "}";
  }
  out << (model.empty() ? "}" : "}}");
  if (!scores.traffic.empty()) {
    out << ",\n  \"traffic\": {";
    bool first = true;
    for (const auto& [m, t] : scores.traffic) {
      out << (first ? "" : ", ") << '"' << m << "\": {\"vehicle_corrections\": " << t.vehicle_corrections
          << ", \"vehicle_wrong_vehicle\": " << t.vehicle_wrong << ", \"vehicle_hmi\": " << t.vehicle_hmi
          << ", \"fleet_corrections\": " << t.fleet_corrections
          << ", \"fleet_wrong_vehicle\": " << t.fleet_wrong << ", \"fleet_hmi\": " << t.fleet_hmi
          << ", \"fleet_pm50_mae_m\": " << json_number(t.fleet_pm50.mae_m)
          << ", \"fleet_pm50_max_m\": " << json_number(t.fleet_pm50.max_m)
          << ", \"wrong_vehicle\": " << t.vehicle_wrong + t.fleet_wrong << "}";
      first = false;
    }
    out << "}";
  }
  out << "\n}\n";
  return out.str();
}

void write_frames_csv(const ExperimentScores& scores, const std::string& path) {
  std::ofstream out(path);
  if (!out)
    throw std::runtime_error("cannot write " + path);
  out << "method,time_ns,along_road_m,error_m,yaw_error_deg\n";
  for (const auto& [method, estimates] : scores.estimates) {
    for (const auto& e : estimates) {
      out << method << ',' << e.time_ns << ',' << fmt(e.along_road_m, 3) << ',' << fmt(e.error_m, 5) << ','
          << fmt(e.yaw_error_deg, 3) << '\n';
    }
  }
}

}  // namespace rsu::eval
