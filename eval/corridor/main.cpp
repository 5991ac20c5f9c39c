// SPDX-License-Identifier: Apache-2.0
// rsu-corridor: the paper's realistic experiment (Sec. 4) in the corridor street.
//   rsu-corridor ndt EXPERIMENT --out DIR      the vehicle's own NDT self-localization -> DIR/ndt.csv
//   rsu-corridor report EXPERIMENT --out DIR   score NDT, RSU and fused estimates -> table, summary.json
//   rsu-corridor map EXPERIMENT --out DIR      the street's map the vehicles localize in -> DIR/map.pcd
//   rsu-corridor placement EXPERIMENT --out DIR  where to put the RSU's LiDAR
//   (eval/corridor/placement_study.h)
// eval/corridor/run_experiment.sh runs the whole experiment (the live part through the real processes).
#include <boost/program_options.hpp>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include "eval/corridor/experiment_config.h"
#include "eval/corridor/map_sampling.h"
#include "eval/corridor/placement_study.h"
#include "eval/corridor/report.h"
#include "eval/corridor/vehicle_ndt_run.h"
#include "io/pcd_io.h"
#include "sim/parallel_indices.h"
#include "sim/raycaster.h"
#include "tools/cli/version.h"

namespace po = boost::program_options;
using namespace rsu;

