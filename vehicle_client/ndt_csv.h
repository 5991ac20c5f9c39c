// SPDX-License-Identifier: Apache-2.0
// The rsu-vehicle CLI's input: the vehicle's NDT poses as CSV, one pose a line, after a header line
// naming the columns: time_ns,x,y,yaw first, then any of
//   sxx,syy,syaw                 variances of x (m^2), y (m^2) and yaw (rad^2), all three or none
//   converged,iterations,fitness,degeneracy   the match's quality indicator (vehicle/ndt_quality.h),
//                                each optional: converged 0 or 1, iterations a count, fitness PCL's
//                                score in m^2, degeneracy a ratio >= 1 ("inf": no curvature at all)
//   weak_axis                    the direction the match holds the vehicle most weakly (rad, map frame,
//                                modulo pi), optional: a degenerate pose is then weakened along it only
// in any order. time_ns: the common clock (ns); x, y: map frame ENU, m; yaw: rad CCW from east. Blank
// lines and lines starting with '#' are skipped. Every error names the line. Pure parsing: the caller
// reads the lines.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "common/pose.h"
#include "common/time.h"
#include "vehicle/ndt_quality.h"

namespace rsu::vehicle_client {

struct NdtPoseRow {
  TimeNs time = 0;
  Pose2 pose;
  std::optional<Eigen::Vector3d> variances;  // (x, y, yaw), when the file has the columns
  vehicle::NdtQuality quality;               // the indicators the file has
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
  bool has_header() const { return !columns_.empty(); }
  bool has_variances() const;

  // What each column holds.
  enum class Column {
    kTime,
    kX,
    kY,
    kYaw,
    kSxx,
    kSyy,
    kSyaw,
    kConverged,
    kIterations,
    kFitness,
    kDegeneracy,
    kWeakAxis
  };

 private:
  void parse_header(const std::vector<std::string_view>& fields, std::string_view line);
  void parse_field(Column column, std::string_view field, NdtPoseRow& row, double& variance) const;

  std::size_t line_number_ = 0;
  std::vector<Column> columns_;  // empty until the header was read
};

}  // namespace rsu::vehicle_client
