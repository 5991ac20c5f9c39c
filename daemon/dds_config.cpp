// SPDX-License-Identifier: Apache-2.0
#include "daemon/dds_config.h"

#include <cmath>

namespace rsu::daemon {

namespace {

using io::YamlField;

bool flag_of(const YamlField& f) {
  const std::string v = f.text();
  if (v != "true" && v != "false")
    f.fail("expected true or false, got \"" + v + "\"");
  return v == "true";
}

// A ROS 2 topic name: [A-Za-z0-9_/{}~] (ROS's rules, plus the {vehicle_id} placeholder), not ending
// in '/', no "//". Empty allowed only where `may_be_empty` (the output is then off).
std::string topic_of(const YamlField& f, bool may_be_empty) {
  const std::string t = f.text();
  if (t.empty()) {
    if (!may_be_empty)
      f.fail("expected a topic name");
    return t;
  }
  for (const char ch : t) {
    const bool ok = (ch >= 'a' && ch <= 'z') || (ch >= 'A' && ch <= 'Z') || (ch >= '0' && ch <= '9') ||
                    ch == '_' || ch == '/' || ch == '{' || ch == '}' || ch == '~';
    if (!ok)
      f.fail("\"" + t + "\" is not a ROS topic name (letters, digits, _ and / only)");
  }
  if (t.back() == '/' || t.find("//") != std::string::npos)
    f.fail("\"" + t + "\" is not a ROS topic name (empty segment)");
  return t;
}

PeerBusConfig read_peers(const YamlField& f, core::PeerConfig& limits) {
  f.expect_map({"enabled", "topic", "qos", "rate_per_s", "burst", "max_sources"});
  PeerBusConfig c;
  if (f.has("enabled"))
    c.enabled = flag_of(f.child("enabled"));
  if (f.has("topic")) {
    c.topic = topic_of(f.child("topic"), false);
    if (c.topic.find_first_of("{}") != std::string::npos)
      f.child("topic").fail("must not contain { or }");
  }
  if (f.has("qos"))
    c.qos = dds::read_qos_config(f.child("qos"), c.qos);
  auto& l = limits.flood;
  l.bucket.rate_per_s = f.positive_or("rate_per_s", l.bucket.rate_per_s);
  l.bucket.burst = f.positive_or("burst", l.bucket.burst);
  if (l.bucket.burst < 1)
    f.child("burst").fail("must be >= 1");
  if (f.has("max_sources")) {
    const double v = f.child("max_sources").number();
    if (v < 1 || v > 1e6 || v != std::floor(v))
      f.child("max_sources").fail("must be a whole number within [1, 1000000]");
    l.max_sources = static_cast<std::size_t>(v);
  }
  return c;
}

}  // namespace

DdsConfig read_dds_config(const YamlField& f, const std::filesystem::path& base, core::PeerConfig& peers) {
  f.expect_map({"enabled", "domain_id", "cyclone_config", "pose_topic", "frame_id", "pose_qos",
                "object_list_topic", "object_list_qos", "object_list_max_age_s", "peers"});
  DdsConfig c;
  if (f.has("enabled"))
    c.enabled = flag_of(f.child("enabled"));
  if (f.has("domain_id")) {
    const YamlField d = f.child("domain_id");
    const double v = d.number();
    if (v < 0 || v > 232 || v != std::floor(v))
      d.fail("must be a whole number within [0, 232]");
    c.participant.domain_id = static_cast<std::uint32_t>(v);
  }
  if (f.has("cyclone_config")) {
    const std::filesystem::path p = f.child("cyclone_config").text();
    if (!p.empty())
      c.participant.cyclone_config = (p.is_absolute() ? p : base / p).lexically_normal().string();
  }
  if (f.has("pose_topic")) {
    c.pose_topic = topic_of(f.child("pose_topic"), true);
    if (!c.pose_topic.empty() && c.pose_topic.find("{vehicle_id}") == std::string::npos)
      f.child("pose_topic").fail("must contain {vehicle_id} (one topic per vehicle)");
  }
  if (f.has("frame_id")) {
    c.frame_id = f.child("frame_id").text();
    if (c.frame_id.empty())
      f.child("frame_id").fail("expected a frame name, e.g. map");
  }
  if (f.has("pose_qos"))
    c.pose_qos = dds::read_qos_config(f.child("pose_qos"), c.pose_qos);
  if (f.has("object_list_topic")) {
    c.object_list_topic = topic_of(f.child("object_list_topic"), true);
    if (c.object_list_topic.find_first_of("{}") != std::string::npos)
      f.child("object_list_topic").fail("must not contain { or }");
  }
  if (f.has("object_list_qos"))
    c.object_list_qos = dds::read_qos_config(f.child("object_list_qos"), c.object_list_qos);
  c.object_list_max_age_s = f.positive_or("object_list_max_age_s", c.object_list_max_age_s);
  if (f.has("peers")) {
    c.peers = read_peers(f.child("peers"), peers);
    if (c.peers.enabled && !c.enabled)
      f.child("peers").child("enabled").fail("needs the DDS participant: set dds.enabled: true");
  }
  return c;
}

DdsPointCloud2Input read_dds_pointcloud2_input(const YamlField& f) {
  f.expect_map({"topic", "qos", "whole_rotation", "ring_order", "frame_id"});
  DdsPointCloud2Input in;
  if (f.has("topic")) {
    in.topic = topic_of(f.child("topic"), false);
    if (in.topic.find_first_of("{}") != std::string::npos)
      f.child("topic").fail("must not contain { or }");
  }
  if (f.has("qos"))
    in.qos = dds::read_qos_config(f.child("qos"), in.qos);
  if (f.has("whole_rotation"))
    in.whole_rotation = flag_of(f.child("whole_rotation"));
  if (f.has("ring_order")) {
    const YamlField r = f.child("ring_order");
    const std::string v = r.text();
    if (v == "channel")
      in.ring_order = ros::RingOrder::kChannel;
    else if (v == "elevation")
      in.ring_order = ros::RingOrder::kElevation;
    else
      r.fail("expected channel or elevation, got \"" + v + "\"");
  }
  if (f.has("frame_id"))
    in.frame_id = f.child("frame_id").text();
  return in;
}

std::string vehicle_pose_topic(const std::string& pattern, std::uint64_t vehicle_id) {
  static constexpr std::string_view kPlaceholder = "{vehicle_id}";
  std::string out = pattern;
  for (std::size_t at = out.find(kPlaceholder); at != std::string::npos;
       at = out.find(kPlaceholder, at + 1)) {
    out.replace(at, kPlaceholder.size(), std::to_string(vehicle_id));
  }
  return out;
}

}  // namespace rsu::daemon
