// SPDX-License-Identifier: Apache-2.0
#include "perception/face_traces.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace rsu::perception {

double median_in_place(std::vector<double>& v) {
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

double spread_length(std::span<const double> along) {
  if (along.size() < 2)
    return 0.0;
  double mean = 0.0;
  for (const double s : along)
    mean += s;
  mean /= static_cast<double>(along.size());
  double sum_sq = 0.0;
  for (const double s : along)
    sum_sq += (s - mean) * (s - mean);
  return std::sqrt(12.0 * sum_sq / static_cast<double>(along.size()));
}

double least_squares_slope(std::span<const double> s, std::span<const double> n) {
  if (s.size() < 2)
    return 0.0;
  double ms = 0.0, mn = 0.0;
  for (std::size_t i = 0; i < s.size(); ++i) {
    ms += s[i];
    mn += n[i];
  }
  ms /= static_cast<double>(s.size());
  mn /= static_cast<double>(s.size());
  double sss = 0.0, ssn = 0.0;
  for (std::size_t i = 0; i < s.size(); ++i) {
    sss += (s[i] - ms) * (s[i] - ms);
    ssn += (s[i] - ms) * (n[i] - mn);
  }
  return sss > 0.0 ? ssn / sss : 0.0;
}

std::vector<TracePoint> traces_near(std::span<const Eigen::Vector3d> points,
                                    std::span<const std::size_t> ranks, const FaceLine& edge, double depth) {
  std::vector<TracePoint> near;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector2d r = points[i].head<2>() - edge.a;
    const double s = r.dot(edge.t);
    const double n = r.x() * edge.t.y() - r.y() * edge.t.x();
    if (ranks[i] == LaserLookup::kNone || s < -edge.band || s > edge.length + edge.band ||
        std::abs(n) > depth)
      continue;
    near.push_back({s, n, points[i].z(), ranks[i], i});
  }
  return near;
}

std::vector<SpanTrace> span_traces(const std::vector<TracePoint>& near, std::size_t lasers,
                                   const FaceLine& edge, double ground_z, double max_height) {
  std::vector<SpanTrace> traces(lasers);
  for (const TracePoint& p : near) {
    if (p.along < edge.band || p.along > edge.length - edge.band || p.z - ground_z > max_height)
      continue;
    SpanTrace& trace = traces[p.laser];
    trace.along.push_back(p.along);
    trace.across.push_back(p.across);
    trace.in_band += std::abs(p.across) <= edge.band ? 1U : 0U;
  }
  return traces;
}

double crossing_trace_departure(const std::vector<SpanTrace>& traces, double length, double collinear_m) {
  double departure = 0.0;
  for (const SpanTrace& trace : traces) {
    const std::size_t off_band = trace.along.size() - trace.in_band;
    if (trace.in_band == 0 || off_band <= 3 * trace.in_band || off_band < 3)
      continue;
    const double k = least_squares_slope(trace.along, trace.across);
    std::vector<double> offset;
    offset.reserve(trace.along.size());
    for (std::size_t i = 0; i < trace.along.size(); ++i)
      offset.push_back(trace.across[i] - k * trace.along[i]);
    const double centre = median_in_place(offset);
    for (double& x : offset)  // now the residuals (median_in_place only reordered them)
      x = std::abs(x - centre);
    if (median_in_place(offset) <= collinear_m)
      departure = std::max(departure, 0.5 * std::abs(k) * length);
  }
  return departure;
}

TraceRuns trace_runs(const std::vector<TracePoint>& near, std::size_t lasers, const FaceLine& edge) {
  TraceRuns runs{std::vector<std::size_t>(near.size(), LaserLookup::kNone), {}};
  // Each laser's current run, while its last return was in the band.
  std::vector<std::size_t> open(lasers, LaserLookup::kNone);
  for (std::size_t i = 0; i < near.size(); ++i) {
    std::size_t& current = open[near[i].laser];
    if (std::abs(near[i].across) > edge.band) {
      current = LaserLookup::kNone;
      continue;
    }
    if (current == LaserLookup::kNone) {
      current = runs.size.size();
      runs.size.push_back(0);
    }
    runs.run[i] = current;
    ++runs.size[current];
  }
  return runs;
}

std::vector<bool> crossing_returns(const std::vector<TracePoint>& near, const TraceRuns& runs,
                                   std::size_t count, std::size_t min_points) {
  std::vector<bool> crossing(count, false);
  for (std::size_t i = 0; i < near.size(); ++i) {
    if (runs.run[i] != LaserLookup::kNone && runs.size[runs.run[i]] < min_points)
      crossing[near[i].index] = true;
  }
  return crossing;
}

double run_tilt_departure(const std::vector<TracePoint>& near, const TraceRuns& runs, double length,
                          double noise_sigma, std::size_t min_points) {
  // The returns grouped by run, each run's in the order they came (a counting sort).
  std::vector<std::size_t> first(runs.size.size() + 1, 0);
  for (std::size_t r = 0; r < runs.size.size(); ++r)
    first[r + 1] = first[r] + runs.size[r];
  std::vector<std::size_t> grouped(first.back());
  std::vector<std::size_t> next(first.begin(), first.end() - 1);
  for (std::size_t i = 0; i < near.size(); ++i) {
    if (runs.run[i] != LaserLookup::kNone)
      grouped[next[runs.run[i]]++] = i;
  }
  double tilt = 0.0;
  std::vector<double> along, across;
  for (std::size_t r = 0; r < runs.size.size(); ++r) {
    if (runs.size[r] < min_points)
      continue;
    along.clear();
    across.clear();
    for (std::size_t k = first[r]; k < first[r + 1]; ++k) {
      along.push_back(near[grouped[k]].along);
      across.push_back(near[grouped[k]].across);
    }
    const double extent = spread_length(along);
    if (!(extent > 0.0))
      continue;
    const double error = noise_sigma * std::sqrt(12.0 / static_cast<double>(along.size())) / extent;
    tilt = std::max(tilt, std::abs(least_squares_slope(along, across)) - 2.0 * error);
  }
  return 0.5 * length * tilt;
}

}  // namespace rsu::perception
