// SPDX-License-Identifier: Apache-2.0
#include "tools/rsu_sim/scenario_options.h"

#include <stdexcept>

namespace rsu::tools {
namespace po = boost::program_options;

void add_scenario_options(po::options_description& options) {
  options.add_options()("scenario", po::value<std::string>(), "scenario YAML file")(
      "model", po::value<std::string>(),
      "use this LiDAR model instead of the scenario's (vlp16, vlp32c, genericN)")(
      "without-vehicles", "simulate the scene without its vehicles (a background recording)");
}

sim::Scenario load_scenario(const po::variables_map& vm) {
  if (!vm.count("scenario"))
    throw std::runtime_error("a scenario file is required (see --help)");
  sim::Scenario scenario = sim::load_scenario_file(vm["scenario"].as<std::string>());
  if (vm.count("model")) {
    const std::string name = vm["model"].as<std::string>();
    auto model = lidar::sensor_model_by_name(name);
    if (!model)
      throw std::runtime_error("--model: unknown LiDAR model \"" + name + "\"");
    model->rpm = scenario.lidar.model.rpm;
    scenario.lidar.model_name = name;
    scenario.lidar.model = *model;
  }
  if (vm.count("without-vehicles"))
    scenario.scene.vehicles.clear();
  return scenario;
}

}  // namespace rsu::tools
