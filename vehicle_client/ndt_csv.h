// The rsu-vehicle CLI's input: the vehicle's NDT poses as CSV, one pose a line, after a header line:
//   time_ns,x,y,yaw                 or   time_ns,x,y,yaw,sxx,syy,syaw
// time_ns: common clock (DESIGN.md §3); x, y: map frame ENU, m; yaw: rad CCW from east; sxx, syy,
// syaw: variances of x (m^2), y (m^2) and yaw (rad^2). Blank lines and lines starting with '#' are
// skipped. Every error names the line. Pure parsing: the caller reads the lines.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

#include "common/pose.h"
#include "common/time.h"

namespace rsu::vehicle_client {

struct NdtPoseRow {
  TimeNs time = 0;
  Pose2 pose;
  std::optional<Eigen::Vector3d> variances;  // (x, y, yaw), when the file has the columns
};

class NdtCsvError : public std::runtime_error {
 public:
  NdtCsvError(std::size_t line, const std::string& what);
  std::size_t line() const { return line_; }

 private:
  std::size_t line_;
};

class NdtCsvParser {
 public:
  // One line (without its newline; a trailing '\r' is ignored). Returns the pose, or nothing for the
  // header, a blank or a comment line. Throws NdtCsvError naming the line number on bad input.
  std::optional<NdtPoseRow> parse_line(std::string_view line);

  std::size_t line_number() const { return line_number_; }
  bool has_header() const { return columns_ != 0; }
  bool has_variances() const { return columns_ == 7; }

 private:
  std::size_t line_number_ = 0;
  std::size_t columns_ = 0;  // 0 until the header was read; then 4 or 7
};

}  // namespace rsu::vehicle_client
