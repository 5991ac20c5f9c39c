// SPDX-License-Identifier: Apache-2.0
// rsud.yaml's dds: section and the dds_pointcloud2 input: defaults, every key, located errors.
#include <gtest/gtest.h>

#include <string>

#include "daemon/config.h"
#include "daemon/dds_config.h"

namespace rsu::daemon {
namespace {

const std::string kHead =
    "rsu_id: 1\n"
    "lidar:\n"
    "  model: vlp32c\n"
    "  mount: {x: 0, y: 0, z: 2}\n";

DaemonConfig parse(const std::string& body) {
  return parse_config(kHead + body, "/etc/rsud/rsud.yaml");
}

void expect_refused(const std::string& body, const std::string& expected) {
  try {
    parse(body);
    ADD_FAILURE() << "accepted:\n" << body;
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
  }
}

TEST(DdsConfig, OffByDefaultWithDocumentedDefaults) {
  const DaemonConfig c = parse("  input: {velodyne_udp: {}}\n");
  EXPECT_FALSE(c.dds.enabled);
  EXPECT_EQ(c.dds.pose_topic, "vehicles/{vehicle_id}/rsu/pose_with_covariance");
  EXPECT_EQ(c.dds.frame_id, "map");
  EXPECT_EQ(c.dds.object_list_topic, "rsu/vehicle_fixes");
  EXPECT_TRUE(c.dds.participant.cyclone_config.empty());
}

TEST(DdsConfig, ReadsEveryKey) {
  const DaemonConfig c = parse(
      "  input:\n"
      "    dds_pointcloud2:\n"
      "      topic: /velodyne_points\n"
      "      whole_rotation: false\n"
      "      ring_order: elevation\n"
      "      frame_id: velodyne\n"
      "      qos: {reliability: best_effort, history_depth: 4}\n"
      "dds:\n"
      "  enabled: true\n"
      "  domain_id: 42\n"
      "  cyclone_config: cyclone.xml\n"
      "  pose_topic: rsu/{vehicle_id}/pose\n"
      "  frame_id: earth\n"
      "  pose_qos: {durability: transient_local}\n"
      "  object_list_topic: \"\"\n"
      "  object_list_max_age_s: 1.5\n");
  ASSERT_TRUE(std::holds_alternative<DdsPointCloud2Input>(c.input));
  const auto& in = std::get<DdsPointCloud2Input>(c.input);
  EXPECT_EQ(in.topic, "/velodyne_points");
  EXPECT_FALSE(in.whole_rotation);
  EXPECT_EQ(in.ring_order, ros::RingOrder::kElevation);
  EXPECT_EQ(in.frame_id, "velodyne");
  EXPECT_EQ(in.qos.reliability, dds::Reliability::kBestEffort);
  EXPECT_EQ(in.qos.history_depth, 4U);
  EXPECT_TRUE(c.dds.enabled);
  EXPECT_EQ(c.dds.participant.domain_id, 42U);
  EXPECT_EQ(c.dds.participant.cyclone_config, "/etc/rsud/cyclone.xml");  // relative to the file
  EXPECT_EQ(c.dds.pose_topic, "rsu/{vehicle_id}/pose");
  EXPECT_EQ(c.dds.frame_id, "earth");
  EXPECT_EQ(c.dds.pose_qos.durability, dds::Durability::kTransientLocal);
  EXPECT_TRUE(c.dds.object_list_topic.empty());
  EXPECT_EQ(c.dds.object_list_max_age_s, 1.5);
}

TEST(DdsConfig, ErrorsNameFileLineAndField) {
  expect_refused("  input: {velodyne_udp: {}}\ndds:\n  enabled: yes please\n",
                 "/etc/rsud/rsud.yaml:7: dds.enabled: expected true or false");
  expect_refused("  input: {velodyne_udp: {}}\ndds:\n  domian_id: 3\n",
                 "rsud.yaml:7: dds.domian_id: unknown field");
  expect_refused("  input: {velodyne_udp: {}}\ndds:\n  domain_id: 300\n",
                 "dds.domain_id: must be a whole number");
  expect_refused("  input: {velodyne_udp: {}}\ndds:\n  pose_topic: vehicles/pose\n",
                 "dds.pose_topic: must contain {vehicle_id}");
  expect_refused("  input: {velodyne_udp: {}}\ndds:\n  pose_topic: \"vehicles/{vehicle_id}/a b\"\n",
                 "dds.pose_topic: \"vehicles/{vehicle_id}/a b\" is not a ROS topic name");
  expect_refused("  input: {velodyne_udp: {}}\ndds:\n  pose_qos: {reliability: maybe}\n",
                 "rsud.yaml:7: dds.pose_qos.reliability: expected reliable or best_effort");
  expect_refused("  input:\n    dds_pointcloud2: {topic: points}\n",
                 "lidar.input.dds_pointcloud2: needs the DDS participant: set dds.enabled: true");
  expect_refused("  input:\n    dds_pointcloud2: {ring_order: sideways}\ndds: {enabled: true}\n",
                 "rsud.yaml:6: lidar.input.dds_pointcloud2.ring_order: expected channel or elevation");
  expect_refused("  input:\n    dds_pointcloud2: {topic: \"\"}\ndds: {enabled: true}\n",
                 "lidar.input.dds_pointcloud2.topic: expected a topic name");
  expect_refused("  input: {velodyne_udp: {}, dds_pointcloud2: {}}\ndds: {enabled: true}\n",
                 "exactly one of udp (velodyne_udp), pcap, pcd, dds_pointcloud2 is required");
}

TEST(DdsConfig, VehiclePoseTopicReplacesEveryPlaceholder) {
  EXPECT_EQ(vehicle_pose_topic("vehicles/{vehicle_id}/rsu/pose", 7), "vehicles/7/rsu/pose");
  EXPECT_EQ(vehicle_pose_topic("a/{vehicle_id}/b/{vehicle_id}", 123456789012ULL),
            "a/123456789012/b/123456789012");
}

}  // namespace
}  // namespace rsu::daemon
