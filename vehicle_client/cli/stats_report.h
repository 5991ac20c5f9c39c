// SPDX-License-Identifier: Apache-2.0
// What rsu-vehicle reports when it ends: a one-line summary on stderr and, with --stats FILE, every
// counter as "key value" lines (as rsud's stats file): the V2I client's, the fuser's, the vehicle's own
// NDT health and the integrity monitor's, overall and per RSU (issue 18: exclusions say which RSU, why,
// how soon after its first inconsistent fix, and whether it was readmitted).
#pragma once

#include <cstdio>
#include <string>

#include "v2i/message_authenticator.h"
#include "vehicle/vehicle_core.h"
#include "vehicle_client/vehicle_client.h"

namespace rsu::vehicle_client::cli {

void print_summary(std::FILE* out, const VehicleClientStats& client, const vehicle::VehicleCore& core,
                   v2i::SecurityMode mode);

// Throws std::runtime_error when the file cannot be written.
void write_stats_file(const std::string& path, const VehicleClientStats& client,
                      const vehicle::VehicleCore& core);

// A withheld fix's reason with what the notice adds to it: "position_unbounded (sigma S m, at most B m)",
// "mount (mount_moved)", ", packets lost nearby".
std::string describe(const v2i::FixWithheld& notice);

// One line for an exclusion or readmission this fix caused (empty when it caused none).
std::string integrity_event(const v2i::Correction& fix, const vehicle::FixCheck& check,
                            const vehicle::IntegrityMonitor& monitor);

}  // namespace rsu::vehicle_client::cli
