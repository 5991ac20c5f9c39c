// SPDX-License-Identifier: Apache-2.0
#include "vehicle_client/ndt_csv.h"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <utility>

namespace rsu::vehicle_client {

namespace {

using Column = NdtCsvParser::Column;

constexpr std::array<std::pair<const char*, Column>, 12> kColumnNames = {{
    {"time_ns", Column::kTime},
    {"x", Column::kX},
    {"y", Column::kY},
    {"yaw", Column::kYaw},
    {"sxx", Column::kSxx},
    {"syy", Column::kSyy},
    {"syaw", Column::kSyaw},
    {"converged", Column::kConverged},
    {"iterations", Column::kIterations},
    {"fitness", Column::kFitness},
    {"degeneracy", Column::kDegeneracy},
    {"weak_axis", Column::kWeakAxis},
}};

const char* name_of(Column column) {
  for (const auto& [name, c] : kColumnNames) {
    if (c == column) {
      return name;
    }
  }
  return "?";
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) {
    s.remove_prefix(1);
  }
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) {
    s.remove_suffix(1);
  }
  return s;
}

std::vector<std::string_view> split_fields(std::string_view line) {
  std::vector<std::string_view> fields;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = line.find(',', start);
    fields.push_back(
        trim(line.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start)));
    if (comma == std::string_view::npos) {
      return fields;
    }
    start = comma + 1;
  }
}

// Parses the whole field as T, or nothing.
template <typename T>
std::optional<T> parse_number(std::string_view field) {
  T value{};
  if (!field.empty() && field.front() == '+') {
    field.remove_prefix(1);  // from_chars refuses a leading '+'
  }
  const char* end = field.data() + field.size();
  const auto [ptr, ec] = std::from_chars(field.data(), end, value);
  if (field.empty() || ec != std::errc() || ptr != end) {
    return std::nullopt;
  }
  return value;
}

}  // namespace

NdtCsvError::NdtCsvError(std::size_t line, const std::string& what)
    : std::runtime_error("line " + std::to_string(line) + ": " + what), line_(line) {}

bool NdtCsvParser::has_variances() const {
  return std::find(columns_.begin(), columns_.end(), Column::kSxx) != columns_.end();
}

void NdtCsvParser::parse_header(const std::vector<std::string_view>& fields, std::string_view line) {
  std::vector<Column> columns;
  for (std::size_t i = 0; i < fields.size(); ++i) {
    const auto known = std::find_if(kColumnNames.begin(), kColumnNames.end(),
                                    [&](const auto& entry) { return fields[i] == entry.first; });
    const bool in_place = known != kColumnNames.end() && (i >= 4 || known->second == static_cast<Column>(i));
    if (!in_place || (i >= 4 && static_cast<int>(known->second) < 4)) {
      throw NdtCsvError(line_number_,
                        "expected a header \"time_ns,x,y,yaw\" followed by any of sxx,syy,syaw (all three), "
                        "converged, iterations, fitness, degeneracy, weak_axis; got \"" +
                            std::string(line) + "\"");
    }
    if (std::find(columns.begin(), columns.end(), known->second) != columns.end()) {
      throw NdtCsvError(line_number_, "column \"" + std::string(fields[i]) + "\" appears twice");
    }
    columns.push_back(known->second);
  }
  const auto count = [&](Column c) { return std::count(columns.begin(), columns.end(), c); };
  if (columns.size() < 4 || count(Column::kSxx) != count(Column::kSyy) ||
      count(Column::kSxx) != count(Column::kSyaw)) {
    throw NdtCsvError(line_number_,
                      "the header needs time_ns,x,y,yaw first and sxx,syy,syaw all three or none; got \"" +
                          std::string(line) + "\"");
  }
  columns_ = std::move(columns);
}

void NdtCsvParser::parse_field(Column column, std::string_view field, NdtPoseRow& row,
                               double& variance) const {
  const std::string name = name_of(column);
  if (column == Column::kTime) {
    const auto time = parse_number<TimeNs>(field);
    if (!time) {
      throw NdtCsvError(line_number_, "time_ns \"" + std::string(field) + "\" is not an integer (ns)");
    }
    row.time = *time;
    return;
  }
  if (column == Column::kConverged || column == Column::kIterations) {
    const auto value = parse_number<int>(field);
    if (!value || *value < 0 || (column == Column::kConverged && *value > 1)) {
      throw NdtCsvError(line_number_, name + " \"" + std::string(field) + "\" is not " +
                                          (column == Column::kConverged ? "0 or 1" : "a count"));
    }
    if (column == Column::kConverged) {
      row.quality.converged = *value == 1;
    } else {
      row.quality.iterations = *value;
    }
    return;
  }
  const auto value = parse_number<double>(field);
  // A degeneracy may be infinite (no curvature at all along some direction); everything else is finite.
  if (!value || std::isnan(*value) || (!std::isfinite(*value) && column != Column::kDegeneracy)) {
    throw NdtCsvError(line_number_, name + " \"" + std::string(field) + "\" is not a finite number");
  }
  switch (column) {
    case Column::kX:
      row.pose.x = *value;
      return;
    case Column::kY:
      row.pose.y = *value;
      return;
    case Column::kYaw:
      row.pose.yaw = *value;
      return;
    case Column::kFitness:
      if (*value < 0.0) {
        throw NdtCsvError(line_number_, "fitness must not be negative, got " + std::string(field));
      }
      row.quality.fitness_m2 = *value;
      return;
    case Column::kDegeneracy:
      if (!(*value >= 1.0)) {
        throw NdtCsvError(line_number_, "degeneracy must be at least 1, got " + std::string(field));
      }
      row.quality.degeneracy = *value;
      return;
    case Column::kWeakAxis:
      row.quality.weak_axis_rad = *value;
      return;
    default:
      if (!(*value > 0.0)) {
        throw NdtCsvError(line_number_, name + " must be a positive variance, got " + std::string(field));
      }
      variance = *value;
      return;
  }
}

std::optional<NdtPoseRow> NdtCsvParser::parse_line(std::string_view raw) {
  ++line_number_;
  const std::string_view line = trim(raw);
  if (line.empty() || line.front() == '#') {
    return std::nullopt;
  }
  const std::vector<std::string_view> fields = split_fields(line);
  if (columns_.empty()) {
    parse_header(fields, line);
    return std::nullopt;
  }
  if (fields.size() != columns_.size()) {
    throw NdtCsvError(line_number_, "expected " + std::to_string(columns_.size()) +
                                        " comma-separated fields, got " + std::to_string(fields.size()));
  }
  NdtPoseRow row;
  Eigen::Vector3d variances = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < fields.size(); ++i) {
    const Column column = columns_[i];
    double variance = 0.0;
    parse_field(column, fields[i], row, variance);
    if (column == Column::kSxx || column == Column::kSyy || column == Column::kSyaw) {
      variances[static_cast<int>(column) - static_cast<int>(Column::kSxx)] = variance;
    }
  }
  if (has_variances()) {
    row.variances = variances;
  }
  return row;
}

}  // namespace rsu::vehicle_client
