#include "rsu/correction_builder.h"

#include <algorithm>

#include "common/angles.h"

namespace rsu::core {

v2i::YawResolution to_wire(perception::AmbiguityResolution resolution) {
  switch (resolution) {
    case perception::AmbiguityResolution::prior:
      return v2i::YawResolution::kPrior;
    case perception::AmbiguityResolution::geometry:
      return v2i::YawResolution::kGeometry;
    case perception::AmbiguityResolution::edge_lengths:
    case perception::AmbiguityResolution::unresolved:
      break;
  }
  return v2i::YawResolution::kUnresolved;
}

std::uint32_t faces_seen(const perception::RectangleFit& fit) {
  const auto n = std::count_if(fit.edges.begin(), fit.edges.end(), [](const auto& e) { return e.seen; });
  return static_cast<std::uint32_t>(std::min<std::ptrdiff_t>(n, 2));
}

v2i::Correction make_correction(const CorrectionInputs& in, const perception::CorrectedPose& fix,
                                const perception::RectangleFit& fit, const Eigen::Vector2d& lidar_xy) {
  v2i::Correction c;
  c.rsu_id = in.rsu_id;
  c.vehicle_id = in.vehicle_id;
  c.sequence = in.sequence;
  c.announcement_sequence = in.announcement_sequence;
  c.sweep_time = in.sweep_time;
  c.pose = {fix.pose.x, fix.pose.y, wrap_angle(fix.pose.yaw)};
  c.pose_covariance = fix.covariance;
  c.quality.points_used = static_cast<std::uint32_t>(in.points_used);
  c.quality.faces_seen = faces_seen(fit);
  c.quality.range_m = (fix.alignment_point - lidar_xy).norm();
  c.quality.yaw_resolution = to_wire(fix.resolution);
  c.quality.confidence = std::clamp(fix.confidence, 0.0, 1.0);
  return c;
}

}  // namespace rsu::core
