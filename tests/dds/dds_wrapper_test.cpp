// SPDX-License-Identifier: Apache-2.0
// The DDS plumbing (dds/): a participant configured by the shipped loopback file, a typed writer and
// reader over rt/ topics, QoS from YAML, Cyclone errors as exceptions with Cyclone's text.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <string>
#include <thread>

#include <unistd.h>

#include "dds/dds_error.h"
#include "dds/participant.h"
#include "dds/qos_config.h"
#include "dds/typed_entities.h"
#include "geometry_msgs.h"
#include "io/yaml_field.h"

namespace rsu::dds {
namespace {

using PoseStamped = geometry_msgs_msg_dds__PoseWithCovarianceStamped_;

ParticipantConfig loopback() {
  ParticipantConfig c;
  c.domain_id = 0;
  c.cyclone_config = std::string(RSU_SOURCE_DIR) + "/deploy/cyclonedds-loopback.xml";
  return c;
}

// A topic name no other test process uses at the same time.
std::string unique_topic(const std::string& base) {
  return ros_topic(base + "_" + std::to_string(::getpid()));
}

TEST(RosTopic, PrefixesRtAndDropsLeadingSlash) {
  EXPECT_EQ(ros_topic("points"), "rt/points");
  EXPECT_EQ(ros_topic("/vehicles/7/pose"), "rt/vehicles/7/pose");
}

TEST(DdsWrapper, WriterToReaderRoundTripWithListener) {
  Participant participant(loopback());
  Topic topic(participant, unique_topic("dds_wrapper_test/pose"),
              geometry_msgs_msg_dds__PoseWithCovarianceStamped__desc);
  std::atomic<int> notified{0};
  Reader<PoseStamped> reader(participant, topic, QosConfig{}, [&notified] { ++notified; });
  Writer<PoseStamped> writer(participant, topic, QosConfig{});

  // Local reader and writer match at once (same participant), but wait boundedly all the same.
  for (int i = 0; i < 200 && writer.matched_readers() == 0; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  ASSERT_EQ(writer.matched_readers(), 1U);
  ASSERT_EQ(reader.matched_writers(), 1U);

  PoseStamped msg{};
  msg.header.stamp = {12, 345};
  std::string frame = "map";
  msg.header.frame_id = frame.data();
  msg.pose.pose.position = {1.5, -2.5, 0.0};
  msg.pose.pose.orientation = {0, 0, 0, 1};
  for (int i = 0; i < 36; ++i)
    msg.pose.covariance[i] = i * 0.5;
  writer.write(msg);

  int got = 0;
  for (int i = 0; i < 200 && got == 0; ++i) {
    got += static_cast<int>(reader.take(8, [&](const PoseStamped& s, const dds_sample_info_t& info) {
      EXPECT_EQ(s.header.stamp.sec, 12);
      EXPECT_EQ(s.header.stamp.nanosec, 345U);
      EXPECT_STREQ(s.header.frame_id, "map");
      EXPECT_EQ(s.pose.pose.position.x, 1.5);
      EXPECT_EQ(s.pose.pose.position.y, -2.5);
      EXPECT_EQ(s.pose.covariance[35], 17.5);
      EXPECT_GT(info.source_timestamp, 0);
    }));
    if (got == 0)
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_EQ(got, 1);
  EXPECT_GE(notified.load(), 1);
}

TEST(DdsWrapper, TwoParticipantsInOneProcessShareTheDomain) {
  Participant first(loopback());
  Participant second(loopback());  // the domain exists: created without a second configuration
  EXPECT_NE(first.handle(), second.handle());
}

TEST(DdsWrapper, ErrorsCarryCyclonesText) {
  ParticipantConfig missing;
  missing.cyclone_config = "/nonexistent/cyclone.xml";
  try {
    Participant p(missing);
    FAIL() << "a missing configuration file was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/cyclone.xml"), std::string::npos) << e.what();
  }
  Participant participant(loopback());
  // A topic name with a character DDS forbids is refused by Cyclone.
  try {
    Topic bad(participant, "rt/bad name*", geometry_msgs_msg_dds__PoseWithCovarianceStamped__desc);
    FAIL() << "an invalid topic name was accepted";
  } catch (const DdsError& e) {
    EXPECT_LT(e.code(), 0);
    EXPECT_NE(std::string(e.what()).find(dds_strretcode(e.code())), std::string::npos) << e.what();
  }
}

QosConfig parse_qos(const std::string& yaml) {
  const YAML::Node node = io::parse_yaml(yaml, "qos.yaml");
  const std::string source = "qos.yaml";
  return read_qos_config(io::YamlField(node, "qos", source, 1), QosConfig{});
}

TEST(QosConfig, ReadsEveryKeyAndKeepsDefaults) {
  const QosConfig d = parse_qos("{}");
  EXPECT_EQ(d.reliability, Reliability::kReliable);
  EXPECT_EQ(d.history_depth, QosConfig{}.history_depth);
  const QosConfig q = parse_qos(
      "{reliability: best_effort, durability: transient_local, history_depth: 5, max_blocking_s: 0.5}");
  EXPECT_EQ(q.reliability, Reliability::kBestEffort);
  EXPECT_EQ(q.durability, Durability::kTransientLocal);
  EXPECT_EQ(q.history_depth, 5U);
  EXPECT_EQ(q.max_blocking_s, 0.5);
  // The Cyclone QoS says what the struct says.
  const QosPtr made = make_qos(q);
  dds_reliability_kind_t kind{};
  dds_duration_t blocking = 0;
  ASSERT_TRUE(dds_qget_reliability(made.get(), &kind, &blocking));
  EXPECT_EQ(kind, DDS_RELIABILITY_BEST_EFFORT);
  dds_history_kind_t hist{};
  int32_t depth = 0;
  ASSERT_TRUE(dds_qget_history(made.get(), &hist, &depth));
  EXPECT_EQ(depth, 5);
}

TEST(QosConfig, ErrorsNameTheLineAndField) {
  const auto refused = [](const std::string& yaml, const std::string& expected) {
    try {
      parse_qos(yaml);
      ADD_FAILURE() << "accepted: " << yaml;
    } catch (const io::YamlError& e) {
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
    }
  };
  refused("reliability: sometimes\n", "qos.yaml:1: qos.reliability: expected reliable or best_effort");
  refused("history_depth: 1\nhistory_depht: 2\n", "qos.yaml:2: qos.history_depht: unknown field");
  refused("history_depth: 0\n", "qos.history_depth: must be a whole number");
  refused("durability: forever\n", "qos.durability: expected volatile or transient_local");
}

}  // namespace
}  // namespace rsu::dds
