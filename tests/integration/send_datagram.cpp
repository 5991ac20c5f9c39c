// SPDX-License-Identifier: Apache-2.0
// Test helper for the integration tests: sends ONE crafted V2I datagram, signed with --key or unsigned
// (--unsigned 1), from a UDP socket on --from: a forged correction (a key the vehicle does not trust),
// an unsigned announcement, a stale one (--age-ms). Python has no libsodium binding here, so the
// harness signs through this. Prints the datagram's hex and exits 0 once sent.
//   rsud_test_send --to IP:PORT --kind correction|announcement --id VEHICLE (--key FILE | --unsigned 1)
//                  [--from IP] [--rsu-id N] [--seq N] [--reply-port P] [--age-ms A]
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <string>

#include "edge/host_clock.h"
#include "helper_io.h"
#include "v2i/security/key_text.h"
#include "v2i/wire_codec.h"

namespace {

[[noreturn]] void usage(const std::string& why) {
  std::fprintf(
      stderr,
      "send_datagram: %s\nusage: rsud_test_send --to IP:PORT --kind correction|announcement --id N "
      "(--key FILE | --unsigned 1) [--from IP] [--rsu-id N] [--seq N] [--reply-port P] [--age-ms A]\n",
      why.c_str());
  std::exit(2);
}

sockaddr_in ipv4(const std::string& ip, int port) {
  const auto a = rsu::integration::ipv4_endpoint(ip, port);
  if (!a)
    usage("not an IPv4 address: " + ip);
  return *a;
}

}  // namespace

int main(int argc, char** argv) {
  std::string to_text, from = "127.0.0.1", kind, key_path;
  bool unsigned_message = false;
  std::uint64_t id = 0, rsu_id = 1;
  std::uint32_t seq = 1;
  int reply_port = 9;
  long age_ms = 0;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string k = argv[i], v = argv[i + 1];
    if (k == "--to")
      to_text = v;
    else if (k == "--from")
      from = v;
    else if (k == "--kind")
      kind = v;
    else if (k == "--key")
      key_path = v;
    else if (k == "--unsigned")
      unsigned_message = v == "1";
    else if (k == "--id")
      id = std::strtoull(v.c_str(), nullptr, 10);
    else if (k == "--rsu-id")
      rsu_id = std::strtoull(v.c_str(), nullptr, 10);
    else if (k == "--seq")
      seq = static_cast<std::uint32_t>(std::strtoul(v.c_str(), nullptr, 10));
    else if (k == "--reply-port")
      reply_port = std::atoi(v.c_str());
    else if (k == "--age-ms")
      age_ms = std::atol(v.c_str());
    else
      usage("unknown option " + k);
  }
  const auto colon = to_text.rfind(':');
  if (colon == std::string::npos || id == 0 || (kind != "correction" && kind != "announcement"))
    usage("--to, --kind and --id are required");
  if (unsigned_message == !key_path.empty())
    usage("give --key FILE or --unsigned 1");
  std::optional<rsu::v2i::security::SigningKey> key;
  if (!key_path.empty()) {
    const auto text = rsu::integration::file_text(key_path);
    if (!text)
      usage("cannot read " + key_path);
    try {
      key = rsu::v2i::security::parse_secret_key_text(*text, key_path);
    } catch (const std::exception& e) {
      usage(e.what());
    }
  }
  const rsu::TimeNs now = rsu::edge::host_now_ns() - age_ms * rsu::kNsPerMs;
  const rsu::v2i::MessageHeader header{now, seq};
  const rsu::v2i::security::SigningKey* signer = key ? &*key : nullptr;
  std::vector<std::uint8_t> bytes;
  if (kind == "correction") {
    rsu::v2i::Correction c;  // a plausible fix 2 m off where any vehicle in the tests is
    c.rsu_id = rsu_id;
    c.vehicle_id = id;
    c.sequence = seq;
    c.sweep_time = now - 20 * rsu::kNsPerMs;
    c.pose = {17.0, 6.0, 0.35};
    c.pose_covariance = Eigen::Vector3d(0.01, 0.01, 0.001).asDiagonal();
    c.quality.points_used = 100;
    bytes = rsu::v2i::encode_v2i_message(c, header, signer);
  } else {
    rsu::v2i::VehicleAnnouncement a;
    a.vehicle_id = id;
    a.sequence = seq;
    a.generation_time = now;
    a.size = {4.89, 1.92, 1.70};
    a.pose = {30.0, -20.0, 0.1};
    a.pose_covariance = Eigen::Vector3d(0.25, 0.25, 0.01).asDiagonal();
    a.reply_to = {from, static_cast<std::uint32_t>(reply_port)};
    bytes = rsu::v2i::encode_v2i_message(a, header, signer);
  }
  const int fd = socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in local = ipv4(from, 0);
  if (fd < 0 || bind(fd, reinterpret_cast<sockaddr*>(&local), sizeof local) != 0)
    usage("cannot bind " + from);
  const sockaddr_in to = ipv4(to_text.substr(0, colon), std::atoi(to_text.substr(colon + 1).c_str()));
  const ssize_t sent =
      sendto(fd, bytes.data(), bytes.size(), 0, reinterpret_cast<const sockaddr*>(&to), sizeof to);
  close(fd);
  if (sent != static_cast<ssize_t>(bytes.size()))
    usage("send failed");
  std::printf("%s\n", rsu::v2i::security::to_hex(bytes).c_str());
  return 0;
}
