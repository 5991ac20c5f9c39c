// SPDX-License-Identifier: Apache-2.0
// rsu-sim: the LiDAR and scene simulator's command line.
//   rsu-sim simulate SCENARIO [--out DIR] [--frames N]   frames (PCD), packets (pcap), truth, picture data
//   rsu-sim stream SCENARIO --to HOST:PORT [...]         Velodyne packets over UDP, real time or fast
#include <cstdio>
#include <cstring>
#include <exception>
#include <string>
#include <vector>

#include "tools/cli/version.h"
#include "tools/rsu_sim/commands.h"

namespace {

constexpr const char* kUsage =
    "usage: rsu-sim <command> [options]\n"
    "\n"
    "commands:\n"
    "  simulate SCENARIO   simulate frames; write PCD frames, a Velodyne pcap, the truth and a top-down\n"
    "                      picture's data into --out (see rsu-sim simulate --help)\n"
    "  stream SCENARIO     send the scenario's Velodyne packets over UDP (see rsu-sim stream --help)\n"
    "  --version           print the version and exit\n"
    "\n"
    "Scenario files: scenarios/*.yaml (pilot.yaml, corridor.yaml).\n";

}  // namespace

int main(int argc, char** argv) {
  if (rsu::tools::cli::print_version_if_asked(argc, argv, "rsu-sim"))
    return 0;
  if (argc < 2 || std::strcmp(argv[1], "--help") == 0 || std::strcmp(argv[1], "-h") == 0) {
    std::fputs(kUsage, argc < 2 ? stderr : stdout);
    return argc < 2 ? 2 : 0;
  }
  const std::string command = argv[1];
  const std::vector<std::string> args(argv + 2, argv + argc);
  try {
    if (command == "simulate")
      return rsu::tools::run_simulate(args);
    if (command == "stream")
      return rsu::tools::run_stream(args);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rsu-sim: %s\n", e.what());
    return 1;
  }
  std::fprintf(stderr, "rsu-sim: unknown command \"%s\"\n\n%s", command.c_str(), kUsage);
  return 2;
}
