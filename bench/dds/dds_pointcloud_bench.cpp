// SPDX-License-Identifier: Apache-2.0
// DDS input benchmark (issue 6): VLP-32C clouds (~57,900 points, ~1 MB as PointCloud2) published at
// 10 Hz over Cyclone DDS on loopback into a real rsud (child process) for a bounded time, with a
// vehicle in the cloud announced over V2I so that poses come back over DDS. Prints, per run:
//   clouds published, taken by rsud (its stats file), lost;
//   latency publish -> rsud took the sample (rsud's dds.take_latency_us: source timestamp to take);
//   latency publish -> PoseWithCovarianceStamped received back here;
//   latency sweep -> pose received (the pose's stamp is when the LiDAR swept the car);
// each as p50 / p99 / max. Baselines in the same invocation: the same pipeline with a small cloud
// (the 20-degree sector around the car), and the same scene as Velodyne UDP packets (`rsu-sim
// stream`, rsud's native input, streamed as the sensor sweeps) with the poses read over DDS alike.
//
//   build/bench/dds/dds_pointcloud_bench [--seconds 20] [--rate-hz 10] [--rsud PATH] [--announcer PATH]
//                                        [--rsu-sim PATH]
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
#include "io/pcd_io.h"
#include "sensor_msgs.h"
#include "sim/lidar_simulator.h"
#include "sim/scenario.h"

