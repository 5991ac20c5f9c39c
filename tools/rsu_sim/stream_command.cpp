// SPDX-License-Identifier: Apache-2.0
// rsu-sim stream: the scenario's Velodyne data packets over UDP, or with --ouster an Ouster's lidar
// packets (sim/ouster_simulator.h; the metadata JSON rsud needs written to --metadata-out), paced at real
// time (as a sensor sends them) or as fast as possible. Packet times are the simulation clock; with --clock
// wall the simulation clock is shifted so that the first packet is "now" on the host clock (the common clock
// of tests on one machine). --loss and --reorder impair the stream as a bad network would (issue 7's
// fault tests), drawn per packet from a counter-based random stream, so a seed repeats a run exactly.
// --truth-out logs, for each packet sent with returns on a vehicle, when it left and which vehicles: the
// ray caster's truth of the last packet covering a vehicle, from which the load test measures latency.
#include <utility>  // before Asio: Boost 1.74's awaitable.hpp uses std::exchange under C++20

#include <boost/asio.hpp>
#include <boost/program_options.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <optional>
#include <thread>

#include "common/random.h"
#include "edge/address_text.h"
#include "edge/host_clock.h"
#include "lidar/velodyne_packet.h"
#include "sim/lidar_simulator.h"
#include "sim/ouster_simulator.h"
#include "sim/scenario.h"
#include "tools/rsu_sim/commands.h"
#include "tools/rsu_sim/scenario_options.h"

namespace rsu::tools {
namespace po = boost::program_options;
namespace asio = boost::asio;

namespace {

// Uniform in (0, 1) for packet k of the impairment stream `stream` (1 loss, 2 reordering).
double impairment_draw(std::uint64_t seed, std::uint64_t stream, std::int64_t k) {
  return uniform_open01(mix64(seed ^ mix64(stream ^ mix64(static_cast<std::uint64_t>(k)))));
}

// --truth-out: one line per sent packet whose returns lie on vehicles, "SENT_NS K ID [ID ...]" (host clock
// just after the send, the packet's index in the schedule, the vehicles' ids).
class TruthLog {
 public:
  explicit TruthLog(const po::variables_map& vm) {
    if (!vm.count("truth-out"))
      return;
    path_ = vm["truth-out"].as<std::string>();
    out_.open(path_);
    if (!out_)
      throw std::runtime_error("stream: cannot write " + path_);
    out_ << "# sent_host_ns packet vehicle_ids: packets with returns on vehicles, as sent\n";
  }
  bool enabled() const { return out_.is_open(); }
  void sent(std::int64_t k, const std::vector<std::uint32_t>& vehicles) {
    if (!enabled() || vehicles.empty())
      return;
    out_ << edge::host_now_ns() << ' ' << k;
    for (const std::uint32_t id : vehicles)
      out_ << ' ' << id;
    out_ << '\n';
  }
  void close() {
    if (enabled() && !out_.flush())
      throw std::runtime_error("stream: cannot write " + path_);
  }

