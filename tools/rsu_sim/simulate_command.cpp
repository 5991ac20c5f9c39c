// SPDX-License-Identifier: Apache-2.0
// rsu-sim simulate: frames as PCD (sensor frame), the Velodyne packets as a pcap, the true vehicle
// poses, and the data of a top-down picture (drawn by eval/plots/topdown.py).
#include <boost/program_options.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <span>
#include <vector>

#include "io/pcd_io.h"
#include "lidar/pcap.h"
#include "lidar/point_eigen.h"
#include "lidar/velodyne_packet.h"
#include "sim/lidar_simulator.h"
#include "sim/parallel_indices.h"
#include "sim/scenario.h"
#include "sim/trajectory.h"
#include "tools/rsu_sim/commands.h"
#include "tools/rsu_sim/scenario_options.h"

namespace rsu::tools {
namespace po = boost::program_options;

namespace {

void write_file(const std::filesystem::path& path, const std::vector<std::uint8_t>& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  if (!out)
    throw std::runtime_error("cannot write " + path.string());
}

// When the LiDAR swept vehicle `id` (docs/design.md §3): the median firing time of its points, or the
// frame's middle when it was not seen. A car at 40 km/h moves 0.55 m in half a rotation, so truth taken
// at any other time would misplace the box.
TimeNs sweep_time(const sim::SimulatedFrame& frame, std::uint32_t id) {
  std::vector<TimeNs> times;
  for (std::size_t i = 0; i < frame.truth.size(); ++i) {
    if (frame.truth[i].surface == sim::SurfaceClass::kVehicle && frame.truth[i].vehicle_id == id)
      times.push_back(frame.frame.points[i].time_ns);
  }
  if (times.empty())
    return (frame.frame.start_ns + frame.frame.end_ns) / 2;
  std::nth_element(times.begin(), times.begin() + static_cast<std::ptrdiff_t>(times.size() / 2), times.end());
  return times[times.size() / 2];
}

// The picture's data: map-frame points with their truth label and the true boxes at mid-frame.
void write_topdown(const std::filesystem::path& out_dir, const sim::Scenario& scenario,
                   const sim::SimulatedFrame& frame) {
  const Eigen::Isometry3d sensor_to_map = scenario.lidar.mount.to_isometry();
  std::ofstream points(out_dir / "topdown_points.csv");
  points << "x,y,z,label\n";
  for (std::size_t i = 0; i < frame.frame.points.size(); ++i) {
    const lidar::LidarPoint& p = frame.frame.points[i];
    const Eigen::Vector3d m = sensor_to_map * lidar::position_of(p);
    const auto& truth = frame.truth[i];
    const long label =
        truth.surface == sim::SurfaceClass::kVehicle ? static_cast<long>(truth.vehicle_id) : -1L;
    points << m.x() << ',' << m.y() << ',' << m.z() << ',' << label << '\n';
  }
  std::ofstream boxes(out_dir / "topdown_boxes.csv");
  boxes << "id,x,y,yaw,length,width\n";
  for (const sim::Vehicle& v : scenario.scene.vehicles) {
    const Pose2 pose = sim::pose_at(v.trajectory, sweep_time(frame, v.id));
    boxes << v.id << ',' << pose.x << ',' << pose.y << ',' << pose.yaw << ',' << v.shape.length << ','
          << v.shape.width << '\n';
  }
  std::ofstream lidar(out_dir / "topdown_lidar.csv");
  lidar << "x,y,z\n"
        << scenario.lidar.mount.x << ',' << scenario.lidar.mount.y << ',' << scenario.lidar.mount.z << '\n';
}

}  // namespace

int run_simulate(const std::vector<std::string>& args) {
  po::options_description options("rsu-sim simulate SCENARIO [options]");
  options.add_options()("help,h", "show this help")(
      "out,o", po::value<std::string>()->default_value("out/sim"), "output folder")(
      "frames,n", po::value<int>(), "number of frames (default: the scenario's simulation.frames)")(
      "no-pcd", "do not write PCD frames")(
      "threads,j", po::value<int>(),
      "threads casting each frame's and the pcap's rays (default: the machine's hardware threads); the "
      "output is the same bytes whatever the count");
  add_scenario_options(options);
  po::positional_options_description positional;
  positional.add("scenario", 1);
  po::variables_map vm;
  po::store(po::command_line_parser(args).options(options).positional(positional).run(), vm);
  po::notify(vm);
  if (vm.count("help")) {
    std::cout
        << options << "\nWrites into the output folder:\n"
        << "  frame_NNNN.pcd     points in the sensor frame (x y z intensity ring azimuth time)\n"
        << "  packets.pcap       the Velodyne data packets (UDP port 2368), if the model has a packet "
           "format\n"
        << "  truth.csv          true vehicle poses when the LiDAR swept them (median point time)\n"
        << "  topdown_*.csv      data of the top-down picture of the middle frame (eval/plots/topdown.py)\n";
    return 0;
  }

  const sim::Scenario scenario = load_scenario(vm);
  const int frames = vm.count("frames") ? vm["frames"].as<int>() : scenario.frames;
  if (frames < 1 || frames > 100000)
    throw std::runtime_error("simulate: --frames must be within [1, 100000]");
  // No default in the options: the help (and the man page made from it) must not depend on the machine.
  const int threads = vm.count("threads") ? vm["threads"].as<int>() : sim::hardware_threads();
  if (threads < 1 || threads > 256)
    throw std::runtime_error("simulate: --threads must be within [1, 256]");
  const std::filesystem::path out_dir = vm["out"].as<std::string>();
  std::filesystem::create_directories(out_dir);

  const auto wall_start = std::chrono::steady_clock::now();
  const sim::LidarSimulator simulator(scenario.lidar.model, scenario.lidar.mount, scenario.lidar.noise,
                                      scenario.scene, 0, scenario.lidar.start_azimuth_deg);
  const TimeNs period = simulator.rotation_period_ns();

  std::ofstream truth(out_dir / "truth.csv");
  truth << "frame,time_ns,vehicle_id,x,y,yaw,length,width\n";
  std::uint64_t total_points = 0, total_firings = 0;
  for (int f = 0; f < frames; ++f) {
    const TimeNs start = scenario.start_ns + f * period;
    const sim::SimulatedFrame frame = simulator.simulate_frame(start, std::nullopt, threads);
    total_points += frame.frame.points.size();
    total_firings += frame.counts.firings;
    if (!vm.count("no-pcd")) {
      char name[32];
      std::snprintf(name, sizeof name, "frame_%04d.pcd", f);
      io::write_pcd((out_dir / name).string(), frame.frame.points);
    }
    for (const sim::Vehicle& v : scenario.scene.vehicles) {
      const TimeNs swept = sweep_time(frame, v.id);
      const Pose2 pose = sim::pose_at(v.trajectory, swept);
      truth << f << ',' << swept << ',' << v.id << ',' << pose.x << ',' << pose.y << ',' << pose.yaw << ','
            << v.shape.length << ',' << v.shape.width << '\n';
    }
    if (f == frames / 2)
      write_topdown(out_dir, scenario, frame);
  }

  std::uint64_t packets = 0;
  if (scenario.lidar.model.has_packet_format()) {
    std::vector<std::uint8_t> pcap = lidar::pcap_global_header();
    const std::int64_t first = simulator.packet_index_at(scenario.start_ns);
    const std::int64_t last = simulator.packet_index_at(scenario.start_ns + frames * period);
    std::array<std::uint8_t, lidar::kPacketBytes> payload{};
    // A rotation's packets at a time (~150 of a VLP-32C at 10 Hz), simulated on the threads together.
    std::vector<lidar::PacketReturns> returns(
        static_cast<std::size_t>(simulator.packet_index_at(period) + 1));
    for (std::int64_t k = first; k < last; k += static_cast<std::int64_t>(returns.size())) {
      const auto n = static_cast<std::size_t>(std::min<std::int64_t>(last - k, std::ssize(returns)));
      simulator.simulate_packets(k, std::span(returns).first(n), threads);
      for (std::size_t i = 0; i < n; ++i) {
        lidar::encode_packet(scenario.lidar.model, returns[i], payload);
        lidar::append_udp_record(pcap, returns[i].blocks.first_firing_ns,
                                 {lidar::ipv4_address(192, 168, 1, 201), lidar::kVelodyneDataPort},
                                 {lidar::ipv4_address(255, 255, 255, 255), lidar::kVelodyneDataPort},
                                 payload);
        ++packets;
      }
    }
    write_file(out_dir / "packets.pcap", pcap);
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();

  std::printf("scenario   %s (%s)\n", scenario.name.c_str(), scenario.source.c_str());
  std::printf("lidar      %s, %zu lasers, mount (%.2f, %.2f, %.2f) m\n", scenario.lidar.model_name.c_str(),
              scenario.lidar.model.laser_count(), scenario.lidar.mount.x, scenario.lidar.mount.y,
              scenario.lidar.mount.z);
  std::printf("frames     %d x %.1f ms: %llu firings, %llu points (%.0f per frame)\n", frames,
              to_seconds(period) * 1e3, static_cast<unsigned long long>(total_firings),
              static_cast<unsigned long long>(total_points), static_cast<double>(total_points) / frames);
  std::printf("packets    %llu Velodyne data packets\n", static_cast<unsigned long long>(packets));
  std::printf("wall time  %.2f s on %d thread%s\n", seconds, threads, threads == 1 ? "" : "s");
  std::printf("output     %s\n", out_dir.string().c_str());
  return 0;
}

}  // namespace rsu::tools
