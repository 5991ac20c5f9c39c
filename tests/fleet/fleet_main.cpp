// SPDX-License-Identifier: Apache-2.0
// rsu-fleet: many connected vehicles in one process, for the load, fault and mis-association tests
// (issue 7). The scenario's vehicles announce their TRUE poses at the common clock (scenario time 0 =
// --epoch-ns, as rsu-sim stream is given), moved by a fixed error as a vehicle's own estimate would
// be; synthetic vehicles (--extra) announce static poses beyond the LiDAR's coverage, as vehicles in
// radio range but out of sight do. Each vehicle has its own UDP socket on its own loopback address
// (rsud rate-limits per source host), paced round-robin so the datagrams are spread evenly. With
// --signed each vehicle signs with its own test key (wire format v2), its trust list written first.
//
// Every correction received is written as one line to --corrections, with its error against the
// truth of the vehicle it was addressed to AND against the nearest OTHER scenario vehicle (connected
// or not), so the tests can count corrections sent to the wrong vehicle:
//   correction <recv ns> <socket's vehicle> <correction's vehicle> <rsu id> <sequence> <sweep ns>
//              <x> <y> <yaw> <points> <error to own truth m> <yaw error rad> <nearest other id>
//              <error to nearest other m> <the position error in sigmas of the stated covariance:
//              sqrt(e^T S^-1 e) over x, y>
// (errors -1 and other id 0 where there is no truth, i.e. for synthetic vehicles; recv ns: the kernel's
// stamp of its arrival at the vehicle's socket); and one line
//   size_change <vehicle> <send ns>
// when a vehicle first announces its changed size. At the end, on stdout:
//   summary sent=N send_failed=N corrections=N foreign=N undecodable=N
// (foreign: a correction naming another vehicle than the socket's owner).
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/epoll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <optional>
#include <stdexcept>
#include <tuple>
#include <variant>
#include <vector>

#include "common/angles.h"
#include "common/random.h"
#include "edge/arrival_stamp.h"
#include "edge/host_clock.h"
#include "sim/scenario.h"
#include "sim/trajectory.h"
#include "tests/fleet/fleet_options.h"
#include "v2i/message_signer.h"
#include "v2i/security/trust_list.h"
#include "v2i/wire_codec.h"

namespace rsu::fleet {
namespace {

std::string ipv4_text(std::uint32_t host_order) {
  in_addr a{};
  a.s_addr = htonl(host_order);
  char text[INET_ADDRSTRLEN] = {};
  inet_ntop(AF_INET, &a, text, sizeof text);
  return text;
}

sockaddr_in endpoint(std::uint32_t host_order_address, std::uint16_t port) {
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(port);
  a.sin_addr.s_addr = htonl(host_order_address);
  return a;
}

struct FleetVehicle {
  std::uint64_t id = 0;
  const sim::Vehicle* truth = nullptr;  // null for a synthetic vehicle
  Pose2 static_pose;                    // a synthetic vehicle's
  v2i::BoxSize size;
  std::optional<SizeChange> change;
  bool change_logged = false;
  int fd = -1;
  std::string address;
  std::uint16_t port = 0;
  std::uint32_t sequence = 0;
  std::optional<v2i::MessageSigner> signer;  // signed mode (--signed)
};

// Where the vehicles are: footprint-centre truth of every scenario vehicle at a scenario time.
class Truth {
 public:
  explicit Truth(const sim::Scenario& scenario) : scenario_(scenario) {}
  Pose2 pose(const sim::Vehicle& v, TimeNs scenario_ns) const {
    return sim::pose_at(v.trajectory, scenario_ns);
  }
  // The scenario vehicle other than `not_id` nearest to (x, y) at the time, and its distance.
  std::pair<std::uint64_t, double> nearest_other(std::uint64_t not_id, double x, double y, TimeNs t) const {
    std::pair<std::uint64_t, double> best{0, -1.0};
    for (const sim::Vehicle& v : scenario_.scene.vehicles) {
      if (v.id == not_id)
        continue;
      const Pose2 p = pose(v, t);
      const double d = std::hypot(p.x - x, p.y - y);
      if (best.second < 0 || d < best.second)
        best = {v.id, d};
    }
    return best;
  }

