// DDS input benchmark (issue 6): VLP-32C clouds (~57,900 points, ~1 MB as PointCloud2) published at
// 10 Hz over Cyclone DDS on loopback into a real rsud (child process) for a bounded time, with a
// vehicle in the cloud announced over V2I so that poses come back. Prints, per run:
//   clouds published, taken by rsud (its stats file), lost;
//   latency publish -> rsud took the sample (rsud's dds.take_latency_us, source timestamp to take);
//   latency publish -> PoseWithCovarianceStamped received back here (p50 / p99 / max).
// The baseline, in the same invocation: the same pipeline with a small cloud (the 20-degree sector
// around the car, ~1/18 of the points).
//
//   build/bench/dds/dds_pointcloud_bench [--seconds 20] [--rate-hz 10] [--rsud PATH] [--announcer PATH]
#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "dds/participant.h"
#include "dds/typed_entities.h"
#include "geometry_msgs.h"
#include "sensor_msgs.h"
#include "sim/lidar_simulator.h"
#include "sim/scenario.h"

namespace {

using rsu::LidarPoint;
using rsu::TimeNs;
using PointCloud2 = sensor_msgs_msg_dds__PointCloud2_;
using PoseStamped = geometry_msgs_msg_dds__PoseWithCovarianceStamped_;

constexpr std::uint16_t kVehicleId = 1;
constexpr double kVehicleX = 12.0, kVehicleY = -5.0, kVehicleYawDeg = 30.0;  // courtyard.yaml
constexpr int kLearningFrames = 10;

TimeNs wall_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

void sleep_until_ns(TimeNs t) {
  const TimeNs now = wall_ns();
  if (t > now)
    std::this_thread::sleep_for(std::chrono::nanoseconds(t - now));
}

// The cloud as a Velodyne driver would publish it, packed: x, y, z float32, intensity uint8, ring
// uint8, time float32 seconds relative to the stamp (the rotation's first firing): 18 bytes a point.
struct Cloud {
  std::size_t points = 0;
  std::vector<std::uint8_t> data;
};
constexpr std::uint32_t kPointStep = 18;

Cloud pack(const std::vector<LidarPoint>& points, TimeNs frame_start) {
  Cloud c;
  c.points = points.size();
  c.data.resize(points.size() * kPointStep);
  std::uint8_t* out = c.data.data();
  for (const LidarPoint& p : points) {
    const float t = static_cast<float>(rsu::to_seconds(p.time_ns - frame_start));
    const auto intensity = static_cast<std::uint8_t>(std::clamp(p.intensity, 0.0F, 255.0F));
    const auto ring = static_cast<std::uint8_t>(p.ring);
    std::memcpy(out + 0, &p.x, 4);
    std::memcpy(out + 4, &p.y, 4);
    std::memcpy(out + 8, &p.z, 4);
    out[12] = intensity;
    out[13] = ring;
    std::memcpy(out + 14, &t, 4);
    out += kPointStep;
  }
  return c;
}

// Frames of the scene with or without the car, all points or only the sector around the car.
std::vector<Cloud> simulate(const rsu::sim::Scenario& scenario, bool with_vehicle, bool sector_only,
                            int frames) {
  rsu::sim::Scene scene = scenario.scene;
  if (!with_vehicle)
    scene.vehicles.clear();
  const auto& lidar = scenario.lidar;
  const rsu::sim::LidarSimulator sim(lidar.model, lidar.mount, lidar.noise, scene, 0,
                                     lidar.start_azimuth_deg);
  // The car's azimuth as LidarPoint measures it (clockwise from +x).
  const double car_azimuth = std::atan2(-(kVehicleY - lidar.mount.y), kVehicleX - lidar.mount.x);
  std::vector<Cloud> out;
  for (int i = 0; i < frames; ++i) {
    const TimeNs start = scenario.start_ns + i * sim.rotation_period_ns();
    std::vector<LidarPoint> points = sim.simulate_frame(start).frame.points;
    if (sector_only) {
      std::erase_if(points, [car_azimuth](const LidarPoint& p) {
        const double d =
            std::remainder(static_cast<double>(p.azimuth_rad) - car_azimuth, 2 * std::numbers::pi);
        return std::abs(d) > 10.0 * std::numbers::pi / 180.0;
      });
    }
    out.push_back(pack(points, start));
  }
  return out;
}

pid_t spawn(const std::vector<std::string>& argv, const std::string& log) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  std::vector<char*> args;
  for (const std::string& a : argv)
    args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  pid_t pid = 0;
  const int rc = posix_spawn(&pid, args[0], &actions, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0)
    throw std::runtime_error("cannot start " + argv[0] + ": " + std::strerror(rc));
  return pid;
}

