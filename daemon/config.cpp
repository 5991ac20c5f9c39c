// SPDX-License-Identifier: Apache-2.0
#include "daemon/config.h"

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <sstream>

#include "common/angles.h"
#include "daemon/dds_config.h"
#include "io/mount_calibration_file.h"
#include "io/velodyne_calibration.h"
#include "io/yaml_field.h"
#include "lidar/lidar_decoder.h"
#include "lidar/ouster/ouster_lidar_decoder.h"
#include "lidar/sensor_model.h"
#include "lidar/velodyne_packet.h"
#include "v2i/security/key_text.h"

namespace rsu::daemon {

namespace {

using io::YamlField;

std::uint16_t port_of(const YamlField& f) {
  const double v = f.number();
  if (v < 1 || v > 65535 || v != std::floor(v))
    f.fail("must be a port number within [1, 65535]");
  return static_cast<std::uint16_t>(v);
}

// A port, or 0 for "the sensor's own" / "none" (lidar.input.udp and pcap).
std::uint16_t port_or_zero_of(const YamlField& f) {
  const double v = f.number();
  if (v < 0 || v > 65535 || v != std::floor(v))
    f.fail("must be a port number within [1, 65535], or 0");
  return static_cast<std::uint16_t>(v);
}

std::uint64_t unsigned_of(const YamlField& f, double max) {
  const double v = f.number();
  if (v < 0 || v > max || v != std::floor(v))
    f.fail("must be a whole number within [0, " + std::to_string(max) + "]");
  return static_cast<std::uint64_t>(v);
}

// A socket receive buffer: at least 64 KiB (less would drop a burst of one LiDAR rotation's packets),
// at most 1 GiB (the kernel's int).
std::size_t receive_buffer_of(const YamlField& f) {
  const std::uint64_t v = unsigned_of(f, 1 << 30);
  if (v < (64u << 10))
    f.fail("must be at least 65536 bytes");
  return static_cast<std::size_t>(v);
}

std::string address_of(const YamlField& f) {
  const std::string text = f.text();
  if (text.empty())
    f.fail("expected an IP address");
  return text;  // checked when the socket is made (Asio's parser) and by --check-config
}

std::string path_of(const YamlField& f, const std::filesystem::path& base) {
  const std::filesystem::path p = f.text();
  if (p.empty())
    f.fail("expected a file path");
  return (p.is_absolute() ? p : base / p).lexically_normal().string();
}

Pose3 read_mount(const YamlField& f) {
  f.expect_map({"x", "y", "z", "roll_deg", "pitch_deg", "yaw_deg"});
  Pose3 p;
  p.x = f.required("x").number();
  p.y = f.required("y").number();
  p.z = f.required("z").number();
  p.roll = f.angle_deg_or("roll_deg", 0.0);
  p.pitch = f.angle_deg_or("pitch_deg", 0.0);
  p.yaw = f.angle_deg_or("yaw_deg", 0.0);
  return p;
}

bool bool_of(const YamlField& f) {
  const std::string v = f.text();
  if (v != "true" && v != "false")
    f.fail("expected true or false");
  return v == "true";
}

UdpInput read_udp_input(const YamlField& u) {
  u.expect_map({"bind_address", "port", "auxiliary_port", "reorder_packets", "receive_buffer_bytes"});
  UdpInput in;
  in.port = 0;  // the sensor's data port unless set: read_lidar() (Velodyne) or rsud (the metadata's)
  if (u.has("bind_address"))
    in.bind_address = address_of(u.child("bind_address"));
  if (u.has("port"))
    in.port = port_or_zero_of(u.child("port"));
  if (u.has("auxiliary_port"))
    in.auxiliary_port = port_or_zero_of(u.child("auxiliary_port"));
  if (u.has("reorder_packets"))
    in.reorder_packets = unsigned_of(u.child("reorder_packets"), 64);
  if (u.has("receive_buffer_bytes"))
    in.receive_buffer_bytes = receive_buffer_of(u.child("receive_buffer_bytes"));
  return in;
}

PcapInput read_pcap_input(const YamlField& p, const std::filesystem::path& base) {
  p.expect_map({"file", "pace", "loop", "port", "auxiliary_port"});
  PcapInput in;
  in.file = path_of(p.required("file"), base);
  if (p.has("pace")) {
    const std::string v = p.child("pace").text();
    if (v == "realtime")
      in.pace = PcapInput::Pace::kRealtime;
    else if (v == "max")
      in.pace = PcapInput::Pace::kMax;
    else
      p.child("pace").fail("expected realtime or max, got \"" + v + "\"");
  }
  if (p.has("loop"))
    in.loop = bool_of(p.child("loop"));
  if (p.has("port"))
    in.port = port_or_zero_of(p.child("port"));
  if (p.has("auxiliary_port"))
    in.auxiliary_port = port_or_zero_of(p.child("auxiliary_port"));
  return in;
}

LidarInput read_input(const YamlField& f, const std::filesystem::path& base) {
  f.expect_map({"udp", "velodyne_udp", "pcap", "pcd", "dds_pointcloud2"});
  const int kinds = int{f.has("udp")} + int{f.has("velodyne_udp")} + int{f.has("pcap")} + int{f.has("pcd")} +
                    int{f.has("dds_pointcloud2")};
  if (kinds != 1)
    f.fail("exactly one of udp (velodyne_udp), pcap, pcd, dds_pointcloud2 is required");
  if (f.has("dds_pointcloud2"))
    return read_dds_pointcloud2_input(f.child("dds_pointcloud2"));
  if (f.has("udp"))
    return read_udp_input(f.child("udp"));
  if (f.has("velodyne_udp"))
    return read_udp_input(f.child("velodyne_udp"));
  if (f.has("pcap"))
    return read_pcap_input(f.child("pcap"), base);
  {
    const YamlField p = f.child("pcd");
    p.expect_map({"files", "rate_hz"});
    PcdInput in;
    for (const YamlField& file : p.required("files").items())
      in.files.push_back(path_of(file, base));
    if (in.files.empty())
      p.child("files").fail("needs at least one file");
    in.rate_hz = p.positive_or("rate_hz", in.rate_hz);
    if (in.rate_hz > 100)
      p.child("rate_hz").fail("must be <= 100 Hz");
    return in;
  }
}

void read_lidar(const YamlField& f, DaemonConfig& c, const std::filesystem::path& base) {
  f.expect_map({"model", "calibration", "metadata", "returns", "scan_phase_deg", "time_source",
                "clock_tolerance_ms", "mount", "input", "max_packet_age_ms"});
  const YamlField model = f.required("model");
  c.core.sensor_model = model.text();
  if (!lidar::is_decodable_model(c.core.sensor_model))
    model.fail("unknown LiDAR model \"" + c.core.sensor_model + "\" (expected " +
               std::string(lidar::kDecodableModels) + ")");
  // An Ouster's metadata JSON (its beams and packet format); read by load_lidar_files().
  const bool ouster = lidar::ouster::is_ouster_model(c.core.sensor_model);
  if (f.has("metadata")) {
    if (!ouster)
      f.child("metadata")
          .fail("the metadata JSON is for Ouster sensors; " + c.core.sensor_model + " has none");
    c.core.sensor_options.metadata_source = path_of(f.child("metadata"), base);
  } else if (ouster) {
    model.fail(
        "an Ouster needs lidar.metadata: the JSON the sensor (or the Ouster SDK, next to a recording) wrote");
  }
  // A Velodyne unit's calibration file; read (and applied) by load_lidar_files().
  if (f.has("calibration")) {
    if (!lidar::sensor_model_by_name(c.core.sensor_model))
      f.child("calibration").fail("a Velodyne calibration file; the " + c.core.sensor_model + " takes none");
    c.sensor_files.calibration = path_of(f.child("calibration"), base);
  }
  lidar::LidarDecoderOptions& sensor = c.core.sensor_options;
  if (f.has("returns")) {
    const YamlField r = f.child("returns");
    const auto selection = lidar::return_selection_by_name(r.text());
    if (!selection)
      r.fail("expected both, strongest or last, got \"" + r.text() + "\"");
    sensor.returns = *selection;
  }
  sensor.rotation_start_azimuth_deg = f.number_or("scan_phase_deg", 0.0);
  if (sensor.rotation_start_azimuth_deg < 0 || sensor.rotation_start_azimuth_deg >= 360)
    f.child("scan_phase_deg").fail("must be within [0, 360) deg");
  if (f.has("time_source")) {
    const YamlField t = f.child("time_source");
    const std::string v = t.text();
    if (v == "sensor")
      c.core.time_source = core::TimeSource::kSensor;
    else if (v == "host_receive")
      c.core.time_source = core::TimeSource::kHostReceive;
    else
      t.fail("expected sensor or host_receive, got \"" + v + "\"");
  }
  if (f.has("clock_tolerance_ms")) {
    const double ms = f.positive_or("clock_tolerance_ms", 100.0);
    if (ms > 3600e3)
      f.child("clock_tolerance_ms").fail("must be <= 3600000 ms");
    c.core.clock_tolerance = static_cast<TimeNs>(ms * 1e6);
  }
  c.core.mount = read_mount(f.required("mount"));
  c.input = read_input(f.required("input"), base);
  if (auto* u = std::get_if<UdpInput>(&c.input)) {
    c.core.packet_order.depth = u->reorder_packets;
    if (u->port == 0 && !ouster)
      u->port = lidar::kVelodyneDataPort;  // an Ouster's comes from its metadata (rsud resolves it)
  }
  if (f.has("max_packet_age_ms")) {
    const double ms = f.non_negative_or("max_packet_age_ms", 0.0);
    if (ms > 60000)
      f.child("max_packet_age_ms").fail("must be <= 60000 ms");
    c.core.max_packet_age = static_cast<TimeNs>(ms * 1e6);
  }
}

void read_background(const YamlField& f, DaemonConfig& c, const std::filesystem::path& base) {
  f.expect_map({"learning_frames", "pcd_files"});
  if (f.has("learning_frames"))
    c.core.background.learning_frames = static_cast<int>(unsigned_of(f.child("learning_frames"), 10000));
  if (f.has("pcd_files")) {
    for (const YamlField& file : f.child("pcd_files").items())
      c.background_pcd_files.push_back(path_of(file, base));
  }
}

void read_perception(const YamlField& f, DaemonConfig& c) {
  f.expect_map({"background_method", "ground_z", "ground_min_height_m", "range_image_margin_m",
                "reference_match_radius_m", "cluster_tolerance_m", "cluster_min_points", "cluster_max_points",
                "correction", "max_position_sigma_m", "coverage_radius_m", "release_margin_deg",
                "joint_release_range_gap_m", "footprint_track", "prepare_thread", "release_fixed_open"});
  auto& p = c.core.perception;
  if (f.has("background_method")) {
    const YamlField m = f.child("background_method");
    const std::string v = m.text();
    if (v == "range_image")
      p.background = perception::BackgroundMethod::range_image;
    else if (v == "reference_frame")
      p.background = perception::BackgroundMethod::reference_frame;
    else if (v == "ground_height")
      p.background = perception::BackgroundMethod::ground_height;
    else
      m.fail("expected range_image, reference_frame or ground_height, got \"" + v + "\"");
  }
  if (f.has("prepare_thread"))
    c.prepare_thread = bool_of(f.child("prepare_thread"));
  if (f.has("release_fixed_open"))
    c.core.release_fixed_open = bool_of(f.child("release_fixed_open"));
  p.ground.ground_z = f.number_or("ground_z", p.ground.ground_z);
  p.ground.min_height = f.non_negative_or("ground_min_height_m", p.ground.min_height);
  p.range_image.margin_m = f.non_negative_or("range_image_margin_m", p.range_image.margin_m);
  p.reference_frame.match_radius_m =
      f.positive_or("reference_match_radius_m", p.reference_frame.match_radius_m);
  p.clustering.tolerance_m = f.positive_or("cluster_tolerance_m", p.clustering.tolerance_m);
  if (p.clustering.tolerance_m > 5)
    f.child("cluster_tolerance_m").fail("must be <= 5 m");
  if (f.has("cluster_min_points"))
    p.clustering.min_points = unsigned_of(f.child("cluster_min_points"), 1e6);
  if (f.has("cluster_max_points"))
    p.clustering.max_points = unsigned_of(f.child("cluster_max_points"), 1e7);
  if (p.clustering.min_points < 3)
    f.child("cluster_min_points").fail("must be >= 3 (a rectangle needs 3 points)");
  if (p.clustering.max_points < p.clustering.min_points)
    f.child("cluster_max_points").fail("must be >= cluster_min_points");
  if (f.has("correction")) {
    const YamlField m = f.child("correction");
    const std::string v = m.text();
    if (v == "improved")
      p.fix.method = perception::CorrectionMethod::improved;
    else if (v == "algorithm1")
      p.fix.method = perception::CorrectionMethod::algorithm1;
    else
      m.fail("expected improved or algorithm1, got \"" + v + "\"");
  }
  auto& correction = p.fix.correction;
  correction.max_position_sigma_m = f.positive_or("max_position_sigma_m", correction.max_position_sigma_m);
  if (correction.max_position_sigma_m > 10)
    f.child("max_position_sigma_m").fail("must be <= 10 m");
  c.core.coverage_radius_m = f.positive_or("coverage_radius_m", c.core.coverage_radius_m);
  c.core.sweep.release_margin_deg = f.non_negative_or("release_margin_deg", c.core.sweep.release_margin_deg);
  if (c.core.sweep.release_margin_deg > 30)
    f.child("release_margin_deg").fail("must be <= 30 deg");
  c.core.sweep.joint_release_range_gap_m =
      f.non_negative_or("joint_release_range_gap_m", c.core.sweep.joint_release_range_gap_m);
  if (f.has("footprint_track"))
    c.core.footprint_track.enabled = bool_of(f.child("footprint_track"));
}

// v2i.refusal_notices, v2i.withheld_notices: whether, and how often, a vehicle is told why it gets nothing.
void read_notices(const YamlField& n, core::NoticeConfig& r) {
  n.expect_map({"enabled", "per_vehicle_interval_s", "rate_per_s"});
  if (n.has("enabled"))
    r.enabled = bool_of(n.child("enabled"));
  r.per_vehicle_interval_s = n.positive_or("per_vehicle_interval_s", r.per_vehicle_interval_s);
  r.rate_per_s = n.positive_or("rate_per_s", r.rate_per_s);
}

void read_v2i(const YamlField& f, DaemonConfig& c) {
  // The key before v2i.reply_to: a configuration written for it names its replacement instead of
  // "unknown field" (true checked the address only; false trusted any reply_to, which no policy does now).
  if (f.has("require_reply_to_source_address"))
    f.child("require_reply_to_source_address")
        .fail(
            "replaced by reply_to: write `reply_to: match_address` for true, `reply_to: use_source` for "
            "false (vehicles behind NAT), or leave it out for the default match_address_and_port");
  f.expect_map({"listen_address", "port", "reply_to", "refusal_notices", "withheld_notices", "advertisement",
                "receive_buffer_bytes", "verifier_thread"});
  if (f.has("listen_address"))
    c.v2i_listen_address = address_of(f.child("listen_address"));
  if (f.has("port"))
    c.v2i_port = port_of(f.child("port"));
  if (f.has("receive_buffer_bytes"))
    c.v2i_receive_buffer_bytes = receive_buffer_of(f.child("receive_buffer_bytes"));
  if (f.has("verifier_thread"))
    c.v2i_verifier_thread = bool_of(f.child("verifier_thread"));
  if (f.has("reply_to")) {
    const YamlField r = f.child("reply_to");
    const std::string v = r.text();
    if (v == "match_address_and_port")
      c.core.reply_to = core::ReplyToPolicy::kMatchAddressAndPort;
    else if (v == "match_address")
      c.core.reply_to = core::ReplyToPolicy::kMatchAddress;
    else if (v == "use_source")
      c.core.reply_to = core::ReplyToPolicy::kUseSource;
    else
      r.fail("expected match_address_and_port, match_address or use_source, got \"" + v + "\"");
  }
  if (f.has("refusal_notices"))
    read_notices(f.child("refusal_notices"), c.core.refusal_notices);
  if (f.has("withheld_notices"))
    read_notices(f.child("withheld_notices"), c.core.withheld_notices);
  if (f.has("advertisement")) {
    const YamlField a = f.child("advertisement");
    a.expect_map({"enabled", "address", "port", "interval_s"});
    if (a.has("enabled"))
      c.advertisement.enabled = bool_of(a.child("enabled"));
    if (a.has("address"))
      c.advertisement.address = address_of(a.child("address"));
    if (a.has("port"))
      c.advertisement.port = port_of(a.child("port"));
    c.advertisement.interval_s = a.positive_or("interval_s", c.advertisement.interval_s);
  }
  c.core.announcement_port = c.v2i_port;
  c.core.correction_port = c.v2i_port;  // corrections leave from the announcement socket
}

void read_registry(const YamlField& f, DaemonConfig& c) {
  f.expect_map({"capacity", "silence_timeout_s", "rate_per_s", "burst", "max_sources"});
  auto& r = c.core.registry;
  if (f.has("capacity"))
    r.capacity = unsigned_of(f.child("capacity"), 1e6);
  if (r.capacity == 0)
    f.child("capacity").fail("must be >= 1");
  r.silence_timeout = from_seconds(f.positive_or("silence_timeout_s", to_seconds(r.silence_timeout)));
  r.rate_limit.bucket.rate_per_s = f.positive_or("rate_per_s", r.rate_limit.bucket.rate_per_s);
  r.rate_limit.bucket.burst = f.positive_or("burst", r.rate_limit.bucket.burst);
  if (r.rate_limit.bucket.burst < 1)
    f.child("burst").fail("must be >= 1");
  if (f.has("max_sources"))
    r.rate_limit.max_sources = unsigned_of(f.child("max_sources"), 1e7);
}

void read_flood(const YamlField& f, DaemonConfig& c) {
  f.expect_map({"rate_per_s", "burst", "max_sources"});
  auto& l = c.core.datagram_flood;
  l.bucket.rate_per_s = f.positive_or("rate_per_s", l.bucket.rate_per_s);
  l.bucket.burst = f.positive_or("burst", l.bucket.burst);
  if (l.bucket.burst < 1)
    f.child("burst").fail("must be >= 1");
  if (f.has("max_sources"))
    l.max_sources = unsigned_of(f.child("max_sources"), 1e7);
}

void read_association(const YamlField& f, DaemonConfig& c) {
  f.expect_map({"gate_chi2", "fit_sigma_floor_m", "size_relative_tolerance", "size_absolute_tolerance_m"});
  auto& a = c.core.association;
  a.gate_chi2 = f.positive_or("gate_chi2", a.gate_chi2);
  a.fit_sigma_floor_m = f.positive_or("fit_sigma_floor_m", a.fit_sigma_floor_m);
  a.size_relative_tolerance = f.non_negative_or("size_relative_tolerance", a.size_relative_tolerance);
  a.size_absolute_tolerance_m = f.non_negative_or("size_absolute_tolerance_m", a.size_absolute_tolerance_m);
}

// security: mode, key files, replay window (lib/v2i/message_authenticator.h).
void read_security(const YamlField& f, DaemonConfig& c, const std::filesystem::path& base) {
  f.expect_map({"mode", "key_file", "trust_list_file", "max_age_s", "max_future_s", "max_signers",
                "verify_beyond_coverage_m"});
  auto& s = c.core.security;
  if (f.has("mode")) {
    const YamlField m = f.child("mode");
    const std::string v = m.text();
    if (v == "signed")
      s.mode = v2i::SecurityMode::kSigned;
    else if (v == "insecure")
      s.mode = v2i::SecurityMode::kInsecure;
    else
      m.fail("expected signed or insecure, got \"" + v + "\"");
  }
  if (f.has("key_file"))
    c.security.key_file = path_of(f.child("key_file"), base);
  if (f.has("trust_list_file"))
    c.security.trust_list_file = path_of(f.child("trust_list_file"), base);
  s.replay.max_age = from_seconds(f.positive_or("max_age_s", to_seconds(s.replay.max_age)));
  s.replay.max_future = from_seconds(f.positive_or("max_future_s", to_seconds(s.replay.max_future)));
  if (s.replay.max_age > 60 * kNsPerSecond)
    f.child("max_age_s").fail("must be <= 60 s (a longer window lets captured messages be replayed)");
  if (s.replay.max_future > 60 * kNsPerSecond)
    f.child("max_future_s").fail("must be <= 60 s");
  if (f.has("max_signers"))
    s.replay.max_signers = unsigned_of(f.child("max_signers"), 1e7);
  if (s.replay.max_signers == 0)
    f.child("max_signers").fail("must be >= 1");
  // Verify on demand (RsuCoreConfig::verify_beyond_coverage_m): a margin in metres, or "all".
  if (f.has("verify_beyond_coverage_m")) {
    const YamlField v = f.child("verify_beyond_coverage_m");
    const std::string text = v.text();
    char* end = nullptr;
    const double margin = std::strtod(text.c_str(), &end);
    if (text == "all")
      c.core.verify_beyond_coverage_m.reset();
    else if (text.empty() || *end != '\0' || !std::isfinite(margin) || margin < 0)
      v.fail("expected a margin in metres (>= 0) or \"all\", got \"" + text + "\"");
    else
      c.core.verify_beyond_coverage_m = margin;
  }
}

void read_logging(const YamlField& f, DaemonConfig& c) {
  f.expect_map({"level", "bad_input_log_first", "summary_interval_s", "stats_interval_s", "stats_file"});
  if (f.has("level")) {
    const YamlField l = f.child("level");
    const std::string v = l.text();
    if (v != "trace" && v != "debug" && v != "info" && v != "warn" && v != "error") {
      l.fail("expected trace, debug, info, warn or error, got \"" + v + "\"");
    }
    c.logging.level = v;
  }
  if (f.has("bad_input_log_first"))
    c.logging.bad_input_log_first = static_cast<int>(unsigned_of(f.child("bad_input_log_first"), 1000));
  c.logging.summary_interval_s = f.positive_or("summary_interval_s", c.logging.summary_interval_s);
  c.logging.stats_interval_s = f.non_negative_or("stats_interval_s", c.logging.stats_interval_s);
  if (f.has("stats_file"))
    c.stats_file = f.child("stats_file").text();
}

void read_metrics(const YamlField& f, DaemonConfig& c) {
  f.expect_map({"textfile", "interval_s"});
  if (f.has("textfile")) {
    const YamlField t = f.child("textfile");
    c.metrics.textfile = t.text();
    // node_exporter's textfile collector reads only *.prom files.
    if (!c.metrics.textfile.empty() && !c.metrics.textfile.ends_with(".prom"))
      t.fail("must end in .prom (node_exporter's textfile collector reads only those)");
  }
  c.metrics.interval_s = f.positive_or("interval_s", c.metrics.interval_s);
}

void read_mount_integrity(const YamlField& f, DaemonConfig& c) {
  f.expect_map({"enabled", "max_position_error_m", "resume_after_s", "check_thread"});
  calibration::MountMonitorConfig& m = c.core.mount_monitor;
  if (f.has("enabled"))
    m.enabled = bool_of(f.child("enabled"));
  if (f.has("check_thread"))
    c.mount_check_thread = bool_of(f.child("check_thread"));
  m.max_position_error_m = f.positive_or("max_position_error_m", m.max_position_error_m);
  const double resume_s = f.non_negative_or("resume_after_s", to_seconds(m.resume_after));
  if (resume_s > 3600)
    f.child("resume_after_s").fail("must be at most 3600 s");
  m.resume_after = from_seconds(resume_s);
}

void read_state(const YamlField& f, DaemonConfig& c, const std::filesystem::path& base) {
  f.expect_map({"directory", "persist_background", "use_calibration"});
  if (f.has("directory"))
    c.state.directory = path_of(f.child("directory"), base);
  if (f.has("persist_background"))
    c.state.persist_background = bool_of(f.child("persist_background"));
  if (f.has("use_calibration"))
    c.state.use_calibration = bool_of(f.child("use_calibration"));
}

}  // namespace

DaemonConfig parse_config(const std::string& yaml_text, const std::string& source_name) {
  DaemonConfig c;
  c.source = source_name;
  const std::filesystem::path base = std::filesystem::path(source_name).parent_path();
  try {
    const YAML::Node root = io::parse_yaml(yaml_text, source_name);
    const YamlField f(root, "", c.source, 1);
    f.expect_map({"rsu_id", "lidar", "background", "perception", "v2i", "security", "registry", "flood_limit",
                  "association", "dds", "logging", "metrics", "state", "mount_integrity"});
    c.core.rsu_id = unsigned_of(f.required("rsu_id"), 9.007e15);
    if (c.core.rsu_id == 0)
      f.child("rsu_id").fail("must be non-zero");
    read_lidar(f.required("lidar"), c, base);
    if (f.has("background"))
      read_background(f.child("background"), c, base);
    if (f.has("perception"))
      read_perception(f.child("perception"), c);
    if (f.has("v2i"))
      read_v2i(f.child("v2i"), c);
    else
      c.core.announcement_port = c.core.correction_port = c.v2i_port;
    // Signed is the default: without a security section the keys are read from /etc/rsud/keys/.
    if (f.has("security"))
      read_security(f.child("security"), c, base);
    if (f.has("registry"))
      read_registry(f.child("registry"), c);
    if (f.has("flood_limit"))
      read_flood(f.child("flood_limit"), c);
    if (f.has("association"))
      read_association(f.child("association"), c);
    if (f.has("dds"))
      c.dds = read_dds_config(f.child("dds"), base, c.core.peers);
    if (std::holds_alternative<DdsPointCloud2Input>(c.input) && !c.dds.enabled) {
      f.child("lidar")
          .child("input")
          .child("dds_pointcloud2")
          .fail("needs the DDS participant: set dds.enabled: true");
    }
    if (f.has("logging"))
      read_logging(f.child("logging"), c);
    if (f.has("metrics"))
      read_metrics(f.child("metrics"), c);
    if (f.has("state"))
      read_state(f.child("state"), c, base);
    if (f.has("mount_integrity"))
      read_mount_integrity(f.child("mount_integrity"), c);
  } catch (const io::YamlError& e) {
    throw ConfigError(e.what());
  } catch (const YAML::Exception& e) {
    throw ConfigError(source_name + ":" + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
  return c;
}

void load_security(DaemonConfig& c) {
  if (c.core.security.mode != v2i::SecurityMode::kSigned)
    return;
  const auto read = [&](const std::string& path, const char* field) {
    try {
      return io::read_text_file(path);
    } catch (const io::YamlError& e) {
      throw ConfigError(c.source + ": security." + field + ": " + e.what());
    }
  };
  try {
    c.core.signing_key =
        v2i::security::parse_secret_key_text(read(c.security.key_file, "key_file"), c.security.key_file);
    std::error_code ec;
    const auto perms = std::filesystem::status(c.security.key_file, ec).permissions();
    c.security.key_file_exposed =
        !ec && (perms & (std::filesystem::perms::group_all | std::filesystem::perms::others_all)) !=
                   std::filesystem::perms::none;
    c.core.trust_list = v2i::security::parse_trust_list_text(
        read(c.security.trust_list_file, "trust_list_file"), c.security.trust_list_file);
  } catch (const std::invalid_argument& e) {
    throw ConfigError(e.what());  // "<file>:<line>: ..."
  }
}

void load_lidar_files(DaemonConfig& c) {
  lidar::LidarDecoderOptions& o = c.core.sensor_options;
  if (!o.metadata_source.empty()) {
    try {
      o.metadata_text = io::read_text_file(o.metadata_source);
    } catch (const io::YamlError& e) {
      throw ConfigError(c.source + ": lidar.metadata: " + e.what());
    }
  }
  if (!c.sensor_files.calibration.empty()) {
    try {
      o.calibrated_model = io::apply_velodyne_calibration(*lidar::sensor_model_by_name(c.core.sensor_model),
                                                          io::read_text_file(c.sensor_files.calibration),
                                                          c.sensor_files.calibration);
    } catch (const io::YamlError& e) {
      throw ConfigError(e.what());  // "<file>:<line>: <field>: ..."
    }
  }
}

DaemonConfig load_config(const ConfigSource& source) {
  const std::string& path = source.path;
  std::string text;
  try {
    text = io::read_text_file(path);
  } catch (const io::YamlError& e) {
    throw ConfigError(e.what());
  }
  DaemonConfig config = parse_config(text, path);
  if (!source.key_file.empty())
    config.security.key_file = source.key_file;
  load_lidar_files(config);
  load_security(config);
  load_state_calibration(config);
  return config;
}

void load_state_calibration(DaemonConfig& c) {
  if (c.state.directory.empty()) {
    // systemd's StateDirectory= (several are separated by ':'; the unit names one).
    const char* env = std::getenv("STATE_DIRECTORY");
    if (env != nullptr)
      c.state.directory = std::string(env).substr(0, std::string(env).find(':'));
  }
  if (c.state.directory.empty() || !c.state.use_calibration)
    return;
  const std::string path = (std::filesystem::path(c.state.directory) / "calibration.yaml").string();
  std::error_code ec;
  if (!std::filesystem::exists(path, ec))
    return;
  try {
    const io::MountCalibrationFile file = io::read_mount_calibration(path);
    if (file.verdict != "good") {
      c.state_warnings.push_back(path + ": verdict " + file.verdict + " (" + file.reason +
                                 "): not used, lidar.mount stays in effect");
      return;
    }
    c.core.mount = file.mount;
    c.mount_source = path;
  } catch (const io::MountCalibrationError& e) {
    c.state_warnings.push_back(std::string(e.what()) + ": not used, lidar.mount stays in effect");
  }
}

std::string summarize(const DaemonConfig& c) {
  std::ostringstream out;
  const Pose3& m = c.core.mount;
  out << "rsu_id " << c.core.rsu_id << "\n";
  out << "mount from " << c.mount_source << "\n";
  if (c.core.mount_monitor.enabled)
    out << "mount integrity: fixes stop when the LiDAR's motion moves a fix more than "
        << c.core.mount_monitor.max_position_error_m << " m at " << c.core.coverage_radius_m << " m\n";
  else
    out << "mount integrity: off\n";
  out << "state directory "
      << (c.state.directory.empty() ? std::string("none (nothing kept between runs)") : c.state.directory)
      << (c.state.persist_background ? "" : " (background not kept)") << "\n";
  for (const std::string& w : c.state_warnings)
    out << "WARNING: " << w << "\n";
  out << "lidar " << c.core.sensor_model << " at (" << m.x << ", " << m.y << ", " << m.z << ") m, yaw "
      << rad_to_deg(m.yaw) << " deg, pitch " << rad_to_deg(m.pitch) << " deg, roll " << rad_to_deg(m.roll)
      << " deg\n";
  if (!c.core.sensor_options.metadata_source.empty())
    out << "lidar metadata " << c.core.sensor_options.metadata_source << "\n";
  out << "lidar "
      << (c.sensor_files.calibration.empty()
              ? (c.core.sensor_options.metadata_source.empty() ? "built-in tables"
                                                               : "tables from the metadata")
              : "calibration " + c.sensor_files.calibration)
      << ", returns " << to_string(c.core.sensor_options.returns) << ", scan phase "
      << c.core.sensor_options.rotation_start_azimuth_deg << " deg, time source "
      << (c.core.time_source == core::TimeSource::kSensor ? "sensor" : "host_receive") << " (clock tolerance "
      << to_seconds(c.core.clock_tolerance) * 1e3 << " ms)\n";
  if (const auto* u = std::get_if<UdpInput>(&c.input)) {
    out << "input udp " << u->bind_address << ":"
        << (u->port != 0 ? std::to_string(u->port) : std::string("the metadata's udp_port_lidar"))
        << (u->auxiliary_port != 0 ? ", auxiliary port " + std::to_string(u->auxiliary_port) : std::string())
        << "\n";
  } else if (const auto* c2 = std::get_if<PcapInput>(&c.input)) {
    out << "input pcap " << c2->file << " at "
        << (c2->pace == PcapInput::Pace::kMax ? "maximum pace" : "recorded pace")
        << (c2->loop ? ", looped" : "") << "\n";
  } else if (const auto* p = std::get_if<PcdInput>(&c.input)) {
    out << "input pcd " << p->files.size() << " file(s) at " << p->rate_hz << " Hz\n";
  } else if (const auto* d = std::get_if<DdsPointCloud2Input>(&c.input)) {
    out << "input dds_pointcloud2 " << d->topic << (d->whole_rotation ? " (whole rotations)" : " (parts)")
        << "\n";
  }
  if (c.background_pcd_files.empty()) {
    out << "background learned from the first " << c.core.background.learning_frames << " rotations\n";
  } else {
    out << "background from " << c.background_pcd_files.size() << " PCD file(s)\n";
  }
  out << "v2i announcements on " << c.v2i_listen_address << ":" << c.v2i_port << ", corrections within "
      << c.core.coverage_radius_m << " m\n";
  out << "registry capacity " << c.core.registry.capacity << ", expiry "
      << to_seconds(c.core.registry.silence_timeout) << " s, " << c.core.registry.rate_limit.bucket.rate_per_s
      << " announcements/s per source\n";
  if (c.advertisement.enabled) {
    out << "advertisement to " << c.advertisement.address << ":" << c.advertisement.port << " every "
        << c.advertisement.interval_s << " s\n";
  }
  if (c.dds.enabled) {
    out << "dds domain " << c.dds.participant.domain_id << " ("
        << (c.dds.participant.cyclone_config.empty() ? std::string("Cyclone defaults / CYCLONEDDS_URI")
                                                     : c.dds.participant.cyclone_config)
        << "), poses on " << (c.dds.pose_topic.empty() ? "-" : c.dds.pose_topic) << ", object list on "
        << (c.dds.object_list_topic.empty() ? "-" : c.dds.object_list_topic) << "\n";
    if (c.dds.peers.enabled)
      out << "announcements shared with the other RSUs on " << c.dds.peers.topic << "\n";
  }
  const auto& s = c.core.security;
  if (s.mode == v2i::SecurityMode::kSigned) {
    out << "security signed: key ";
    if (c.core.signing_key)
      out << v2i::security::to_hex(c.core.signing_key->key_id()) << " (" << c.security.key_file
          << (c.security.key_file_exposed ? ", WARNING: readable by group or others, chmod 600 it" : "")
          << ")";
    else
      out << c.security.key_file << " (not read)";
    out << ", trust list " << c.security.trust_list_file << ": "
        << c.core.trust_list.count(v2i::security::SignerRole::kVehicle) << " vehicle key(s), "
        << c.core.trust_list.count(v2i::security::SignerRole::kRsu) << " RSU key(s); window -"
        << to_seconds(s.replay.max_age) << " s / +" << to_seconds(s.replay.max_future)
        << " s, sequence window 64; ";
    if (c.core.verify_beyond_coverage_m)
      out << "announcements verified within " << c.core.coverage_radius_m + *c.core.verify_beyond_coverage_m
          << " m of the LiDAR (coverage + " << *c.core.verify_beyond_coverage_m
          << " m), dropped unverified beyond\n";
    else
      out << "every announcement verified\n";
  } else {
    out << "security INSECURE: nothing is signed or verified (local development only)\n";
  }
  out << "log level " << c.logging.level << "\n";
  return out.str();
}

}  // namespace rsu::daemon
