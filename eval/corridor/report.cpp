#include "eval/corridor/report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "common/angles.h"
#include "sim/trajectory.h"

namespace rsu::eval {
namespace {

// A CSV file with a header row, columns looked up by name.
struct CsvTable {
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;

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

// epoch_ns: subtracted from the file's times (processes that ran on the host clock, see run_experiment.sh).
std::vector<ScoredEstimate> score_file(const CorridorExperimentConfig& config, const std::string& path,
                                       bool box_yaw, TimeNs epoch_ns) {
  const CsvTable t = read_csv(path);
  const std::size_t ct = t.column("time_ns", path), cx = t.column("x", path), cy = t.column("y", path),
                    cyaw = t.column("yaw", path);
  const sim::Vehicle& vehicle = vehicle_of(config);
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
    out.push_back(e);
  }
  return out;
}

const std::pair<const char*, double> kRanges[] = {{"pm36", 36.0}, {"pm50", 50.0}};

std::string fmt(double v, int precision = 4) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.*f", precision, v);
  return buf;
}

}  // namespace

ErrorStats error_stats(const std::vector<double>& errors) {
  ErrorStats s;
  s.count = errors.size();
  if (errors.empty())
    return s;
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
  }
  for (const auto& [method, estimates] : scores.estimates) {
    for (const auto& [range, half] : kRanges) {
      std::vector<double> errors;
      for (const auto& e : estimates) {
        if (std::abs(e.along_road_m) <= half)
          errors.push_back(e.error_m);
      }
      scores.stats[method][range] = error_stats(errors);
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
    out << "  method          fixes      MAE m     RMSE m      p95 m      max m\n";
    for (const std::string& m : methods) {
      const auto it = scores.stats.find(m);
      if (it == scores.stats.end())
        continue;
      const ErrorStats& s = it->second.at(range);
      char line[160];
      std::snprintf(line, sizeof line, "  %-14s %6zu %10s %10s %10s %10s\n", m.c_str(), s.count,
                    fmt(s.mae_m, 3).c_str(), fmt(s.rmse_m, 3).c_str(), fmt(s.p95_m, 3).c_str(),
                    fmt(s.max_m, 3).c_str());
      out << line;
    }
  }
  return out.str();
}

std::string summary_json(const ExperimentScores& scores, const std::vector<std::string>& methods) {
  std::ostringstream out;
  out << "{\n";
  const char* fields[] = {"mae_m", "rmse_m", "p95_m", "max_m", "count"};
  for (int f = 0; f < 5; ++f) {
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
                                  : static_cast<double>(s.count);
        out << (first_range ? "" : ", ") << '"' << range << "\": " << (f == 4 ? fmt(v, 0) : fmt(v, 6));
        first_range = false;
      }
      out << "}";
    }
    out << "}" << (f < 4 ? "," : "") << "\n";
  }
  out << "}\n";
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
