// SPDX-License-Identifier: Apache-2.0
// Test helper for the integration tests: a minimal connected vehicle. Announces a fixed pose at 10 Hz
// to rsud from a UDP socket on --bind, signed with --key (or unsigned with --insecure), and prints
// every correction it accepts on that socket (signed mode: verified against --trust-list, fresh, not
// replayed; v2i/message_authenticator.h), one line each, flushed:
//   correction <receive time ns> <vehicle id> <sequence> <sweep time ns> <x> <y> <yaw> <points> <faces> <rsu
//   id>
// and every datagram it refuses as "refused <verdict>". With --dump-bytes it also prints the bytes of
// each announcement sent ("announced <hex>") and of each correction accepted ("received <hex>"), for
// replay tests. Runs for --seconds and exits 0. Plain POSIX sockets: no dependence on the vehicle client.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "edge/host_clock.h"
#include "helper_io.h"
#include "v2i/message_authenticator.h"
#include "v2i/message_signer.h"
#include "v2i/messages.h"
#include "v2i/security/key_text.h"
#include "v2i/security/trust_list.h"
#include "v2i/wire_codec.h"

namespace {

[[noreturn]] void usage(const char* why) {
  std::fprintf(stderr,
               "announcer: %s\nusage: announcer --rsu IP:PORT --bind IP --id N --pose X,Y,YAW [--seconds S]\n"
               "                 (--key FILE --trust-list FILE | --insecure 1) [--dump-bytes 1]\n",
               why);
  std::exit(2);
}

sockaddr_in ipv4(const std::string& ip, int port) {
  const auto a = rsu::integration::ipv4_endpoint(ip, port);
  if (!a)
    usage("not an IPv4 address");
  return *a;
}

std::string read_file(const std::string& path) {
  const auto text = rsu::integration::file_text(path);
  if (!text)
    usage(("cannot read " + path).c_str());
  return *text;
}

}  // namespace

