// SPDX-License-Identifier: Apache-2.0
// Command line of rsu-fleet (fleet_main.cpp): which vehicles announce, how, to whom, for how long.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "common/time.h"
#include "v2i/messages.h"

namespace rsu::fleet {

// A scenario vehicle that announces a different size from some scenario time on.
struct SizeChange {
  TimeNs at_scenario_ns = 0;
  v2i::BoxSize size;
};

struct FleetOptions {
  std::string rsu_address;  // IPv4 literal
  std::uint16_t rsu_port = 0;
  std::string scenario;  // the scenario rsu-sim streams; its vehicles announce their true poses
  TimeNs epoch_ns = 0;   // host-clock time of scenario time 0 (rsu-sim stream --epoch-ns)
  // Scenario vehicles that announce (connected); empty: all of them.
  std::vector<std::uint32_t> connected;
  int extra_vehicles = 0;  // synthetic vehicles beyond the LiDAR's coverage, ids from 100001
  double rate_hz = 10.0;
  double seconds = 10.0;
  std::uint32_t address_base = 0x7f010001;  // 127.1.0.1: vehicle k sends from base + k
  // Added to every generation time: the vehicle's clock error against the RSU's (docs/design.md §3).
  TimeNs clock_offset_ns = 0;
  // The announced pose is the truth moved by this much along +x and -y of the map (the vehicle's own
  // estimate is off), with the announced covariance below.
  double pose_error_m = 0.3;
  std::map<std::uint32_t, v2i::BoxSize> announced_size;  // overrides the scenario's shape
  std::map<std::uint32_t, SizeChange> size_change;
  std::string corrections_path;  // one line per received correction (fleet_main.cpp)
  // Signed announcements (proto/v2i.proto v2): each vehicle signs with its own TEST key, derived from
  // its id and this seed, and the vehicles' trust list is written to `trust_list_path` first (for
  // rsud's security.trust_list_file). Derived keys are for tests only: anyone knowing the scheme has
  // them. Empty path: unsigned (rsud in insecure mode).
  std::string trust_list_path;
  std::uint64_t key_seed = 1;
  bool write_trust_list_only = false;  // write the trust list and exit
};

// Parses argv; prints --help and exits 0, or throws std::runtime_error naming the bad option.
FleetOptions parse_fleet_options(int argc, char** argv);

}  // namespace rsu::fleet