// Stops a child: SIGTERM, then SIGKILL after 5 s.
void stop(pid_t pid) {
  if (pid <= 0)
    return;
  kill(pid, SIGTERM);
  for (int i = 0; i < 500; ++i) {
    int status = 0;
    if (waitpid(pid, &status, WNOHANG) == pid)
      return;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  kill(pid, SIGKILL);
  waitpid(pid, nullptr, 0);
}

std::map<std::string, double> read_stats(const std::string& path) {
  std::map<std::string, double> s;
  std::ifstream in(path);
  std::string key;
  double value = 0;
  while (in >> key >> value)
    s[key] = value;
  return s;
}

double percentile_ms(std::vector<TimeNs> v, double q) {
  if (v.empty())
    return std::nan("");
  std::sort(v.begin(), v.end());
  const auto k = static_cast<std::size_t>(std::lround(q * static_cast<double>(v.size() - 1)));
  return static_cast<double>(v[k]) / 1e6;
}

struct RunResult {
  std::string name;
  std::size_t points = 0;
  std::size_t bytes = 0;
  int published = 0;
  double taken = 0;
  double take_p50_us = 0, take_p99_us = 0, take_max_us = 0;
  std::vector<TimeNs> pose_latency;
};

struct Options {
  double seconds = 20;
  double rate_hz = 10;
  std::string rsud = RSUD_PATH;
  std::string announcer = ANNOUNCER_PATH;
  std::string cyclone_config = std::string(RSU_SOURCE_DIR) + "/deploy/cyclonedds-loopback.xml";
};

int free_udp_port() {
  // The kernel's choice for an ephemeral bind, released at once (the same trick as the tests).
  const int fd = socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a);
  socklen_t len = sizeof a;
  getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len);
  close(fd);
  return ntohs(a.sin_port);
}

