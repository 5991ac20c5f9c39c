// SPDX-License-Identifier: Apache-2.0
// rsu-pilot: reproduces the paper's pilot experiment (Sec. 3.1) for each LiDAR model and writes
// cells.csv and summary.json into the output folder; eval/plots/pilot_heatmaps.py draws the heat maps.
// `rsu-pilot matrix` runs it over mounts x LiDAR models x vehicles (eval/pilot/run_matrix.sh adds the
// heat maps of every cell).
#include <boost/program_options.hpp>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <stdexcept>

#include "eval/pilot/pilot_experiment.h"
#include "eval/pilot/pilot_matrix.h"
#include "eval/pilot/pilot_summary.h"
#include "sim/scenario.h"
#include "tools/cli/renamed_options.h"
#include "tools/cli/version.h"

namespace po = boost::program_options;

namespace {

template <typename T>
std::vector<T> split_list(const std::string& text) {
  std::vector<T> out;
  std::stringstream list(text);
  for (std::string item; std::getline(list, item, ',');) {
    if (item.empty())
      continue;
    if constexpr (std::is_same_v<T, std::string>) {
      out.push_back(item);
    } else {
      std::size_t used = 0;
      const double v = std::stod(item, &used);
      if (used != item.size())
        throw std::invalid_argument("not a number: \"" + item + "\"");
      out.push_back(v);
    }
  }
  return out;
}

// Options both commands share: the grid, the prior, the seed, the threads.
po::options_description grid_options(const rsu::eval::PilotConfig& defaults, double step, double spin) {
  po::options_description o("grid");
  o.add_options()("distance-min-m", po::value<double>()->default_value(defaults.distance_min_m), "m")(
      "distance-max-m", po::value<double>()->default_value(defaults.distance_max_m), "m")(
      "distance-step-m", po::value<double>()->default_value(step), "m")(
      "spin-rate-deg-per-s", po::value<double>()->default_value(spin),
      "deg/s of the spinning vehicle (at 10 Hz: 20 = 2 deg per frame, 180 frames per turn)")(
      "prior-error-deg", po::value<double>()->default_value(defaults.prior_error_deg),
      "bound of the uniform error of the vehicle's yaw prior (improved correction)")(
      "seed", po::value<std::uint64_t>()->default_value(defaults.noise.seed), "noise seed")(
      "threads", po::value<int>()->default_value(defaults.threads), "worker threads")(
      "max-position-sigma-m",
      po::value<double>()->default_value(defaults.fix.correction.max_position_sigma_m),
      "the fix's cap (rsud.yaml perception.correction.max_position_sigma_m, 0-10 m): a fix stating more is "
      "withheld (position_unbounded); another value than rsud's default is printed with the results");
  return o;
}

const char* kFixConfigNote =
    "fix configuration: rsud's (perception::VehicleFixConfig defaults = deploy/rsud.yaml); yaw prior = "
    "truth + uniform error, announced sigma 10 deg";

rsu::eval::PilotConfig base_config(const po::variables_map& vm) {
  rsu::eval::PilotConfig c;
  c.distance_min_m = vm["distance-min-m"].as<double>();
  c.distance_max_m = vm["distance-max-m"].as<double>();
  c.distance_step_m = vm["distance-step-m"].as<double>();
  c.spin_rate_deg_s = vm["spin-rate-deg-per-s"].as<double>();
  c.prior_error_deg = vm["prior-error-deg"].as<double>();
  c.noise.seed = vm["seed"].as<std::uint64_t>();
  c.threads = vm["threads"].as<int>();
  // The same bounds as rsud's configuration (daemon/config.cpp).
  const double cap = vm["max-position-sigma-m"].as<double>();
  if (!(cap > 0.0 && cap <= 10.0))
    throw std::invalid_argument("--max-position-sigma-m must be in (0, 10] m");
  c.fix.correction.max_position_sigma_m = cap;
  return c;
}

// Which fix configuration the results were measured with: rsud's, or rsud's with another cap.
void print_fix_config(const rsu::eval::PilotConfig& config) {
  std::printf("%s\n", kFixConfigNote);
  const double shipped = rsu::perception::CorrectionConfig{}.max_position_sigma_m;
  if (config.fix.correction.max_position_sigma_m != shipped)
    std::printf("NOT rsud's default: max_position_sigma_m %g m (rsud's: %g m)\n",
                config.fix.correction.max_position_sigma_m, shipped);
}

void print_result(const rsu::eval::PilotResult& result) {
  const auto& c = result.config;
  std::printf("%-10s at %.1f m, %s: %zu cells (%zu distances x %d frames) in %.1f s, %.1f M rays\n",
              c.model_name.c_str(), c.lidar_height_m, c.vehicle_name.c_str(), result.cells.size(),
              result.distances.size(), result.frames_per_turn, result.wall_seconds,
              static_cast<double>(result.rays_cast) * 1e-6);
  if (!result.skipped_distances.empty())
    std::printf("        %zu distances skipped (the spinning vehicle would reach into the LiDAR)\n",
                result.skipped_distances.size());
  std::printf("        %-11s %12s %12s %9s %8s %8s %7s %10s %10s %5s\n", "method", "<0.10m 6-36", ">=30 pts",
              "off-by-90", "median", "p95", "no fix", ">3s pos", ">3s yaw", "HMI");
  for (const auto method : rsu::eval::kPilotMethods) {
    const auto s = rsu::eval::summarize(result, method);
    std::printf("        %-11s %11.1f%% %11.1f%% %9d %8.3f %8.3f %7d %9.2f%% %9.2f%% %5d\n",
                rsu::eval::to_string(method), 100.0 * s.share_below_0p10_6_36m,
                100.0 * s.share_below_0p10_6_36m_30pts, s.off_by_90_cells, s.median_error_m, s.p95_error_m,
                s.no_fit_cells, 100.0 * s.beyond_3sigma_position, 100.0 * s.beyond_3sigma_yaw, s.hmi_fixes);
  }
  const auto k = rsu::eval::summarize_consistency(result);
  std::printf(
      "        stated covariance (improved, %d fixes, all distances): yaw sigma mean %.2f deg, beyond 3 "
      "sigma "
      "%.2f%%; position sigma mean %.3f m, beyond 3 sigma %.2f%%; HMI %d\n",
      k.fixes, k.mean_yaw_sigma_deg, 100.0 * k.yaw_beyond_3sigma, k.mean_position_sigma_m,
      100.0 * k.position_beyond_3sigma, k.hmi_fixes);
}

int run_single(int argc, char** argv) {
  rsu::eval::PilotConfig defaults;
  po::options_description options("rsu-pilot [options]: the paper's pilot experiment (Sec. 3.1)");
  options.add_options()("help,h", "show this help")("version", rsu::tools::cli::kVersionHelp)(
      "out,o", po::value<std::string>()->default_value("out/pilot"), "output folder")(
      "models", po::value<std::string>()->default_value("vlp16,vlp32c"), "comma-separated LiDAR models")(
      "lidar-height-m", po::value<double>()->default_value(defaults.lidar_height_m),
      "LiDAR height above the ground, m (the paper's: 2)")(
      "vehicle", po::value<std::string>(),
      "vehicle YAML (`shape:` with the scenario files' vehicle fields; scenarios/vehicles/); default: "
      "the paper's Lexus RX450h");
  options.add(grid_options(defaults, defaults.distance_step_m, defaults.spin_rate_deg_s));
  po::variables_map vm;
  try {
    po::store(po::parse_command_line(argc, argv, options), vm);
    po::notify(vm);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rsu-pilot: %s\n", e.what());
    return 2;
  }
  if (vm.count("help")) {
    std::cout << options << "\nrsu-pilot matrix --help: the matrix of mounts x LiDARs x vehicles\n";
    return 0;
  }
  const std::filesystem::path out = vm["out"].as<std::string>();
  std::filesystem::create_directories(out);
  rsu::eval::PilotConfig base;
  try {
    base = base_config(vm);
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "rsu-pilot: %s\n", e.what());
    return 2;
  }
  base.lidar_height_m = vm["lidar-height-m"].as<double>();
  if (vm.count("vehicle")) {
    const auto v = rsu::sim::load_vehicle_shape_file(vm["vehicle"].as<std::string>());
    base.vehicle = v.shape;
    base.vehicle_name =
        v.name.empty() ? std::filesystem::path(vm["vehicle"].as<std::string>()).stem().string() : v.name;
  }
  print_fix_config(base);
  std::ostringstream json;
  json << "{\n";
  bool first = true;
  for (const std::string& model : split_list<std::string>(vm["models"].as<std::string>())) {
    rsu::eval::PilotConfig config = base;
    config.model_name = model;
    const rsu::eval::PilotResult result = rsu::eval::run_pilot(config);
    rsu::eval::write_cells_csv(result, (out / "cells.csv").string(), !first);
    json << (first ? "" : ",\n") << "  \"" << model << "\": " << rsu::eval::summary_json_entry(result);
    first = false;
    print_result(result);
  }
  json << "\n}\n";
  std::ofstream((out / "summary.json").string()) << json.str();
  std::printf("wrote %s/cells.csv and %s/summary.json\n", out.c_str(), out.c_str());
  return 0;
}