 private:
  const sim::Scenario& scenario_;
};

// The announcement's bytes: signed by the vehicle's own key (generation time = its clock) or unsigned.
std::vector<std::uint8_t> encode_announcement(FleetVehicle& v, const v2i::VehicleAnnouncement& a) {
  return v.signer ? v.signer->encode(a, a.generation_time) : v2i::encode_v2i_message(a);
}

// A vehicle's TEST key: the seed bytes are a counter-based hash of (key seed, vehicle id).
v2i::security::SigningKey test_key(std::uint64_t key_seed, std::uint64_t vehicle_id) {
  v2i::security::Seed seed{};
  for (std::size_t i = 0; i < seed.size(); i += 8) {
    const std::uint64_t bits = mix64(key_seed ^ mix64(vehicle_id ^ mix64(i)));
    for (std::size_t b = 0; b < 8; ++b)
      seed[i + b] = static_cast<std::uint8_t>(bits >> (8 * b));
  }
  return v2i::security::SigningKey(seed);
}

// Gives every vehicle its signer and writes their trust list (each key bound to its one vehicle id).
void sign_fleet(std::vector<FleetVehicle>& fleet, const FleetOptions& o, std::uint32_t first_sequence) {
  std::string text = "# rsu-fleet test keys (derived from the vehicle ids: tests only)\n";
  for (FleetVehicle& v : fleet) {
    const v2i::security::SigningKey key = test_key(o.key_seed, v.id);
    text += v2i::security::trust_entry_text(
        {key.public_key(), v2i::security::SignerRole::kVehicle, std::vector<std::uint64_t>{v.id}});
    v.signer.emplace(key, first_sequence);
  }
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> out(std::fopen(o.trust_list_path.c_str(), "w"),
                                                      std::fclose);
  if (!out || std::fputs(text.c_str(), out.get()) < 0)
    throw std::runtime_error("cannot write " + o.trust_list_path);
}

v2i::VehicleAnnouncement announcement_of(FleetVehicle& v, const Truth& truth, const FleetOptions& o,
                                         TimeNs now) {
  const TimeNs scenario_ns = now - o.epoch_ns;
  v2i::VehicleAnnouncement a;
  a.vehicle_id = v.id;
  a.sequence = ++v.sequence;
  a.generation_time = now + o.clock_offset_ns;
  a.size = v.size;
  if (v.change && scenario_ns >= v.change->at_scenario_ns)
    a.size = v.change->size;
  if (v.truth != nullptr) {
    const Pose2 p = truth.pose(*v.truth, scenario_ns);
    const sim::Velocity2 vel = sim::velocity_at(v.truth->trajectory, scenario_ns);
    a.pose = {p.x + o.pose_error_m, p.y - o.pose_error_m, p.yaw};
    a.speed_mps = vel.vx * std::cos(p.yaw) + vel.vy * std::sin(p.yaw);
    a.yaw_rate_rps = vel.yaw_rate;
  } else {
    a.pose = v.static_pose;
    a.speed_mps = 0.0;
    a.yaw_rate_rps = 0.0;
  }
  a.pose_covariance = Eigen::Vector3d(0.25, 0.25, 0.01).asDiagonal();
  a.reply_to = {v.address, v.port};
  return a;
}

std::vector<FleetVehicle> make_fleet(const sim::Scenario& scenario, const FleetOptions& o) {
  std::vector<FleetVehicle> fleet;
  for (const sim::Vehicle& sv : scenario.scene.vehicles) {
    bool connected = o.connected.empty();
    for (const std::uint32_t id : o.connected)
      connected = connected || id == sv.id;
    if (!connected)
      continue;
    FleetVehicle v;
    v.id = sv.id;
    v.truth = &sv;
    v.size = {sv.shape.length, sv.shape.width, sv.shape.height};
    if (const auto it = o.announced_size.find(sv.id); it != o.announced_size.end())
      v.size = it->second;
    if (const auto it = o.size_change.find(sv.id); it != o.size_change.end())
      v.change = it->second;
    fleet.push_back(v);
  }
  for (const std::uint32_t id : o.connected) {
    bool found = false;
    for (const FleetVehicle& v : fleet)
      found = found || v.id == id;
    if (!found)
      throw std::runtime_error("--connected: vehicle " + std::to_string(id) + " is not in the scenario");
  }
  // Synthetic vehicles on rings 80 to 280 m from the LiDAR, spread by the golden angle: in radio
  // range, beyond any coverage radius, so the RSU predicts and gates them every batch but never sees them.
  const double golden = kPi * (3.0 - std::sqrt(5.0));
  for (int k = 0; k < o.extra_vehicles; ++k) {
    FleetVehicle v;
    v.id = 100001 + static_cast<std::uint64_t>(k);
    const double r = 80.0 + (k % 200);
    const double a = golden * k;
    v.static_pose = {scenario.lidar.mount.x + r * std::cos(a), scenario.lidar.mount.y + r * std::sin(a),
                     wrap_angle(a + kPi / 2)};
    v.size = {4.5, 1.8, 1.5};
    fleet.push_back(v);
  }
  return fleet;
}

void open_sockets(std::vector<FleetVehicle>& fleet, const FleetOptions& o, int epoll_fd) {
  for (std::size_t k = 0; k < fleet.size(); ++k) {
    FleetVehicle& v = fleet[k];
    const std::uint32_t address = o.address_base + static_cast<std::uint32_t>(k);
    v.address = ipv4_text(address);
    v.fd = socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    sockaddr_in local = endpoint(address, 0);
    if (v.fd < 0 || bind(v.fd, reinterpret_cast<sockaddr*>(&local), sizeof local) != 0)
      throw std::runtime_error("cannot bind a socket to " + v.address);
    socklen_t len = sizeof local;
    getsockname(v.fd, reinterpret_cast<sockaddr*>(&local), &len);
    v.port = ntohs(local.sin_port);
    if (!rsu::edge::request_arrival_stamps(v.fd))
      throw std::runtime_error("no arrival timestamps on the socket of " + v.address);
    epoll_event ev{};
    ev.events = EPOLLIN;
    ev.data.u64 = k;
    if (epoll_ctl(epoll_fd, EPOLL_CTL_ADD, v.fd, &ev) != 0)
      throw std::runtime_error("epoll_ctl failed");
  }
}

struct Counts {
  std::uint64_t sent = 0;
  std::uint64_t send_failed = 0;
  std::uint64_t corrections = 0;
  std::uint64_t foreign = 0;
  std::uint64_t undecodable = 0;
};

void receive(FleetVehicle& v, const Truth& truth, const FleetOptions& o, std::FILE* out, Counts& counts) {
  std::array<std::uint8_t, 65536> buffer{};
  for (;;) {
    const rsu::edge::StampedRead read = rsu::edge::read_stamped(v.fd, buffer);
    const ssize_t n = read.bytes;
    if (n <= 0)
      return;  // drained (EAGAIN), or an ICMP error for an earlier datagram
    // Its arrival at the vehicle's socket, stamped by the kernel: not when this loop, busy signing the
    // fleet's announcements, got to it.
    const TimeNs received = read.arrival.value_or(rsu::edge::host_now_ns());
    const auto decoded = v2i::decode_v2i_message(std::span(buffer.data(), static_cast<std::size_t>(n)));
    const auto* c = std::get_if<v2i::Correction>(&decoded.body);
    if (c == nullptr) {
      ++counts.undecodable;
      continue;
    }
    ++counts.corrections;
    if (c->vehicle_id != v.id)
      ++counts.foreign;
    double error = -1.0, yaw_error = 0.0, other_error = -1.0, sigmas = -1.0;
    std::uint64_t other = 0;
    if (v.truth != nullptr) {
      const TimeNs t = c->sweep_time - o.epoch_ns;
      const Pose2 p = truth.pose(*v.truth, t);
      error = std::hypot(c->pose.x - p.x, c->pose.y - p.y);
      const Eigen::Vector2d e(c->pose.x - p.x, c->pose.y - p.y);
      const Eigen::Matrix2d stated = c->pose_covariance.topLeftCorner<2, 2>();
      if (stated.determinant() > 0.0)
        sigmas = std::sqrt(e.dot(stated.ldlt().solve(e)));
      yaw_error = wrap_angle(c->pose.yaw - p.yaw);
      std::tie(other, other_error) = truth.nearest_other(v.id, c->pose.x, c->pose.y, t);
    }
    if (out != nullptr) {
      std::fprintf(out, "correction %lld %llu %llu %llu %u %lld %.4f %.4f %.5f %u %.4f %.5f %llu %.4f %.3f\n",
                   static_cast<long long>(received), static_cast<unsigned long long>(v.id),
                   static_cast<unsigned long long>(c->vehicle_id), static_cast<unsigned long long>(c->rsu_id),
                   c->sequence, static_cast<long long>(c->sweep_time), c->pose.x, c->pose.y, c->pose.yaw,
                   c->quality.points_used, error, yaw_error, static_cast<unsigned long long>(other),
                   other_error, sigmas);
      std::fflush(out);
    }
  }
}

int run(const FleetOptions& o) {
  const sim::Scenario scenario = sim::load_scenario_file(o.scenario);
  const Truth truth(scenario);
  std::vector<FleetVehicle> fleet = make_fleet(scenario, o);
  // Sequences continue from the millisecond clock (at most 100 announcements a second), so a fleet
  // started again for the same vehicles is not refused as replaying old sequence numbers.
  const auto first_sequence = static_cast<std::uint32_t>(rsu::edge::host_now_ns() / kNsPerMs);
  for (FleetVehicle& v : fleet)
    v.sequence = first_sequence;
  if (!o.trust_list_path.empty()) {
    sign_fleet(fleet, o, first_sequence);
    if (o.write_trust_list_only)
      return 0;
  }
  if (fleet.empty())
    throw std::runtime_error("no vehicle to announce");
  const int epoll_fd = epoll_create1(EPOLL_CLOEXEC);
  if (epoll_fd < 0)
    throw std::runtime_error("epoll_create1 failed");
  open_sockets(fleet, o, epoll_fd);
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> out(nullptr, std::fclose);
  if (!o.corrections_path.empty()) {
    out.reset(std::fopen(o.corrections_path.c_str(), "w"));
    if (!out)
      throw std::runtime_error("cannot write " + o.corrections_path);
  }
  const sockaddr_in rsu = endpoint(ntohl(inet_addr(o.rsu_address.c_str())), o.rsu_port);

  // Round-robin slots, slot j at start + j / (rate * N): every vehicle at `rate`, spread evenly.
  const TimeNs start = rsu::edge::host_now_ns();
  const TimeNs end = start + from_seconds(o.seconds);
  const double slots_per_ns = o.rate_hz * static_cast<double>(fleet.size()) * 1e-9;
  std::uint64_t next_slot = 0;
  Counts counts;
  std::array<epoll_event, 64> events{};
  for (TimeNs now = rsu::edge::host_now_ns(); now < end; now = rsu::edge::host_now_ns()) {
    const auto due = static_cast<std::uint64_t>(static_cast<double>(now - start) * slots_per_ns) + 1;
    for (; next_slot < due; ++next_slot) {
      FleetVehicle& v = fleet[next_slot % fleet.size()];
      const v2i::VehicleAnnouncement a = announcement_of(v, truth, o, now);
      const bool changed = v.change && now - o.epoch_ns >= v.change->at_scenario_ns;
      if (changed && !v.change_logged && out) {
        std::fprintf(out.get(), "size_change %llu %lld\n", static_cast<unsigned long long>(v.id),
                     static_cast<long long>(now));
        v.change_logged = true;
      }
      const std::vector<std::uint8_t> bytes = encode_announcement(v, a);
      const ssize_t n =
          sendto(v.fd, bytes.data(), bytes.size(), 0, reinterpret_cast<const sockaddr*>(&rsu), sizeof rsu);
      n == static_cast<ssize_t>(bytes.size()) ? ++counts.sent : ++counts.send_failed;
    }
    const int ready = epoll_wait(epoll_fd, events.data(), static_cast<int>(events.size()), 1);
    for (int i = 0; i < ready; ++i)
      receive(fleet[events[static_cast<std::size_t>(i)].data.u64], truth, o, out.get(), counts);
  }
  for (FleetVehicle& v : fleet)
    close(v.fd);
  close(epoll_fd);
  std::printf(
      "summary sent=%llu send_failed=%llu corrections=%llu foreign=%llu undecodable=%llu\n",
      static_cast<unsigned long long>(counts.sent), static_cast<unsigned long long>(counts.send_failed),
      static_cast<unsigned long long>(counts.corrections), static_cast<unsigned long long>(counts.foreign),
      static_cast<unsigned long long>(counts.undecodable));
  return 0;
}

}  // namespace
}  // namespace rsu::fleet

int main(int argc, char** argv) {
  try {
    return rsu::fleet::run(rsu::fleet::parse_fleet_options(argc, argv));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rsu-fleet: %s\n", e.what());
    return 2;
  }
}
