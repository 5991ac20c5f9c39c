// SPDX-License-Identifier: Apache-2.0
// The pilot experiment over a matrix of LiDAR mounts x sensors x vehicles (issue: fixes that hold from
// 2 m to 8 m mounts, 16 to 128 rings, small car to bus). Each cell of the matrix is one pilot run (the
// grid of distances x yaw angles set by the base configuration: coarser grids run faster); every run's
// cells.csv and summary.json go into its own folder, and one table sums them all up.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "eval/pilot/pilot_experiment.h"
#include "eval/pilot/pilot_summary.h"
#include "sim/scenario.h"

namespace rsu::eval {

struct MatrixConfig {
  std::vector<double> mounts_m = {2.0, 4.0, 6.0, 8.0};
  std::vector<std::string> models = {"vlp16", "vlp32c", "generic128"};
  std::vector<sim::NamedVehicleShape> vehicles;  // at least one
  PilotConfig base;  // distances, spin rate (the grid), prior, noise, fix configuration, threads
};

struct MatrixRow {
  std::string model;
  double mount_m = 0;
  std::string vehicle;
  std::string folder;  // relative to the matrix's output folder
  MethodSummary improved;
  // The worst 5 m band's shares beyond 3 sigma (bands with at least 20 fixes).
  double worst_band_position = 0;
  double worst_band_yaw = 0;
  double mean_points_6_36m = 0;
  double wall_seconds = 0;
};

// Runs every cell, writing <out>/<model>_<mount>m_<vehicle>/{cells.csv,summary.json}; `progress` is
// called after each. Throws std::invalid_argument for an empty matrix.
std::vector<MatrixRow> run_matrix(const MatrixConfig& config, const std::string& out,
                                  const std::function<void(const MatrixRow&)>& progress = {});

// The table as Markdown (README) and as CSV.
std::string matrix_markdown(const std::vector<MatrixRow>& rows);
void write_matrix_csv(const std::vector<MatrixRow>& rows, const std::string& path);

}  // namespace rsu::eval
