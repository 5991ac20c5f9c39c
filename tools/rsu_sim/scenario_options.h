// SPDX-License-Identifier: Apache-2.0
// Options shared by rsu-sim's subcommands: the scenario file and overrides of it.
#pragma once

#include <boost/program_options.hpp>

#include "sim/scenario.h"

namespace rsu::tools {

// Adds "scenario", "model" and "without-vehicles".
void add_scenario_options(boost::program_options::options_description& options);
// Loads the scenario and applies the overrides: --model replaces the LiDAR model (the mount stays), and
// --without-vehicles empties the scene of vehicles (a background recording for the RSU).
sim::Scenario load_scenario(const boost::program_options::variables_map& vm);

}  // namespace rsu::tools
