#include "vehicle_client/ndt_csv.h"

#include <charconv>
#include <cmath>
#include <vector>

namespace rsu::vehicle_client {

namespace {

constexpr const char* kShortHeader = "time_ns,x,y,yaw";
constexpr const char* kLongHeader = "time_ns,x,y,yaw,sxx,syy,syaw";

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

std::optional<NdtPoseRow> NdtCsvParser::parse_line(std::string_view raw) {
  ++line_number_;
  const std::string_view line = trim(raw);
  if (line.empty() || line.front() == '#') {
    return std::nullopt;
  }
  const std::vector<std::string_view> fields = split_fields(line);
  if (columns_ == 0) {
    std::string header;
    for (std::size_t i = 0; i < fields.size(); ++i) {
      if (i > 0) {
        header += ',';
      }
      header.append(fields[i]);
    }
    if (header == kShortHeader || header == kLongHeader) {
      columns_ = fields.size();
      return std::nullopt;
    }
    throw NdtCsvError(line_number_, "expected the header \"" + std::string(kShortHeader) + "\" or \"" +
                                        kLongHeader + "\", got \"" + std::string(line) + "\"");
  }
  if (fields.size() != columns_) {
    throw NdtCsvError(line_number_, "expected " + std::to_string(columns_) + " comma-separated fields, got " +
                                        std::to_string(fields.size()));
  }
  NdtPoseRow row;
  const auto time = parse_number<TimeNs>(fields[0]);
  if (!time) {
    throw NdtCsvError(line_number_, "time_ns \"" + std::string(fields[0]) + "\" is not an integer (ns)");
  }
  row.time = *time;
  static constexpr const char* kNames[] = {"time_ns", "x", "y", "yaw", "sxx", "syy", "syaw"};
  double values[7] = {};
  for (std::size_t i = 1; i < columns_; ++i) {
    const auto value = parse_number<double>(fields[i]);
    if (!value || !std::isfinite(*value)) {
      throw NdtCsvError(line_number_, std::string(kNames[i]) + " \"" + std::string(fields[i]) +
                                          "\" is not a finite number");
    }
    if (i >= 4 && !(*value > 0.0)) {
      throw NdtCsvError(line_number_, std::string(kNames[i]) + " must be a positive variance, got " +
                                          std::string(fields[i]));
    }
    values[i] = *value;
  }
  row.pose = {values[1], values[2], values[3]};
  if (columns_ == 7) {
    row.variances = Eigen::Vector3d(values[4], values[5], values[6]);
  }
  return row;
}

}  // namespace rsu::vehicle_client