 private:
  std::string path_;
  std::ofstream out_;
};

double fraction_option(const po::variables_map& vm, const char* name) {
  const double v = vm[name].as<double>();
  if (!(v >= 0.0 && v < 1.0))
    throw std::runtime_error(std::string("stream: --") + name + " must be within [0, 1)");
  return v;
}

// The Ouster's packets (--ouster): paced like the Velodyne stream, its columns stamped on the shared
// clock (a sensor synchronised by PTP); no impairments.
int stream_ouster(const po::variables_map& vm, const sim::Scenario& scenario, double seconds,
                  bool wall_clock) {
  if (!vm.count("metadata-out"))
    throw std::runtime_error("stream: --ouster needs --metadata-out FILE (the metadata rsud reads)");
  if (scenario.lidar.mount_motion || vm["loss"].as<double>() > 0.0 || vm["reorder"].as<double>() > 0.0)
    throw std::runtime_error("stream: --ouster has no moving mount, --loss or --reorder");
  sim::OusterSpec spec;
  spec.model = vm["ouster"].as<std::string>();
  spec.lidar_mode = vm["lidar-mode"].as<std::string>();
  const auto profile = lidar::ouster::udp_profile_from_string(vm["profile"].as<std::string>());
  if (!profile)
    throw std::runtime_error("stream: --profile must be LEGACY, RNG19_RFL8_SIG16_NIR16 or RNG15_RFL8_NIR8");
  spec.profile = *profile;
  const std::string json = sim::ouster_metadata_json(spec);
  const std::string metadata_path = vm["metadata-out"].as<std::string>();
  {
    std::ofstream out(metadata_path);
    out << json;
    if (!out.flush())
      throw std::runtime_error("stream: cannot write " + metadata_path);
  }
  const lidar::ouster::Metadata metadata = lidar::ouster::parse_metadata(json, metadata_path);
  const sim::Raycaster raycaster(scenario.scene);
  const sim::OusterSimulator simulator(metadata, scenario.lidar.mount, scenario.lidar.noise, raycaster);
  const TimeNs sim_start = vm.count("start") ? from_seconds(vm["start"].as<double>()) : scenario.start_ns;
  const bool has_epoch = vm.count("epoch-ns") > 0;
  const bool fast = vm.count("fast") > 0;
  const TimeNs clock_offset = has_epoch    ? static_cast<TimeNs>(vm["epoch-ns"].as<long long>())
                              : wall_clock ? edge::host_now_ns() - sim_start
                                           : 0;

  asio::io_context io;
  asio::ip::udp::socket socket(io);
  const auto destination = edge::parse_udp_endpoint(vm["to"].as<std::string>());
  socket.open(destination.protocol());
  const auto wall_start = std::chrono::steady_clock::now();
  const std::int64_t first = simulator.packet_index_at(sim_start);
  const std::int64_t last = simulator.packet_index_at(sim_start + from_seconds(seconds));
  std::vector<std::uint8_t> payload;
  std::vector<std::uint32_t> vehicles;
  TruthLog truth(vm);
  std::uint64_t sent = 0, failed = 0, late = 0;
  constexpr TimeNs kLateNs = 1'000'000;
  TimeNs max_behind = 0;
  for (std::int64_t k = first; k < last; ++k) {
    // The packet leaves once its last column has fired, as a sensor sends it. Its returns are cast
    // before that (as the Velodyne stream does): cast after, the ray caster's time delayed every packet
    // (an OS1-128 packet's 2,048 rays, encoded and sent: 156 us, the load street --fast) and with it the
    // release of every cluster, which the load test counted as rsud's latency.
    simulator.packet(k, clock_offset, payload, truth.enabled() ? &vehicles : nullptr);
    const TimeNs due = simulator.packet_time_ns(k + 1);
    if (has_epoch && !fast) {
      std::this_thread::sleep_until(std::chrono::system_clock::time_point(
          std::chrono::duration_cast<std::chrono::system_clock::duration>(
              std::chrono::nanoseconds(due + clock_offset))));
    } else if (!fast) {
      std::this_thread::sleep_until(wall_start + std::chrono::nanoseconds(due - sim_start));
    }
    // How far behind its firing the packet leaves: a sender behind its schedule sends back to back,
    // faster than the sensor would, until it has caught up.
    if (!fast) {
      const TimeNs now = has_epoch ? edge::host_now_ns() - clock_offset
                                   : sim_start + std::chrono::duration_cast<std::chrono::nanoseconds>(
                                                     std::chrono::steady_clock::now() - wall_start)
                                                     .count();
      const TimeNs behind = now - due;
      if (behind > kLateNs)
        ++late;
      max_behind = std::max(max_behind, behind);
    }
    boost::system::error_code ec;
    socket.send_to(asio::buffer(payload), destination, 0, ec);
    ec ? ++failed : ++sent;
    if (!ec)
      truth.sent(k, vehicles);
  }
  truth.close();
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  std::printf(
      "sent %llu %s packets (%s, %s, %zu bytes; %llu failed) to %s in %.2f s; metadata %s; "
      "%llu sent more than 1 ms after their last column fired (at most %.1f ms)\n",
      static_cast<unsigned long long>(sent), spec.model.c_str(), spec.lidar_mode.c_str(),
      std::string(lidar::ouster::to_string(spec.profile)).c_str(), payload.size(),
      static_cast<unsigned long long>(failed), vm["to"].as<std::string>().c_str(), wall,
      metadata_path.c_str(), static_cast<unsigned long long>(late),
      static_cast<double>(std::max<TimeNs>(max_behind, 0)) * 1e-6);
  return failed == 0 ? 0 : 1;
}

}  // namespace

int run_stream(const std::vector<std::string>& args) {
  po::options_description options("rsu-sim stream SCENARIO --to HOST:PORT [options]");
  options.add_options()("help,h", "show this help")("to", po::value<std::string>(),
                                                    "destination, e.g. 127.0.0.1:2368")(
      "seconds", po::value<double>()->default_value(10.0), "simulated seconds to send")(
      "start", po::value<double>(), "simulation start time, s (default: the scenario's simulation.start_s)")(
      "fast", "send as fast as possible instead of at real time")(
      "clock", po::value<std::string>()->default_value("sim"),
      "packet time base: sim (scenario time) or wall (shifted to the host clock at start)")(
      "epoch-ns", po::value<long long>(),
      "host-clock time (ns since the Unix epoch) of scenario time 0: packets carry scenario time + epoch and "
      "are paced against the host clock, so that other processes given the same epoch share the clock")(
      "loss", po::value<double>()->default_value(0.0), "fraction of packets not sent (network loss)")(
      "reorder", po::value<double>()->default_value(0.0),
      "fraction of packets held back and sent after the next one (network reordering)")(
      "impair-seed", po::value<unsigned long long>()->default_value(1), "seed of --loss and --reorder")(
      "ouster", po::value<std::string>(),
      "send an Ouster's lidar packets instead: os0-, os1- or os2- and 16, 32, 64 or 128 beams (os1-128)")(
      "lidar-mode", po::value<std::string>()->default_value("1024x10"),
      "with --ouster: columns x Hz (512x10, 512x20, 1024x10, 1024x20, 2048x10)")(
      "profile", po::value<std::string>()->default_value("RNG19_RFL8_SIG16_NIR16"),
      "with --ouster: LEGACY, RNG19_RFL8_SIG16_NIR16 or RNG15_RFL8_NIR8")(
      "metadata-out", po::value<std::string>(),
      "with --ouster: write the sensor's metadata JSON here (rsud's lidar.metadata) and start")(
      "truth-out", po::value<std::string>(),
      "log each sent packet with returns on vehicles: host-clock send time (ns), packet index, vehicle ids");
  add_scenario_options(options);
  po::positional_options_description positional;
  positional.add("scenario", 1);
  po::variables_map vm;
  po::store(po::command_line_parser(args).options(options).positional(positional).run(), vm);
  po::notify(vm);
  if (vm.count("help")) {
    std::cout << options;
    return 0;
  }
  if (!vm.count("to"))
    throw std::runtime_error("stream: --to HOST:PORT is required");
  const std::string clock = vm["clock"].as<std::string>();
  if (clock != "sim" && clock != "wall")
    throw std::runtime_error("stream: --clock must be sim or wall");
  const double seconds = vm["seconds"].as<double>();
  if (!(seconds > 0 && seconds <= 86400))
    throw std::runtime_error("stream: --seconds must be within (0, 86400]");

  const double loss = fraction_option(vm, "loss");
  const double reorder = fraction_option(vm, "reorder");
  const std::uint64_t impair_seed = vm["impair-seed"].as<unsigned long long>();

  const sim::Scenario scenario = load_scenario(vm);
  if (vm.count("ouster"))
    return stream_ouster(vm, scenario, seconds, clock == "wall");
  if (!scenario.lidar.model.has_packet_format())
    throw std::runtime_error("stream: LiDAR model " + scenario.lidar.model_name +
                             " has no Velodyne packet format");
  const TimeNs sim_start = vm.count("start") ? from_seconds(vm["start"].as<double>()) : scenario.start_ns;
  // A scenario whose LiDAR moves mid-run (lidar.mount_motion: a bumped pole) rides it on a carrier.
  const sim::Raycaster raycaster(scenario.scene);
  const sim::MovingMount moving = sim::moving_mount(scenario.lidar);
  const bool moves = scenario.lidar.mount_motion.has_value();
  const sim::LidarSimulator simulator(
      scenario.lidar.model, moves ? moving.mount_on_carrier : scenario.lidar.mount, scenario.lidar.noise,
      raycaster, 0, scenario.lidar.start_azimuth_deg, moves ? &moving.carrier : nullptr);

  asio::io_context io;
  asio::ip::udp::socket socket(io);
  const auto destination = edge::parse_udp_endpoint(vm["to"].as<std::string>());
  socket.open(destination.protocol());

  const std::int64_t first = simulator.packet_index_at(sim_start);
  const std::int64_t last = simulator.packet_index_at(sim_start + from_seconds(seconds));
  const auto wall_start = std::chrono::steady_clock::now();
  // Shifts only the packets' timestamps: the scene keeps moving on the scenario's clock.
  const bool has_epoch = vm.count("epoch-ns") > 0;
  const TimeNs clock_offset = has_epoch         ? static_cast<TimeNs>(vm["epoch-ns"].as<long long>())
                              : clock == "wall" ? edge::host_now_ns() - sim_start
                                                : 0;
  // A packet with the vehicles its returns are on (--truth-out).
  struct Packet {
    std::int64_t k = 0;
    std::array<std::uint8_t, lidar::kPacketBytes> bytes{};
    std::vector<std::uint32_t> vehicles;
  };
  Packet packet;
  std::optional<Packet> held_back;  // sent after the next packet
  TruthLog truth(vm);
  std::uint64_t sent = 0, failed = 0, dropped = 0, reordered = 0;
  const auto send = [&](const Packet& p) {
    boost::system::error_code ec;
    socket.send_to(asio::buffer(p.bytes), destination, 0, ec);
    ec ? ++failed : ++sent;
    if (!ec)
      truth.sent(p.k, p.vehicles);
  };
  const TimeNs packet_period = simulator.schedule().packet_period_ns();
  for (std::int64_t k = first; k < last; ++k) {
    lidar::PacketReturns returns =
        simulator.simulate_packet(k, std::nullopt, truth.enabled() ? &packet.vehicles : nullptr);
    packet.k = k;
    // The packet leaves once its last firing has fired, as a sensor sends it.
    const TimeNs due = returns.blocks.first_firing_ns + packet_period;
    if (has_epoch && !vm.count("fast")) {
      std::this_thread::sleep_until(std::chrono::system_clock::time_point(
          std::chrono::duration_cast<std::chrono::system_clock::duration>(
              std::chrono::nanoseconds(due + clock_offset))));
    } else if (!vm.count("fast")) {
      std::this_thread::sleep_until(wall_start + std::chrono::nanoseconds(due - sim_start));
    }
    returns.blocks.first_firing_ns += clock_offset;
    lidar::encode_packet(scenario.lidar.model, returns, packet.bytes);
    if (loss > 0.0 && impairment_draw(impair_seed, 1, k) < loss) {
      ++dropped;
      continue;
    }
    if (!held_back && reorder > 0.0 && impairment_draw(impair_seed, 2, k) < reorder) {
      held_back = packet;
      ++reordered;
      continue;
    }
    send(packet);
    if (held_back) {
      send(*held_back);
      held_back.reset();
    }
  }
  if (held_back)
    send(*held_back);
  truth.close();
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  std::printf("sent %llu packets (%llu failed, %llu dropped, %llu reordered) to %s in %.2f s\n",
              static_cast<unsigned long long>(sent), static_cast<unsigned long long>(failed),
              static_cast<unsigned long long>(dropped), static_cast<unsigned long long>(reordered),
              vm["to"].as<std::string>().c_str(), wall);
  return failed == 0 ? 0 : 1;
}

}  // namespace rsu::tools
