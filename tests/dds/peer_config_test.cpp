// SPDX-License-Identifier: Apache-2.0
// rsud.yaml's dds.peers section (announcements shared between RSUs): defaults, every key, located errors;
// and v2i.reply_to, which says where rsud answers the announcements it accepts (or shares).
#include <gtest/gtest.h>

#include <string>

#include "daemon/config.h"

namespace rsu::daemon {
namespace {

// A VLP-16 RSU's configuration with these sections (dds:, v2i:, ...) after its lidar: section.
DaemonConfig parse_with(const std::string& sections) {
  return parse_config(
      "rsu_id: 1\n"
      "lidar:\n"
      "  model: vlp16\n"
      "  mount: {x: 0, y: 0, z: 2}\n"
      "  input: {velodyne_udp: {}}\n" +
          sections,
      "/etc/rsud/rsud.yaml");
}

std::string refusal_with(const std::string& sections) {
  try {
    parse_with(sections);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "accepted";
}

TEST(PeerConfig, OffByDefaultBestEffortAndTheCoreLimits) {
  const DaemonConfig c = parse_with("dds: {enabled: true}\n");
  EXPECT_FALSE(c.dds.peers.enabled);
  EXPECT_EQ(c.dds.peers.topic, "rsu/peer_announcements");
  EXPECT_EQ(c.dds.peers.qos.reliability, dds::Reliability::kBestEffort);
  const core::PeerConfig defaults;
  EXPECT_EQ(c.core.peers.flood.bucket.rate_per_s, defaults.flood.bucket.rate_per_s);
  EXPECT_EQ(c.core.peers.flood.bucket.burst, defaults.flood.bucket.burst);
}

TEST(PeerConfig, ReadsEveryKeyIntoTheBusAndTheCore) {
  const DaemonConfig c = parse_with(
      "dds:\n"
      "  enabled: true\n"
      "  peers:\n"
      "    enabled: true\n"
      "    topic: road7/announcements\n"
      "    qos: {reliability: reliable, history_depth: 32}\n"
      "    rate_per_s: 50\n"
      "    burst: 20\n"
      "    max_sources: 8\n");
  EXPECT_TRUE(c.dds.peers.enabled);
  EXPECT_EQ(c.dds.peers.topic, "road7/announcements");
  EXPECT_EQ(c.dds.peers.qos.reliability, dds::Reliability::kReliable);
  EXPECT_EQ(c.dds.peers.qos.history_depth, 32U);
  EXPECT_EQ(c.core.peers.flood.bucket.rate_per_s, 50.0);
  EXPECT_EQ(c.core.peers.flood.bucket.burst, 20.0);
  EXPECT_EQ(c.core.peers.flood.max_sources, 8U);
}

TEST(PeerConfig, ErrorsNameFileLineAndField) {
  EXPECT_EQ(refusal_with("dds:\n  peers: {enabled: true}\n"),
            "/etc/rsud/rsud.yaml:7: dds.peers.enabled: needs the DDS participant: set dds.enabled: true");
  EXPECT_NE(refusal_with("dds:\n  enabled: true\n  peers: {enabled: true, topci: x}\n")
                .find("/etc/rsud/rsud.yaml:8: dds.peers.topci: unknown field"),
            std::string::npos);
  EXPECT_NE(refusal_with("dds:\n  enabled: true\n  peers: {topic: \"a b\"}\n")
                .find("dds.peers.topic: \"a b\" is not a ROS"),
            std::string::npos);
  EXPECT_NE(
      refusal_with("dds:\n  enabled: true\n  peers: {burst: 0.5}\n").find("dds.peers.burst: must be >= 1"),
      std::string::npos);
  EXPECT_NE(refusal_with("dds:\n  enabled: true\n  peers: {max_sources: 0}\n")
                .find("dds.peers.max_sources: must be"),
            std::string::npos);
  EXPECT_NE(
      refusal_with("dds:\n  enabled: true\n  peers: {qos: {history_depth: many}}\n").find("dds.peers.qos"),
      std::string::npos);
}

TEST(V2iReplyToConfig, PoliciesAndTheReplacedKeyNamed) {
  EXPECT_EQ(parse_with("").core.reply_to, core::ReplyToPolicy::kMatchAddressAndPort);
  EXPECT_EQ(parse_with("v2i: {reply_to: match_address}\n").core.reply_to, core::ReplyToPolicy::kMatchAddress);
  EXPECT_EQ(parse_with("v2i: {reply_to: use_source}\n").core.reply_to, core::ReplyToPolicy::kUseSource);
  EXPECT_NE(refusal_with("v2i: {reply_to: anywhere}\n").find("v2i.reply_to: expected match_address_and_port"),
            std::string::npos);
  // A configuration written before v2i.reply_to existed is told what to write instead.
  const std::string old_key = refusal_with("v2i:\n  require_reply_to_source_address: true\n");
  EXPECT_NE(old_key.find("/etc/rsud/rsud.yaml:7: v2i.require_reply_to_source_address: replaced by reply_to"),
            std::string::npos)
      << old_key;
  EXPECT_NE(old_key.find("`reply_to: match_address` for true"), std::string::npos) << old_key;
}

// v2i.refusal_notices and v2i.withheld_notices: the documented defaults (deploy/rsud.yaml), every key,
// and a rate or interval that is not positive refused with its place.
TEST(V2iNoticesConfig, DefaultsEveryKeyAndLocatedErrors) {
  const DaemonConfig defaults = parse_with("");
  EXPECT_TRUE(defaults.core.withheld_notices.enabled);
  EXPECT_EQ(defaults.core.withheld_notices.per_vehicle_interval_s, 1.0);
  EXPECT_EQ(defaults.core.withheld_notices.rate_per_s, 200.0);
  EXPECT_EQ(defaults.core.refusal_notices.rate_per_s, 50.0);
  const DaemonConfig c = parse_with(
      "v2i:\n"
      "  withheld_notices: {enabled: false, per_vehicle_interval_s: 2.5, rate_per_s: 20}\n"
      "  refusal_notices: {rate_per_s: 5}\n");
  EXPECT_FALSE(c.core.withheld_notices.enabled);
  EXPECT_EQ(c.core.withheld_notices.per_vehicle_interval_s, 2.5);
  EXPECT_EQ(c.core.withheld_notices.rate_per_s, 20.0);
  EXPECT_EQ(c.core.refusal_notices.rate_per_s, 5.0);
  EXPECT_TRUE(c.core.refusal_notices.enabled);
  EXPECT_NE(refusal_with("v2i:\n  withheld_notices: {rate_per_s: 0}\n")
                .find("/etc/rsud/rsud.yaml:7: v2i.withheld_notices.rate_per_s"),
            std::string::npos);
  EXPECT_NE(refusal_with("v2i:\n  withheld_notices: {per_vehicle_interval_s: -1}\n")
                .find("v2i.withheld_notices.per_vehicle_interval_s"),
            std::string::npos);
  EXPECT_NE(refusal_with("v2i:\n  withheld_notices: {every: 1}\n")
                .find("v2i.withheld_notices.every: unknown field"),
            std::string::npos);
}

}  // namespace
}  // namespace rsu::daemon