namespace {

using rsu::TimeNs;
using rsu::lidar::LidarPoint;
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

Cloud pack(const std::vector<LidarPoint>& points) {
  TimeNs frame_start = points.empty() ? 0 : points.front().time_ns;
  for (const LidarPoint& p : points)
    frame_start = std::min(frame_start, p.time_ns);
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

// Frames of the scene with or without the car, as points (sensor frame).
std::vector<std::vector<LidarPoint>> simulate_points(const rsu::sim::Scenario& scenario, bool with_vehicle,
                                                     int frames) {
  rsu::sim::Scene scene = scenario.scene;
  if (!with_vehicle)
    scene.vehicles.clear();
  const auto& lidar = scenario.lidar;
  const rsu::sim::LidarSimulator sim(lidar.model, lidar.mount, lidar.noise, scene, 0,
                                     lidar.start_azimuth_deg);
  std::vector<std::vector<LidarPoint>> out;
  for (int i = 0; i < frames; ++i)
    out.push_back(sim.simulate_frame(scenario.start_ns + i * sim.rotation_period_ns()).frame.points);
  return out;
}

// Frames of the scene with or without the car, all points or only the sector around the car.
std::vector<Cloud> simulate(const rsu::sim::Scenario& scenario, bool with_vehicle, bool sector_only,
                            int frames) {
  // The car's azimuth as LidarPoint measures it (clockwise from +x).
  const auto& mount = scenario.lidar.mount;
  const double car_azimuth = std::atan2(-(kVehicleY - mount.y), kVehicleX - mount.x);
  std::vector<Cloud> out;
  for (std::vector<LidarPoint>& points : simulate_points(scenario, with_vehicle, frames)) {
    if (sector_only) {
      std::erase_if(points, [car_azimuth](const LidarPoint& p) {
        const double d =
            std::remainder(static_cast<double>(p.azimuth_rad) - car_azimuth, 2 * std::numbers::pi);
        return std::abs(d) > 10.0 * std::numbers::pi / 180.0;
      });
    }
    out.push_back(pack(points));
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
  int published = -1;  // -1: not a DDS input run
  double taken = 0;
  double take_p50_us = 0, take_p99_us = 0, take_max_us = 0;
  std::vector<TimeNs> pose_latency;   // publish -> pose back
  std::vector<TimeNs> sweep_latency;  // the pose's sweep time -> pose back
};

struct Options {
  double seconds = 20;
  double rate_hz = 10;
  std::string rsud = RSUD_PATH;
  std::string announcer = ANNOUNCER_PATH;
  std::string rsu_sim = RSU_SIM_PATH;
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

// One rsud (child process, DDS on, poses on rt/bench/vehicles/{id}/pose) in its own work folder, the
// bench's participant reading those poses, and the announcing vehicle. Stops both children and removes
// the folder on the way out.
class RsudUnderTest {
 public:
  RsudUnderTest(const Options& o, std::uint32_t domain, const std::string& input_yaml,
                const std::string& background_yaml,
                const std::vector<std::vector<LidarPoint>>& background_pcd = {})
      : options_(o),
        work_(std::filesystem::temp_directory_path() /
              ("rsu_dds_bench_" + std::to_string(getpid()) + "_" + std::to_string(domain))),
        v2i_port_(free_udp_port()),
        participant_({domain, o.cyclone_config}),
        pose_topic_(participant_, "rt/bench/vehicles/1/pose",
                    geometry_msgs_msg_dds__PoseWithCovarianceStamped__desc),
        poses_(participant_, pose_topic_, rsu::dds::QosConfig{}) {
    std::filesystem::create_directories(work_);
    std::string background = background_yaml;
    for (std::size_t i = 0; i < background_pcd.size(); ++i) {
      const std::string file = (work_ / ("background_" + std::to_string(i) + ".pcd")).string();
      rsu::io::write_pcd(file, background_pcd[i]);
      background += (i == 0 ? "pcd_files: [" : ", ") + file + (i + 1 == background_pcd.size() ? "]" : "");
    }
    std::ofstream cfg(work_ / "rsud.yaml");
    cfg << "rsu_id: 9\nlidar:\n  model: vlp32c\n  mount: {x: 0, y: 0, z: 2.0}\n  input:\n    " << input_yaml
        << "\nbackground: {" << background << "}\n"
        << "v2i: {listen_address: 127.0.0.1, port: " << v2i_port_ << "}\n"
        << "security: {mode: insecure}\n"  // this measures DDS; bench/v2i measures signing and verifying
        << "dds:\n  enabled: true\n  domain_id: " << domain << "\n  cyclone_config: " << o.cyclone_config
        << "\n  pose_topic: bench/vehicles/{vehicle_id}/pose\n"
        << "logging: {level: warn, stats_interval_s: 0.2, stats_file: " << stats_path() << "}\n";
    cfg.close();
    rsud_ = spawn({o.rsud, "--config", (work_ / "rsud.yaml").string()}, log_path());
  }
  ~RsudUnderTest() {
    stop(announcer_);
    stop(rsud_);
    std::error_code ignored;
    std::filesystem::remove_all(work_, ignored);
  }
  RsudUnderTest(const RsudUnderTest&) = delete;
  RsudUnderTest& operator=(const RsudUnderTest&) = delete;

  const rsu::dds::Participant& participant() const { return participant_; }
  int v2i_port() const { return v2i_port_; }
  std::string log_path() const { return (work_ / "rsud.log").string(); }
  std::string stats_path() const { return (work_ / "stats").string(); }
  std::map<std::string, double> stats() const { return read_stats(stats_path()); }

  void wait_ready(double seconds) const {
    const TimeNs deadline = wall_ns() + static_cast<TimeNs>(seconds * 1e9);
    while (stats()["ready"] < 1 && wall_ns() < deadline)
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    if (stats()["ready"] < 1)
      throw std::runtime_error("rsud is not ready (see " + log_path() + ")");
  }

  // Announces the car (its own estimate a little off, as a vehicle's is) for `seconds`.
  void start_vehicle(double seconds) {
    char pose[64];
    std::snprintf(pose, sizeof pose, "%.3f,%.3f,%.4f", kVehicleX + 0.3, kVehicleY - 0.2,
                  kVehicleYawDeg * std::numbers::pi / 180.0 + 0.03);
    announcer_ = spawn({options_.announcer, "--rsu", "127.0.0.1:" + std::to_string(v2i_port_), "--bind",
                        "127.0.0.1", "--insecure", "1", "--id", std::to_string(kVehicleId), "--pose", pose,
                        "--seconds", std::to_string(seconds)},
                       (work_ / "announcer.log").string());
    std::this_thread::sleep_for(std::chrono::milliseconds(300));  // registered before the car is swept
  }

  // Takes the poses that arrived: sweep -> received into `r`, and publish -> received when `sent`
  // (stamp, publication time of each cloud, each covering [stamp, stamp + period]) holds the cloud.
  void take_poses(const std::vector<std::pair<TimeNs, TimeNs>>& sent, TimeNs period, RunResult& r) {
    const TimeNs now = wall_ns();
    poses_.take(16, [&](const PoseStamped& p, const dds_sample_info_t&) {
      const TimeNs stamp = TimeNs{p.header.stamp.sec} * rsu::kNsPerSecond + p.header.stamp.nanosec;
      r.sweep_latency.push_back(now - stamp);
      for (const auto& [s, published] : sent) {
        if (s <= stamp && stamp <= s + period) {
          r.pose_latency.push_back(now - published);
          break;
        }
      }
    });
  }

 private:
  const Options& options_;
  std::filesystem::path work_;
  int v2i_port_;
  pid_t rsud_ = 0;
  pid_t announcer_ = 0;
  rsu::dds::Participant participant_;
  rsu::dds::Topic pose_topic_;
  rsu::dds::Reader<PoseStamped> poses_;
};

// Sleeps until `until`, taking poses meanwhile.
void take_poses_until(RsudUnderTest& rsud, TimeNs until, const std::vector<std::pair<TimeNs, TimeNs>>& sent,
                      TimeNs period, RunResult& r) {
  do {
    rsud.take_poses(sent, period, r);
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  } while (wall_ns() < until);
}

// PointCloud2 over DDS: the background learned from the first rotations (as rsud does at start-up),
// then the car's clouds at the rate for the time asked.
RunResult run_dds(const Options& o, const std::string& name, const std::vector<Cloud>& background,
                  const std::vector<Cloud>& clouds, std::uint32_t domain) {
  RunResult r;
  r.name = name;
  r.points = clouds.front().points;
  r.bytes = clouds.front().data.size();
  RsudUnderTest rsud(o, domain, "dds_pointcloud2: {topic: bench/points, whole_rotation: true}",
                     "learning_frames: " + std::to_string(kLearningFrames));
  rsu::dds::Topic cloud_topic(rsud.participant(), "rt/bench/points", sensor_msgs_msg_dds__PointCloud2__desc);
  rsu::dds::QosConfig qos;
  qos.max_blocking_s = 1.0;
  rsu::dds::Writer<PointCloud2> writer(rsud.participant(), cloud_topic, qos);
  const TimeNs match_deadline = wall_ns() + 10 * rsu::kNsPerSecond;
  while (writer.matched_readers() == 0 && wall_ns() < match_deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  if (writer.matched_readers() == 0)
    throw std::runtime_error("rsud's reader was not discovered within 10 s (see " + rsud.log_path() + ")");

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

  TimeNs next = wall_ns();
  for (int i = 0; i < kLearningFrames + 2; ++i, next += period) {
    sleep_until_ns(next);
    publish(background[static_cast<std::size_t>(i) % background.size()]);
  }
  rsud.wait_ready(5);
  rsud.start_vehicle(o.seconds + 5);
  const std::size_t before = sent.size();
  const int total = static_cast<int>(o.seconds * o.rate_hz);
  next = wall_ns();
  for (int i = 0; i < total; ++i, next += period) {
    take_poses_until(rsud, next, sent, period, r);
    publish(clouds[static_cast<std::size_t>(i) % clouds.size()]);
  }
  r.published = static_cast<int>(sent.size() - before);
  take_poses_until(rsud, wall_ns() + rsu::kNsPerSecond, sent, period, r);
  const auto s = rsud.stats();
  auto stat = [&s](const std::string& key) { return s.count(key) ? s.at(key) : -1.0; };
  r.taken = stat("dds.clouds_received") - static_cast<double>(before);
  r.take_p50_us = stat("dds.take_latency_us.p50");
  r.take_p99_us = stat("dds.take_latency_us.p99");
  r.take_max_us = stat("dds.take_latency_us.max");
  return r;
}

// The same scene as Velodyne packets from `rsu-sim stream` (rsud's native input), poses over DDS.
RunResult run_udp(const Options& o, const std::vector<std::vector<LidarPoint>>& background,
                  std::uint32_t domain) {
  RunResult r;
  r.name = "baseline: Velodyne UDP";
  const int lidar_port = free_udp_port();
  RsudUnderTest rsud(o, domain,
                     "velodyne_udp: {bind_address: 127.0.0.1, port: " + std::to_string(lidar_port) + "}", "",
                     background);
  rsud.wait_ready(10);
  rsud.start_vehicle(o.seconds + 5);
  char seconds[32];
  std::snprintf(seconds, sizeof seconds, "%.3f", o.seconds);
  const pid_t stream =
      spawn({o.rsu_sim, "stream", std::string(RSU_SOURCE_DIR) + "/bench/dds/courtyard.yaml", "--to",
             "127.0.0.1:" + std::to_string(lidar_port), "--clock", "wall", "--seconds", seconds},
            rsud.log_path() + ".stream");
  take_poses_until(rsud, wall_ns() + static_cast<TimeNs>((o.seconds + 1) * 1e9), {}, 0, r);
  stop(stream);
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
    else if (a == "--rsu-sim" && more)
      o.rsu_sim = argv[++i];
    else {
      std::fprintf(
          stderr,
          "usage: dds_pointcloud_bench [--seconds 20] [--rate-hz 10] [--rsud PATH] [--announcer PATH] "
          "[--rsu-sim PATH]\n");
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
    const std::vector<std::vector<LidarPoint>> udp_bg = simulate_points(scenario, false, 4);
    const std::uint32_t domain = 150 + static_cast<std::uint32_t>(getpid() % 25);
    std::vector<RunResult> results;
    results.push_back(run_dds(o, "VLP-32C rotation", full_bg, full, domain));
    results.push_back(run_dds(o, "baseline: 20 deg sector", small_bg, small, domain + 25));
    results.push_back(run_udp(o, udp_bg, domain + 50));

    std::printf(
        "rsud on loopback, %.0f s per run; clouds at %.0f Hz over Cyclone DDS (reliable); poses back over "
        "DDS; latencies in ms as p50 / p99 / max\n",
        o.seconds, o.rate_hz);
    std::printf("%-24s %6s %8s %5s %5s %4s | %-22s | %-27s | %-22s\n", "input", "points", "bytes", "sent",
                "taken", "lost", "publish -> rsud took it", "publish -> pose back", "sweep -> pose back");
    for (const RunResult& r : results) {
      const auto triple = [](const std::vector<TimeNs>& v) {
        char out[64];
        std::snprintf(out, sizeof out, "%6.1f %6.1f %6.1f", percentile_ms(v, 0.5), percentile_ms(v, 0.99),
                      percentile_ms(v, 1.0));
        return std::string(out);
      };
      if (r.published >= 0) {
        std::printf("%-24s %6zu %8zu %5d %5.0f %4.0f | %6.2f %6.2f %6.2f   | %4zu %s | %s\n", r.name.c_str(),
                    r.points, r.bytes, r.published, r.taken, r.published - r.taken, r.take_p50_us / 1e3,
                    r.take_p99_us / 1e3, r.take_max_us / 1e3, r.pose_latency.size(),
                    triple(r.pose_latency).c_str(), triple(r.sweep_latency).c_str());
      } else {
        std::printf("%-24s %6s %8s %5s %5s %4s | %-22s | %4zu %20s | %s\n", r.name.c_str(), "-", "-", "-",
                    "-", "-", "(packets, no DDS)", r.sweep_latency.size(), "-",
                    triple(r.sweep_latency).c_str());
      }
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "dds_pointcloud_bench: %s\n", e.what());
    return 1;
  }
  return 0;
}
