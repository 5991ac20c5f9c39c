// SPDX-License-Identifier: Apache-2.0
#include "dds/pose_messages.h"

#include <algorithm>
#include <iterator>

#include "ros/ros_time.h"

namespace rsu::dds {

builtin_interfaces_msg_dds__Time_ to_msg_time(TimeNs t) {
  const ros::RosTime r = ros::to_ros_time(t);
  return {r.sec, r.nanosec};
}

std::optional<TimeNs> from_msg_time(const builtin_interfaces_msg_dds__Time_& t) {
  return ros::from_ros_time({t.sec, t.nanosec});
}

void to_msg_pose(const ros::RosPoseWithCovariance& p, geometry_msgs_msg_dds__PoseWithCovariance_& out) {
  out.pose.position = {p.position[0], p.position[1], p.position[2]};
  out.pose.orientation = {p.orientation[0], p.orientation[1], p.orientation[2], p.orientation[3]};
  std::copy(p.covariance.begin(), p.covariance.end(), std::begin(out.covariance));
}

ros::RosPoseWithCovariance from_msg_pose(const geometry_msgs_msg_dds__PoseWithCovariance_& m) {
  ros::RosPoseWithCovariance p;
  p.position = {m.pose.position.x, m.pose.position.y, m.pose.position.z};
  p.orientation = {m.pose.orientation.x, m.pose.orientation.y, m.pose.orientation.z, m.pose.orientation.w};
  std::copy(std::begin(m.covariance), std::end(m.covariance), p.covariance.begin());
  return p;
}

}  // namespace rsu::dds
