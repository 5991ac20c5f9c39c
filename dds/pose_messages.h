// SPDX-License-Identifier: Apache-2.0
// geometry_msgs Pose(WithCovariance) and builtin_interfaces Time as idlc's C types <-> lib/ros's plain
// ones, shared by rsud's DDS edge and rsu-autoware-sidecar.
#pragma once

#include <optional>

#include "builtin_interfaces.h"
#include "common/time.h"
#include "geometry_msgs.h"
#include "ros/correction_pose.h"

namespace rsu::dds {

builtin_interfaces_msg_dds__Time_ to_msg_time(TimeNs t);
// nullopt when the message's nanosec is out of range (ros::from_ros_time).
std::optional<TimeNs> from_msg_time(const builtin_interfaces_msg_dds__Time_& t);

void to_msg_pose(const ros::RosPoseWithCovariance& p, geometry_msgs_msg_dds__PoseWithCovariance_& out);
ros::RosPoseWithCovariance from_msg_pose(const geometry_msgs_msg_dds__PoseWithCovariance_& m);

}  // namespace rsu::dds
