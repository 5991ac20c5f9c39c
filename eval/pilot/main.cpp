// rsu-pilot: reproduces the paper's pilot experiment (Sec. 3.1) for each LiDAR model and writes
// cells.csv and summary.json into the output folder; eval/plots/pilot_heatmaps.py draws the heat maps.
#include <boost/program_options.hpp>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include "eval/pilot/pilot_experiment.h"

namespace po = boost::program_options;

int main(int argc, char** argv) {
  rsu::eval::PilotConfig defaults;
  po::options_description options("rsu-pilot [options]: the paper's pilot experiment (Sec. 3.1)");
  options.add_options()("help,h", "show this help")(
      "out,o", po::value<std::string>()->default_value("out/pilot"), "output folder")(
      "models", po::value<std::string>()->default_value("vlp16,vlp32c"), "comma-separated LiDAR models")(
      "distance-min", po::value<double>()->default_value(defaults.distance_min_m), "m")(
      "distance-max", po::value<double>()->default_value(defaults.distance_max_m), "m")(
      "distance-step", po::value<double>()->default_value(defaults.distance_step_m), "m")(
      "prior-error-deg", po::value<double>()->default_value(defaults.prior_error_deg),
      "bound of the uniform error of the vehicle's yaw prior (improved correction)")(
      "seed", po::value<std::uint64_t>()->default_value(defaults.noise.seed), "noise seed")(
      "threads", po::value<int>()->default_value(defaults.threads), "worker threads");
  po::variables_map vm;
  try {
    po::store(po::parse_command_line(argc, argv, options), vm);
    po::notify(vm);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rsu-pilot: %s\n", e.what());
    return 2;
  }
  if (vm.count("help")) {
    std::cout << options;
    return 0;
  }
  try {
    const std::filesystem::path out = vm["out"].as<std::string>();
    std::filesystem::create_directories(out);
    std::vector<std::string> models;
    std::stringstream list(vm["models"].as<std::string>());
    for (std::string m; std::getline(list, m, ',');)
      models.push_back(m);

    std::ostringstream json;
    json << "{\n";
    bool first = true;
    for (const std::string& model : models) {
      rsu::eval::PilotConfig config;
      config.model_name = model;
      config.distance_min_m = vm["distance-min"].as<double>();
      config.distance_max_m = vm["distance-max"].as<double>();
      config.distance_step_m = vm["distance-step"].as<double>();
      config.prior_error_deg = vm["prior-error-deg"].as<double>();
      config.noise.seed = vm["seed"].as<std::uint64_t>();
      config.threads = vm["threads"].as<int>();
      const rsu::eval::PilotResult result = rsu::eval::run_pilot(config);
      rsu::eval::write_cells_csv(result, (out / "cells.csv").string(), !first);
      json << (first ? "" : ",\n") << "  \"" << model << "\": " << rsu::eval::summary_json_entry(result);
      first = false;

      std::printf("%-7s %zu cells (%zu distances x %d frames) in %.1f s, %.1f M rays\n", model.c_str(),
                  result.cells.size(), result.distances.size(), result.frames_per_turn, result.wall_seconds,
                  static_cast<double>(result.rays_cast) * 1e-6);
      std::printf("        %-11s %12s %9s %10s %10s %7s\n", "method", "<0.10m 6-36", "off-by-90", "median m",
                  "p95 m", "no fit");
      for (const char* method : {"lshape", "algorithm1", "improved"}) {
        const auto s = rsu::eval::summarize(result, method);
        std::printf("        %-11s %11.1f%% %9d %10.3f %10.3f %7d\n", method,
                    100.0 * s.share_below_0p10_6_36m, s.off_by_90_cells, s.median_error_m, s.p95_error_m,
                    s.no_fit_cells);
      }
      const auto k = rsu::eval::summarize_consistency(result);
      std::printf(
          "        stated covariance (improved, %d fixes): yaw sigma mean %.2f deg, beyond 3 sigma "
          "%.2f%%; position sigma mean %.3f m, beyond 3 sigma %.2f%%\n",
          k.fixes, k.mean_yaw_sigma_deg, 100.0 * k.yaw_beyond_3sigma, k.mean_position_sigma_m,
          100.0 * k.position_beyond_3sigma);
    }
    json << "\n}\n";
    std::ofstream((out / "summary.json").string()) << json.str();
    std::printf("wrote %s/cells.csv and %s/summary.json\n", out.c_str(), out.c_str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rsu-pilot: %s\n", e.what());
    return 1;
  }
  return 0;
}