int run_matrix_command(int argc, char** argv) {
  rsu::eval::PilotConfig defaults;
  po::options_description options(
      "rsu-pilot matrix [options]: the pilot over LiDAR mounts x models x vehicles; writes one folder per "
      "cell (cells.csv, summary.json) and matrix.md / matrix.csv");
  options.add_options()("help,h", "show this help")("version", rsu::tools::cli::kVersionHelp)(
      "out,o", po::value<std::string>()->default_value("out/pilot_matrix"), "output folder")(
      "mounts", po::value<std::string>()->default_value("2,4,6,8"), "LiDAR heights, m")(
      "models", po::value<std::string>()->default_value("vlp16,vlp32c,generic128"), "LiDAR models")(
      "vehicles",
      po::value<std::string>()->default_value("scenarios/vehicles/small_car.yaml,scenarios/vehicles/suv.yaml,"
                                              "scenarios/vehicles/van.yaml,scenarios/vehicles/bus.yaml"),
      "vehicle YAML files (default: the repository's four, from its top folder)");
  // A coarser grid than the paper's (1 m x 6 deg): 48 cells of 38 x 60 in a few minutes on two cores.
  options.add(grid_options(defaults, 1.0, 60.0));
  po::variables_map vm;
  try {
    po::store(po::parse_command_line(argc, argv, options), vm);
    po::notify(vm);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rsu-pilot matrix: %s\n", e.what());
    return 2;
  }
  if (vm.count("help")) {
    std::cout << options;
    return 0;
  }
  rsu::eval::MatrixConfig config;
  try {
    config.base = base_config(vm);
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "rsu-pilot matrix: %s\n", e.what());
    return 2;
  }
  config.mounts_m = split_list<double>(vm["mounts"].as<std::string>());
  config.models = split_list<std::string>(vm["models"].as<std::string>());
  for (const std::string& file : split_list<std::string>(vm["vehicles"].as<std::string>())) {
    auto v = rsu::sim::load_vehicle_shape_file(file);
    if (v.name.empty())
      v.name = std::filesystem::path(file).stem().string();
    config.vehicles.push_back(v);
  }
  const std::string out = vm["out"].as<std::string>();
  std::filesystem::create_directories(out);
  print_fix_config(config.base);
  const auto rows = rsu::eval::run_matrix(config, out, [](const rsu::eval::MatrixRow& r) {
    std::printf(
        "%-10s %4.1f m %-10s < 0.10 m %5.1f%% (>= 30 points %5.1f%%), p95 %.3f m, off-by-90 %d, no fix %d, "
        ">3 sigma %.2f%% / %.2f%%, HMI %d  (%.1f s)\n",
        r.model.c_str(), r.mount_m, r.vehicle.c_str(), 100.0 * r.improved.share_below_0p10_6_36m,
        100.0 * r.improved.share_below_0p10_6_36m_30pts, r.improved.p95_error_6_36m,
        r.improved.off_by_90_cells, r.improved.no_fit_cells, 100.0 * r.improved.beyond_3sigma_position,
        100.0 * r.improved.beyond_3sigma_yaw, r.improved.hmi_fixes, r.wall_seconds);
    std::fflush(stdout);
  });
  const std::string table = rsu::eval::matrix_markdown(rows);
  std::ofstream(out + "/matrix.md") << table;
  rsu::eval::write_matrix_csv(rows, out + "/matrix.csv");
  std::printf("\n%s\nwrote %s/matrix.md, %s/matrix.csv and one folder per cell\n", table.c_str(), out.c_str(),
              out.c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (rsu::tools::cli::print_version_if_asked(argc, argv, "rsu-pilot"))
    return 0;
  rsu::tools::cli::accept_renamed_options(argc, argv,
                                          {{"distance-min", "distance-min-m"},
                                           {"distance-max", "distance-max-m"},
                                           {"distance-step", "distance-step-m"},
                                           {"spin-rate", "spin-rate-deg-per-s"},
                                           {"lidar-height", "lidar-height-m"}},
                                          "rsu-pilot");
  try {
    if (argc > 1 && std::string(argv[1]) == "matrix")
      return run_matrix_command(argc - 1, argv + 1);
    return run_single(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rsu-pilot: %s\n", e.what());
    return 1;
  }
}