RunResult run(const Options& o, const std::string& name, const std::vector<Cloud>& background,
              const std::vector<Cloud>& clouds, std::uint32_t domain) {
  RunResult r;
  r.name = name;
  r.points = clouds.front().points;
  r.bytes = clouds.front().data.size();
  const std::filesystem::path work =
      std::filesystem::temp_directory_path() /
      ("rsu_dds_bench_" + std::to_string(getpid()) + "_" + std::to_string(domain));
  std::filesystem::create_directories(work);
  const int v2i_port = free_udp_port();
  const std::string stats = (work / "stats").string();
  {
    std::ofstream cfg(work / "rsud.yaml");
    cfg << "rsu_id: 9\nlidar:\n  model: vlp32c\n  mount: {x: 0, y: 0, z: 2.0}\n  input:\n"
        << "    dds_pointcloud2: {topic: bench/points, whole_rotation: true}\n"
        << "background: {learning_frames: " << kLearningFrames << "}\n"
        << "v2i: {listen_address: 127.0.0.1, port: " << v2i_port << "}\n"
        << "security: {mode: insecure}\n"  // this measures DDS; bench/v2i measures signing and verifying
        << "dds:\n  enabled: true\n  domain_id: " << domain << "\n  cyclone_config: " << o.cyclone_config
        << "\n  pose_topic: bench/vehicles/{vehicle_id}/pose\n"
        << "logging: {level: warn, stats_interval_s: 0.2, stats_file: " << stats << "}\n";
  }
  const pid_t rsud = spawn({o.rsud, "--config", (work / "rsud.yaml").string()}, (work / "rsud.log").string());
  pid_t announcer = 0;
  try {
    rsu::dds::Participant participant({domain, o.cyclone_config});
    rsu::dds::Topic cloud_topic(participant, "rt/bench/points", sensor_msgs_msg_dds__PointCloud2__desc);
    rsu::dds::QosConfig qos;
    qos.max_blocking_s = 1.0;
    rsu::dds::Writer<PointCloud2> writer(participant, cloud_topic, qos);
    rsu::dds::Topic pose_topic(participant, "rt/bench/vehicles/1/pose",
                               geometry_msgs_msg_dds__PoseWithCovarianceStamped__desc);
    rsu::dds::Reader<PoseStamped> poses(participant, pose_topic, rsu::dds::QosConfig{});
    const TimeNs match_deadline = wall_ns() + 10 * rsu::kNsPerSecond;
    while (writer.matched_readers() == 0 && wall_ns() < match_deadline)
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    if (writer.matched_readers() == 0)
      throw std::runtime_error("rsud's reader was not discovered within 10 s (see " +
                               (work / "rsud.log").string() + ")");

    std::string frame_id = "velodyne";
    std::vector<sensor_msgs_msg_dds__PointField_> fields = {
        {const_cast<char*>("x"), 0, 7, 1},     {const_cast<char*>("y"), 4, 7, 1},
        {const_cast<char*>("z"), 8, 7, 1},     {const_cast<char*>("intensity"), 12, 2, 1},
        {const_cast<char*>("ring"), 13, 2, 1}, {const_cast<char*>("time"), 14, 7, 1}};
    const TimeNs period = static_cast<TimeNs>(1e9 / o.rate_hz);
    std::vector<std::pair<TimeNs, TimeNs>> sent;  // (stamp, published)
    auto publish = [&](const Cloud& c) {
      PointCloud2 msg{};
      const TimeNs published = wall_ns();
      const TimeNs stamp = published - period;  // stamped with the rotation's start
      msg.header.stamp = {static_cast<std::int32_t>(stamp / rsu::kNsPerSecond),
                          static_cast<std::uint32_t>(stamp % rsu::kNsPerSecond)};
      msg.header.frame_id = frame_id.data();
      msg.height = 1;
      msg.width = static_cast<std::uint32_t>(c.points);
      msg.fields._buffer = fields.data();
      msg.fields._length = msg.fields._maximum = static_cast<std::uint32_t>(fields.size());
      msg.point_step = kPointStep;
      msg.row_step = static_cast<std::uint32_t>(c.data.size());
      msg.data._buffer = const_cast<std::uint8_t*>(c.data.data());
      msg.data._length = msg.data._maximum = static_cast<std::uint32_t>(c.data.size());
      msg.is_dense = true;
      writer.write(msg, published);
      sent.emplace_back(stamp, published);
    };
    auto take_poses = [&] {
      const TimeNs now = wall_ns();
      poses.take(16, [&](const PoseStamped& p, const dds_sample_info_t&) {
        const TimeNs stamp = TimeNs{p.header.stamp.sec} * rsu::kNsPerSecond + p.header.stamp.nanosec;
        // The cloud whose rotation holds the sweep time.
        for (const auto& [s, published] : sent) {
          if (s <= stamp && stamp <= s + period) {
            r.pose_latency.push_back(now - published);
            break;
          }
        }
      });
    };

    // The background is learned from the first rotations, as rsud does at start-up.
    TimeNs next = wall_ns();
    for (int i = 0; i < kLearningFrames + 2; ++i, next += period) {
      sleep_until_ns(next);
      publish(background[static_cast<std::size_t>(i) % background.size()]);
    }
    const TimeNs ready_deadline = wall_ns() + 5 * rsu::kNsPerSecond;
    while (read_stats(stats)["ready"] < 1 && wall_ns() < ready_deadline)
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    if (read_stats(stats)["ready"] < 1)
      throw std::runtime_error("rsud did not learn the background (see " + (work / "rsud.log").string() +
                               ")");
    char pose_arg[64];
    std::snprintf(pose_arg, sizeof pose_arg, "%.3f,%.3f,%.4f", kVehicleX + 0.3, kVehicleY - 0.2,
                  kVehicleYawDeg * std::numbers::pi / 180.0 + 0.03);
    announcer = spawn({o.announcer, "--rsu", "127.0.0.1:" + std::to_string(v2i_port), "--bind", "127.0.0.1",
                       "--insecure", "1", "--id", std::to_string(kVehicleId), "--pose", pose_arg, "--seconds",
                       std::to_string(o.seconds + 5)},
                      (work / "announcer.log").string());
    std::this_thread::sleep_for(std::chrono::milliseconds(300));  // registered before the first cloud

    const std::size_t before = sent.size();
    const int total = static_cast<int>(o.seconds * o.rate_hz);
    next = wall_ns();
    for (int i = 0; i < total; ++i, next += period) {
      while (wall_ns() < next) {
        take_poses();
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
      }
      publish(clouds[static_cast<std::size_t>(i) % clouds.size()]);
    }
    r.published = static_cast<int>(sent.size() - before);
    const TimeNs linger = wall_ns() + rsu::kNsPerSecond;
    while (wall_ns() < linger) {
      take_poses();
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    const auto s = read_stats(stats);
    r.taken = s.count("dds.clouds_received") ? s.at("dds.clouds_received") - static_cast<double>(before) : -1;
    r.take_p50_us = s.count("dds.take_latency_us.p50") ? s.at("dds.take_latency_us.p50") : -1;
    r.take_p99_us = s.count("dds.take_latency_us.p99") ? s.at("dds.take_latency_us.p99") : -1;
    r.take_max_us = s.count("dds.take_latency_us.max") ? s.at("dds.take_latency_us.max") : -1;
  } catch (...) {
    stop(announcer);
    stop(rsud);
    throw;
  }
  stop(announcer);
  stop(rsud);
  std::filesystem::remove_all(work);
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool more = i + 1 < argc;
    if (a == "--seconds" && more)
      o.seconds = std::stod(argv[++i]);
    else if (a == "--rate-hz" && more)
      o.rate_hz = std::stod(argv[++i]);
    else if (a == "--rsud" && more)
      o.rsud = argv[++i];
    else if (a == "--announcer" && more)
      o.announcer = argv[++i];
    else {
      std::fprintf(
          stderr,
          "usage: dds_pointcloud_bench [--seconds 20] [--rate-hz 10] [--rsud PATH] [--announcer PATH]\n");
      return 2;
    }
  }
  if (!(o.seconds > 0 && o.seconds <= 600) || !(o.rate_hz > 0 && o.rate_hz <= 50)) {
    std::fprintf(stderr, "dds_pointcloud_bench: need 0 < seconds <= 600 and 0 < rate <= 50 Hz\n");
    return 2;
  }
  try {
    const rsu::sim::Scenario scenario =
        rsu::sim::load_scenario_file(std::string(RSU_SOURCE_DIR) + "/bench/dds/courtyard.yaml");
    const std::vector<Cloud> full_bg = simulate(scenario, false, false, 4);
    const std::vector<Cloud> full = simulate(scenario, true, false, 4);
    const std::vector<Cloud> small_bg = simulate(scenario, false, true, 4);
    const std::vector<Cloud> small = simulate(scenario, true, true, 4);
    const std::uint32_t domain = 150 + static_cast<std::uint32_t>(getpid() % 40);
    std::vector<RunResult> results;
    results.push_back(run(o, "VLP-32C rotation", full_bg, full, domain));
    results.push_back(run(o, "baseline: 20 deg sector", small_bg, small, domain + 41));

    std::printf("DDS PointCloud2 into rsud on loopback, %.0f s at %.0f Hz per run (Cyclone DDS, reliable)\n",
                o.seconds, o.rate_hz);
    std::printf("%-24s %7s %9s %9s %6s %5s | %-26s | %-26s\n", "cloud", "points", "bytes", "published",
                "taken", "lost", "publish->taken ms p50/p99/max", "publish->pose ms n p50/p99/max");
    for (const RunResult& r : results) {
      std::printf("%-24s %7zu %9zu %9d %6.0f %5.0f | %8.2f %8.2f %8.2f | %4zu %6.1f %6.1f %6.1f\n",
                  r.name.c_str(), r.points, r.bytes, r.published, r.taken, r.published - r.taken,
                  r.take_p50_us / 1e3, r.take_p99_us / 1e3, r.take_max_us / 1e3, r.pose_latency.size(),
                  percentile_ms(r.pose_latency, 0.5), percentile_ms(r.pose_latency, 0.99),
                  percentile_ms(r.pose_latency, 1.0));
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "dds_pointcloud_bench: %s\n", e.what());
    return 1;
  }
  return 0;
}
