// SPDX-License-Identifier: Apache-2.0
// rsud's configuration file (YAML; deploy/rsud.yaml is the annotated example). Read through
// io::YamlField, so every error names the file, the line and the field, e.g.
//   /etc/rsud/rsud.yaml:14: lidar.mount.z: expected a number, got "two"
// Unknown keys are errors: a misspelt key silently falling back to a default is the worst kind of bug
// in a daemon's configuration.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>
#include <variant>
#include <vector>

#include "core/rsu_core_config.h"
#include "dds/participant.h"
#include "dds/qos_config.h"
#include "ros/pointcloud2_layout.h"

namespace rsu::daemon {

// The LiDAR's UDP packets as they arrive (lidar.input.udp; velodyne_udp is the same, its older name).
struct UdpInput {
  std::string bind_address = "0.0.0.0";
  // Velodyne: 2368 unless set (docs/design.md §2); Ouster: 0 unless set, the metadata's udp_port_lidar (0:
  // the decoder's default data port).
  std::uint16_t port = 2368;
  // A second port for the sensor's packets without points (Velodyne position packets, 8308: their
  // $GPRMC gives the data packets' hour); 0: not listened to.
  std::uint16_t auxiliary_port = 0;
  // Packets held to put reordered ones back in time order (lidar/packet_order.h); each adds one
  // packet period of latency (VLP-32C 0.66 ms). 0: a late packet is dropped and counted.
  std::size_t reorder_packets = 0;
  // Asked of the kernel for the data socket (read back and warned about when net.core.rmem_max caps
  // it): ~1500 packets/s (VLP-32C) or ~2600 (a 128-ring sensor at 20 Hz), so 4 MiB hold over a second of
  // them should the loop ever stall.
  std::size_t receive_buffer_bytes = 4 << 20;
};

// A recorded capture (classic pcap: Ethernet, 802.1Q or Linux cooked link type) replayed as if it
// arrived now: the run's clock is the capture's (each datagram's record time), so a replay is the
// same every time. The datagrams to the sensor's ports are decoded; everything else is counted.
struct PcapInput {
  std::string file;
  enum class Pace { kRealtime, kMax } pace = Pace::kRealtime;
  bool loop = false;                 // at the end, start again (the clock moves on by whole hours)
  std::uint16_t port = 0;            // 0: the sensor's data port
  std::uint16_t auxiliary_port = 0;  // 0: the sensor's (Velodyne position packets: 8308)
};

// Whole frames read from PCD files (sensor frame, as `rsu-sim simulate` writes them), replayed in a
// loop at rate_hz with their point times moved to the host clock.
struct PcdInput {
  std::vector<std::string> files;
  double rate_hz = 10.0;
};

// sensor_msgs/PointCloud2 from a ROS 2 LiDAR driver over DDS (needs dds.enabled). Points in the
// LiDAR's own frame: lidar.mount places them, whatever header.frame_id says.
struct DdsPointCloud2Input {
  std::string topic = "points";  // ROS name; "rt/points" on the wire
  dds::QosConfig qos;
  // true: each message is one whole rotation (ROS drivers' default), its clusters released at its
  // end; false: each message is a part of a rotation in firing order, released as the sweep passes.
  bool whole_rotation = true;
  ros::RingOrder ring_order = ros::RingOrder::kChannel;  // kElevation: the Velodyne ROS drivers' ring
  // When set, clouds with another header.frame_id are refused (another sensor's cloud on the topic
  // would be placed with this LiDAR's mount); empty: any.
  std::string frame_id;
};

using LidarInput = std::variant<UdpInput, PcdInput, DdsPointCloud2Input, PcapInput>;

// The Velodyne calibration file (lidar.calibration), read by load_lidar_files() into
// core.sensor_options.calibrated_model (an Ouster's metadata path is core.sensor_options.metadata_source).
struct SensorFiles {
  std::string calibration;  // io/velodyne_calibration.h
};

// The announcements the RSUs of a road share over the bus (daemon/peer_bus.h; README, "Several RSUs on
// one bus"). The per-origin-RSU rate limit is the core's (core::PeerConfig). Needs dds.enabled.
struct PeerBusConfig {
  bool enabled = false;
  std::string topic = "rsu/peer_announcements";  // ROS name; every RSU of the road uses the same
  // Best effort: the writer never blocks rsud's thread on a lagging peer, and a lost announcement is
  // superseded by the vehicle's next one. Samples have no key, so the depth is shared by all vehicles:
  // deep enough for a burst of every vehicle of a busy road.
  dds::QosConfig qos{.reliability = dds::Reliability::kBestEffort, .history_depth = 256};
};

// The DDS data bus (Cyclone DDS, ROS 2 compatible; docs/design.md §5). Off by default.
struct DdsConfig {
  bool enabled = false;
  dds::ParticipantConfig participant;
  // Each correction as geometry_msgs/PoseWithCovarianceStamped on this ROS topic, "{vehicle_id}"
  // replaced by the vehicle's id; empty: not published.
  std::string pose_topic = "vehicles/{vehicle_id}/rsu/pose_with_covariance";
  std::string frame_id = "map";  // header.frame_id of the poses and the object list
  dds::QosConfig pose_qos;
  // Every current fix (rsu_msgs/VehicleFixArray) once per rotation; empty: not published.
  std::string object_list_topic = "rsu/vehicle_fixes";
  dds::QosConfig object_list_qos;
  double object_list_max_age_s = 0.3;  // a fix older than this (sweep time) is no longer current
  PeerBusConfig peers;
};

struct AdvertisementConfig {
  bool enabled = false;
  std::string address = "255.255.255.255";  // where RsuAdvertisement datagrams go (broadcast allowed)
  std::uint16_t port = 4501;
  double interval_s = 1.0;
};

struct LoggingConfig {
  std::string level = "info";  // trace, debug, info, warn, error
  // Bad input: the first `bad_input_log_first` of each reason are logged one by one, then a summary of
  // the counts every `summary_interval_s` while more arrive.
  int bad_input_log_first = 5;
  double summary_interval_s = 10.0;
  double stats_interval_s = 60.0;  // all counters at info level; 0 disables
};

// Prometheus metrics (daemon/metrics_text.h) as a node_exporter textfile: written atomically (a
// temporary file renamed over it), mode 0644 so that node_exporter's user can read it.
struct MetricsConfig {
  std::string textfile;      // empty: no metrics; must end in .prom for node_exporter to read it
  double interval_s = 10.0;  // how often it is rewritten (and on exit)
};

// Where the RSU's keys come from (security: section). The mode and replay limits go to
// core.security; load_security() reads the files into core.signing_key and core.trust_list.
// Signed is the default, also when the file has no security: section; the files then are these.
struct SecurityFiles {
  std::string key_file = "/etc/rsud/keys/rsu.key";            // the RSU's Ed25519 secret key (rsu-keygen)
  std::string trust_list_file = "/etc/rsud/keys/trust.list";  // keys accepted (v2i/security/trust_list.h)
  bool key_file_exposed = false;  // load_security(): the secret key is readable by group or others
};

// What rsud keeps between runs and finds there (README, "Calibrating the mount").
struct StateConfig {
  // Empty: $STATE_DIRECTORY (what systemd's StateDirectory= made: /var/lib/rsud), and without it
  // nothing is kept (a restart learns the background again).
  std::string directory;
  // The learned background is saved there (io/background_state.h) and loaded at start, unless the
  // configuration lists background.pcd_files.
  bool persist_background = true;
  // <directory>/calibration.yaml, rsu-calibrate's report (--out), replaces lidar.mount when its
  // verdict is good.
  bool use_calibration = true;
};

struct DaemonConfig {
  std::string source;  // the file it was read from
  core::RsuCoreConfig core;
  SecurityFiles security;
  SensorFiles sensor_files;
  LidarInput input;
  std::vector<std::string> background_pcd_files;  // when set: the background, instead of learning
  std::string v2i_listen_address = "0.0.0.0";
  std::uint16_t v2i_port = 4500;
  // Asked of the kernel for the V2I socket: 1000 vehicles at 10 Hz are 10 000 announcements/s of
  // ~200 bytes (with their bookkeeping ~1 KiB each in the kernel): 8 MiB hold ~0.8 s of them.
  std::size_t v2i_receive_buffer_bytes = 8 << 20;
  // true: the announcement socket read, and signatures checked, on a thread of its own
  // (daemon/v2i_receiver.h). Off by default: on 2 cores the event loop alone measured lower latency and
  // less CPU at 1000 signed vehicles x 10 Hz, nothing lost either way (README, "Robustness", load).
  bool v2i_verifier_thread = false;
  // mount_integrity.check_thread: the mount check's registration on a thread of its own (live input;
  // a capture replay checks on the loop, so that its output does not depend on the host's timing).
  // Taking effect at a restart.
  bool mount_check_thread = true;
  // perception.prepare_thread: the fits and fixes prepared ahead of a vehicle's release
  // (core/prepared_fixes.h) on a thread of their own (live input, as the mount check). Off by default: on
  // 2 cores, with an OS1-128, its results came back too late for 60 % of the releases, which then computed
  // the fix on the loop, and the p99 latency was no lower (README, Benchmarks). Taking effect at a restart.
  bool prepare_thread = false;
  AdvertisementConfig advertisement;
  DdsConfig dds;
  LoggingConfig logging;
  // Where --stats-file style snapshots go: empty disables. Written on every stats interval and on exit.
  std::string stats_file;
  MetricsConfig metrics;
  StateConfig state;
  // Set by load_state_calibration: where core.mount came from (lidar.mount, or the calibration file),
  // and what the operator should hear about the state directory's calibration (logged at start).
  std::string mount_source = "lidar.mount";
  std::vector<std::string> state_warnings;
};

class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Throws ConfigError "<source>:<line>: <field>: <what is wrong>" (or the core's complaint about an
// unusable combination, e.g. an unknown LiDAR model). Relative paths in the file (PCD files,
// key files) are taken relative to the file's folder. parse_config reads no other file: the key files
// are read by load_security().
DaemonConfig parse_config(const std::string& yaml_text, const std::string& source_name);
// Reads the key file and the trust list named in config.security into config.core (signed mode; in
// insecure mode nothing is read). Throws ConfigError naming the file (and line) when one is missing,
// unreadable or malformed.
void load_security(DaemonConfig& config);
// Reads the LiDAR's own files named in the configuration (lidar.metadata, lidar.calibration) into
// config.core.sensor_options (the decoder checks the metadata's content when RsuCore makes it; the
// calibration is applied here). Throws ConfigError naming the file (and line) when one is missing or
// malformed.
void load_lidar_files(DaemonConfig& config);
// Resolves state.directory ($STATE_DIRECTORY when empty) and, when state.use_calibration and
// <directory>/calibration.yaml exists with verdict good, takes its mount as core.mount (mount_source
// names the file). A calibration that is not good, or a file that cannot be read, leaves lidar.mount in
// effect and says why in state_warnings: never fatal, never silent.
void load_state_calibration(DaemonConfig& config);
// Where rsud's configuration comes from: the file, and what the command line overrides in it.
struct ConfigSource {
  std::string path;
  // Non-empty: replaces security.key_file (rsud --key; under the shipped systemd unit the credential
  // systemd loaded for rsud, %d/rsu.key, since the service's own user cannot read /etc/rsud/keys/rsu.key).
  std::string key_file;
};

// parse_config + the overrides + load_lidar_files + load_security + load_state_calibration.
DaemonConfig load_config(const ConfigSource& source);

// A few lines describing the configuration (for --check-config and the start-up log).
std::string summarize(const DaemonConfig& config);

}  // namespace rsu::daemon