namespace {

// --threads; no default in the options, so that the help does not depend on the machine.
int threads_option(const po::variables_map& vm) {
  const int threads = vm.count("threads") ? vm["threads"].as<int>() : sim::hardware_threads();
  if (threads < 1 || threads > 256)
    throw std::invalid_argument("--threads must be within [1, 256]");
  return threads;
}

int run_ndt(const eval::CorridorExperimentConfig& config, const std::filesystem::path& out, int threads) {
  std::fprintf(stderr, "vehicle NDT self-localization (%s on the roof, %.1f s drive)\n",
               config.vehicle_lidar_model.c_str(), config.duration_s);
  const auto samples = eval::run_vehicle_ndt(config, threads, [](int done, int total) {
    if (done % 10 == 0 || done == total)
      std::fprintf(stderr, "\r  NDT frame %d/%d", done, total);
  });
  std::fprintf(stderr, "\n");
  std::ofstream csv(out / "ndt.csv");
  csv << "time_ns,x,y,yaw,sxx,syy,syaw,converged,iterations,fitness,degeneracy,weak_axis,truth_x,truth_y,"
         "truth_yaw\n";
  csv.precision(10);
  int converged = 0;
  for (const auto& s : samples) {
    csv << s.time_ns << ',' << s.pose.x << ',' << s.pose.y << ',' << s.pose.yaw << ',' << s.covariance(0, 0)
        << ',' << s.covariance(1, 1) << ',' << s.covariance(2, 2) << ',' << (s.converged ? 1 : 0) << ','
        << s.iterations << ',' << s.fitness << ',' << s.degeneracy << ',' << s.weak_axis_rad << ','
        << s.truth.x << ',' << s.truth.y << ',' << s.truth.yaw << '\n';
    converged += s.converged ? 1 : 0;
  }
  std::fprintf(stderr, "  %zu poses (%d converged) -> %s\n", samples.size(), converged,
               (out / "ndt.csv").c_str());
  return 0;
}

int run_report(const eval::CorridorExperimentConfig& config, const std::filesystem::path& out) {
  const eval::ExperimentScores scores = eval::score_experiment(config, out.string());
  std::vector<std::string> methods = {"ndt"};
  for (const auto& m : config.rsu_models)
    methods.push_back("rsu_" + m);
  for (const auto& m : config.rsu_models)
    methods.push_back("fused_" + m);
  const std::string table = eval::format_table(scores, methods);
  std::cout << table;
  std::ofstream(out / "table.txt") << table;
  const std::string comparison = eval::format_paper_comparison(scores, config.rsu_models);
  std::cout << comparison;
  std::ofstream(out / "paper_comparison.txt") << comparison;
  std::ofstream(out / "summary.json") << eval::summary_json(scores, methods);
  eval::write_frames_csv(scores, (out / "frames.csv").string());
  return 0;
}

// The map the vehicles' NDT uses (and rsu-calibrate registers the RSU's background against).
int run_map(const eval::CorridorExperimentConfig& config, const std::filesystem::path& out) {
  const sim::Raycaster raycaster(config.scenario.scene);
  std::vector<lidar::LidarPoint> points;
  for (const Eigen::Vector3f& p : eval::sample_static_map(raycaster, config.map_spacing_m, config.seed))
    points.push_back(lidar::LidarPoint{.x = p.x(), .y = p.y(), .z = p.z()});
  io::write_pcd((out / "map.pcd").string(), points);
  std::fprintf(stderr, "map: %zu points -> %s\n", points.size(), (out / "map.pcd").c_str());
  return 0;
}

// Comma-separated numbers / words.
std::vector<std::string> split_list(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream in(text);
  for (std::string item; std::getline(in, item, ',');) {
    if (!item.empty())
      out.push_back(item);
  }
  return out;
}

int run_placement(const eval::CorridorExperimentConfig& config, const std::filesystem::path& out,
                  const po::variables_map& vm) {
  eval::PlacementStudyConfig study;
  study.duration_s = config.duration_s;
  study.seed = config.seed;
  study.models = split_list(vm["models"].as<std::string>());
  study.heights_m.clear();
  for (const std::string& h : split_list(vm["heights-m"].as<std::string>()))
    study.heights_m.push_back(std::stod(h));
  const std::vector<std::string> laterals = split_list(vm["laterals"].as<std::string>());
  std::erase_if(study.laterals, [&](const auto& l) {
    return std::find(laterals.begin(), laterals.end(), l.first) == laterals.end();
  });
  study.rotation_stride = vm["rotation-stride"].as<int>();
  study.threads = threads_option(vm);
  if (study.models.empty() || study.heights_m.empty() || study.laterals.empty() || study.rotation_stride < 1)
    throw std::invalid_argument(
        "placement: need models, heights, laterals (curb, median, across), stride >= 1");
  std::fprintf(stderr, "placement study: %zu placements in %s (the fix rsud runs, rsud's configuration)\n",
               study.models.size() * study.heights_m.size() * study.laterals.size(),
               config.scenario.source.c_str());
  const auto results = eval::run_placement_study(config.scenario, study);
  std::ofstream(out / "placement.csv") << eval::placement_csv(results);
  std::ofstream(out / "placement_samples.csv") << eval::placement_samples_csv(results);
  const std::string table = eval::placement_table(results, study);
  std::ofstream(out / "placement_table.md") << table;
  std::ofstream(out / "summary.json") << eval::placement_json(results, study, config.scenario.source);
  std::cout << table;
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (rsu::tools::cli::print_version_if_asked(argc, argv, "rsu-corridor"))
    return 0;
  po::options_description options(
      "rsu-corridor {ndt|report|map|placement} EXPERIMENT [--out DIR]: the paper's realistic experiment "
      "(Sec. 4)");
  options.add_options()("help,h", "show this help")("version", rsu::tools::cli::kVersionHelp)(
      "out,o", po::value<std::string>()->default_value("out/corridor"), "output folder")(
      "models", po::value<std::string>()->default_value("vlp16,vlp32c,generic128"),
      "placement: LiDAR models")("heights-m", po::value<std::string>()->default_value("2,4,6,8"),
                                 "placement: mount heights, m")(
      "laterals", po::value<std::string>()->default_value("curb,median,across"),
      "placement: curb (y = -8.5 m, the south sidewalk), median (y = 0), across (y = 8.5 m, the north "
      "sidewalk)")("rotation-stride", po::value<int>()->default_value(1),
                   "placement: score every n-th rotation")("threads", po::value<int>(),
                                                           "worker threads: placements at once (placement), "
                                                           "each frame's rays (ndt); default: the machine's "
                                                           "hardware threads");
  // The positional arguments, named in the usage line above rather than listed as options.
  po::options_description all;
  all.add(options).add_options()("command", po::value<std::string>(), "ndt, report or map")(
      "experiment", po::value<std::string>(), "experiment file, e.g. scenarios/corridor_experiment.yaml");
  po::positional_options_description positional;
  positional.add("command", 1).add("experiment", 1);
  po::variables_map vm;
  try {
    po::store(po::command_line_parser(argc, argv).options(all).positional(positional).run(), vm);
    po::notify(vm);
    if (vm.count("help") || !vm.count("command") || !vm.count("experiment")) {
      std::cout << options;
      return vm.count("help") ? 0 : 2;
    }
    const auto config = eval::load_corridor_experiment(vm["experiment"].as<std::string>());
    const std::filesystem::path out = vm["out"].as<std::string>();
    std::filesystem::create_directories(out);
    const std::string command = vm["command"].as<std::string>();
    if (command == "ndt")
      return run_ndt(config, out, threads_option(vm));
    if (command == "report")
      return run_report(config, out);
    if (command == "map")
      return run_map(config, out);
    if (command == "placement")
      return run_placement(config, out, vm);
    std::fprintf(stderr, "rsu-corridor: unknown command \"%s\" (ndt, report, map or placement)\n",
                 command.c_str());
    return 2;
  } catch (const po::error& e) {  // unknown option, missing value: a usage error
    std::fprintf(stderr, "rsu-corridor: %s (see --help)\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rsu-corridor: %s\n", e.what());
    return 1;
  }
}
