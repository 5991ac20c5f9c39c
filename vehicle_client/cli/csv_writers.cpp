// SPDX-License-Identifier: Apache-2.0
#include "vehicle_client/cli/csv_writers.h"

#include <charconv>
#include <string>

namespace rsu::vehicle_client::cli {

namespace {

// The shortest text that reads back as the same double (std::to_chars without a format), so the
// numbers survive the round trip through CSV exactly without 17-digit noise.
std::string num(double v) {
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), v);
  return {buffer, result.ptr};
}

const char* to_string(v2i::YawResolution r) {
  switch (r) {
    case v2i::YawResolution::kPrior:
      return "prior";
    case v2i::YawResolution::kGeometry:
      return "geometry";
    case v2i::YawResolution::kUnresolved:
      break;
  }
  return "unresolved";
}

}  // namespace

void write_fused_row(std::FILE* out, const fusion::StateEstimate& e, const char* source) {
  const auto& s = e.state;
  const auto& p = e.covariance;
  std::fprintf(out, "%lld,%s,%s,%s,%s,%s,%s,%s,%s,%s\n", static_cast<long long>(e.time),
               num(s(fusion::kX)).c_str(), num(s(fusion::kY)).c_str(), num(s(fusion::kYaw)).c_str(), source,
               num(p(fusion::kX, fusion::kX)).c_str(), num(p(fusion::kY, fusion::kY)).c_str(),
               num(p(fusion::kYaw, fusion::kYaw)).c_str(), num(s(fusion::kSpeed)).c_str(),
               num(s(fusion::kYawRate)).c_str());
}

void write_correction_row(std::FILE* out, const ReceivedCorrection& received, const std::string& fusion) {
  const v2i::Correction& c = received.correction;
  const auto& q = c.quality;
  const Eigen::Matrix3d& v = c.pose_covariance;
  std::string numbers;
  for (const double x :
       {c.pose.x, c.pose.y, c.pose.yaw, v(0, 0), v(0, 1), v(0, 2), v(1, 1), v(1, 2), v(2, 2)}) {
    numbers += num(x) + ",";
  }
  std::fprintf(out, "%lld,%s%u,%u,%s,%s,%s,%llu,%u,%u,%lld,%s\n", static_cast<long long>(c.sweep_time),
               numbers.c_str(), q.points_used, q.faces_seen, num(q.range_m).c_str(),
               to_string(q.yaw_resolution), num(q.confidence).c_str(),
               static_cast<unsigned long long>(c.rsu_id), c.sequence, c.announcement_sequence,
               static_cast<long long>(received.received_time), fusion.c_str());
}

}  // namespace rsu::vehicle_client::cli
