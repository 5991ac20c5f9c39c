// SPDX-License-Identifier: Apache-2.0
// The rsu-vehicle CLI's outputs, as CSV with a header line (map frame ENU, m, rad CCW from east,
// ns of the common clock; docs/design.md §3).
#pragma once

#include <cstdio>
#include <string>

#include "fusion/vehicle_ekf.h"
#include "vehicle_client/vehicle_client.h"

namespace rsu::vehicle_client::cli {

// Fused poses (stdout).
inline constexpr const char* kFusedHeader = "time_ns,x,y,yaw,source,sxx,syy,syaw,speed_mps,yaw_rate_rps";
// source: "ndt" (the estimate at an NDT pose's time, after fusing it) or "rsu" (at a correction's sweep
// time, after fusing it).
void write_fused_row(std::FILE* out, const fusion::StateEstimate& estimate, const char* source);

// Received corrections (--corrections FILE): every accepted datagram, fused or not.
inline constexpr const char* kCorrectionHeader =
    "time_ns,x,y,yaw,cxx,cxy,cxyaw,cyy,cyyaw,cyawyaw,points_used,faces_seen,range_m,yaw_resolution,"
    "confidence,rsu_id,sequence,announcement_sequence,received_ns,fusion";
// fusion: the fuser's decision (accepted, rejected_gate, rejected_yaw_branch, ...) or "not_fused" with
// --announce-only.
void write_correction_row(std::FILE* out, const ReceivedCorrection& received, const std::string& fusion);

}  // namespace rsu::vehicle_client::cli
