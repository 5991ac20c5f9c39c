// SPDX-License-Identifier: Apache-2.0
// The subcommands of rsu-sim. Each returns the process exit code; errors are thrown as exceptions
// with a message fit for the user.
#pragma once

#include <string>
#include <vector>

namespace rsu::tools {

int run_simulate(const std::vector<std::string>& args);
int run_stream(const std::vector<std::string>& args);

}  // namespace rsu::tools