int main(int argc, char** argv) {
  std::string rsu, bind_ip = "127.0.0.1";
  std::uint64_t id = 1;
  double x = 0, y = 0, yaw = 0, seconds = 10;
  std::string key_path, trust_path;
  bool insecure = false, dump = false;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string k = argv[i], v = argv[i + 1];
    if (k == "--rsu")
      rsu = v;
    else if (k == "--bind")
      bind_ip = v;
    else if (k == "--id")
      id = std::strtoull(v.c_str(), nullptr, 10);
    else if (k == "--key")
      key_path = v;
    else if (k == "--trust-list")
      trust_path = v;
    else if (k == "--insecure")
      insecure = v == "1";
    else if (k == "--dump-bytes")
      dump = v == "1";
    else if (k == "--seconds")
      seconds = std::strtod(v.c_str(), nullptr);
    else if (k == "--pose") {
      if (std::sscanf(v.c_str(), "%lf,%lf,%lf", &x, &y, &yaw) != 3)
        usage("--pose X,Y,YAW");
    } else
      usage("unknown option");
  }
  const auto colon = rsu.rfind(':');
  if (colon == std::string::npos)
    usage("--rsu IP:PORT is required");
  const sockaddr_in to = ipv4(rsu.substr(0, colon), std::atoi(rsu.substr(colon + 1).c_str()));
  if (!insecure && (key_path.empty() || trust_path.empty()))
    usage("--key and --trust-list are required (or --insecure 1)");
  rsu::v2i::SecurityConfig security;
  security.mode = insecure ? rsu::v2i::SecurityMode::kInsecure : rsu::v2i::SecurityMode::kSigned;
  std::optional<rsu::v2i::security::SigningKey> key;
  rsu::v2i::security::TrustList trust;
  try {
    if (!insecure) {
      key = rsu::v2i::security::parse_secret_key_text(read_file(key_path), key_path);
      trust = rsu::v2i::security::parse_trust_list_text(read_file(trust_path), trust_path);
    }
  } catch (const std::exception& e) {
    usage(e.what());
  }
  rsu::v2i::MessageSigner signer(key);
  rsu::v2i::MessageAuthenticator authenticator(security, trust);

  const int fd = socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in local = ipv4(bind_ip, 0);
  if (fd < 0 || bind(fd, reinterpret_cast<sockaddr*>(&local), sizeof local) != 0)
    usage("cannot bind");
  socklen_t len = sizeof local;
  getsockname(fd, reinterpret_cast<sockaddr*>(&local), &len);
  std::printf("bound %d\n", ntohs(local.sin_port));
  std::fflush(stdout);

  rsu::v2i::VehicleAnnouncement a;
  a.vehicle_id = id;
  a.size = {4.89, 1.92, 1.70};  // docs/design.md §2: the Lexus RX450h the scenarios drive
  a.pose = {x, y, yaw};
  a.pose_covariance = Eigen::Vector3d(0.25, 0.25, 0.01).asDiagonal();
  a.speed_mps = 0.0;
  a.yaw_rate_rps = 0.0;
  a.reply_to = {bind_ip, ntohs(local.sin_port)};

  const rsu::TimeNs end = rsu::edge::host_now_ns() + static_cast<rsu::TimeNs>(seconds * 1e9);
  rsu::TimeNs next_announce = rsu::edge::host_now_ns();
  std::vector<std::uint8_t> buffer(65536);
  for (rsu::TimeNs now = rsu::edge::host_now_ns(); now < end; now = rsu::edge::host_now_ns()) {
    if (now >= next_announce) {
      a.sequence += 1;
      a.generation_time = now;
      const auto bytes = signer.encode(a, now);
      sendto(fd, bytes.data(), bytes.size(), 0, reinterpret_cast<const sockaddr*>(&to), sizeof to);
      if (dump) {
        std::printf("announced %s\n", rsu::v2i::security::to_hex(bytes).c_str());
        std::fflush(stdout);
      }
      next_announce += 100'000'000;
    }
    pollfd p{fd, POLLIN, 0};
    const auto wait_ms = static_cast<int>(std::max<rsu::TimeNs>(1, (next_announce - now) / 1'000'000));
    if (poll(&p, 1, wait_ms) <= 0)
      continue;
    const ssize_t n = recv(fd, buffer.data(), buffer.size(), 0);
    if (n <= 0)
      continue;
    const std::span<const std::uint8_t> datagram(buffer.data(), static_cast<std::size_t>(n));
    const rsu::v2i::AuthenticatedMessage heard =
        authenticator.authenticate(datagram, rsu::edge::host_now_ns());
    // rsud's own notice that this vehicle's fix was withheld (position_unbounded after shed packets, in a
    // loaded sanitizer pass) is genuine: neither a correction nor a refusal.
    const auto* w = std::get_if<rsu::v2i::FixWithheld>(&heard.message.body);
    if (heard.accepted() && w != nullptr && w->vehicle_id == id) {
      std::printf("withheld\n");
      std::fflush(stdout);
      continue;
    }
    const auto* c = std::get_if<rsu::v2i::Correction>(&heard.message.body);
    if (!heard.accepted() || c == nullptr || c->vehicle_id != id) {
      std::printf("refused %s\n", heard.accepted() ? "not_mine" : rsu::v2i::to_string(heard.verdict));
      std::fflush(stdout);
      continue;
    }
    if (dump)
      std::printf("received %s\n", rsu::v2i::security::to_hex(datagram).c_str());
    // The stated position covariance last (xx, xy, yy): what the vehicle was promised.
    std::printf("correction %lld %llu %u %lld %.4f %.4f %.5f %u %u %llu %.6g %.6g %.6g\n",
                static_cast<long long>(rsu::edge::host_now_ns()),
                static_cast<unsigned long long>(c->vehicle_id), c->sequence,
                static_cast<long long>(c->sweep_time), c->pose.x, c->pose.y, c->pose.yaw,
                c->quality.points_used, c->quality.faces_seen, static_cast<unsigned long long>(c->rsu_id),
                c->pose_covariance(0, 0), c->pose_covariance(0, 1), c->pose_covariance(1, 1));
    std::fflush(stdout);
  }
  close(fd);
  return 0;
}
