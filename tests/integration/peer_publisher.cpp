// SPDX-License-Identifier: Apache-2.0
// Test helper for handover_integration.py's bad_peers case: a misbehaving "RSU" on the peer bus. It
// joins the DDS domain, waits (bounded) until rsud's peer reader matches, and publishes on the peer
// topic, in this order (each phase waits, bounded, for the test to create --go-dir's DIR/bad and
// DIR/flood: the test sees rsud take the bad samples before the flood can push them out of its reader's
// history, whatever the load; fixed sleeps did not hold under TSan):
//   3 samples whose datagram is garbage                      (origin 77)
//   3 valid announcements whose reply_to is not the sender   (origin 77)
//   3 valid announcements carrying rsud's own rsu_id          (origin --rsu-id: a duplicated id)
//   3 samples without a sender address                       (origin 77)
//   --flood garbage samples as fast as it can                 (origin 78)
//   then valid announcements of vehicle 9 at 10 Hz for 1 s    (origin 79: a well-behaved peer)
// and prints one line per group. Exits 0, or 1 when rsud's reader did not match within 10 s or a go
// file did not appear within 30 s.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "dds/participant.h"
#include "dds/typed_entities.h"
#include "edge/host_clock.h"
#include "rsu_msgs.h"
#include "v2i/messages.h"
#include "v2i/wire_codec.h"

namespace {

using Sample = rsu_msgs_msg_dds__PeerAnnouncement_;

[[noreturn]] void usage(const char* why) {
  std::fprintf(stderr,
               "peer_publisher: %s\nusage: peer_publisher --domain N --cyclone-config FILE --topic ROS_NAME "
               "--rsu-id N --go-dir DIR [--flood N]\n",
               why);
  std::exit(2);
}

// The port the shared vehicles announced from, and named in their reply_to (which must match it).
constexpr std::uint16_t kVehiclePort = 40000;

std::vector<std::uint8_t> announcement(std::uint64_t vehicle, std::uint32_t sequence,
                                       const std::string& reply) {
  rsu::v2i::VehicleAnnouncement a;
  a.vehicle_id = vehicle;
  a.sequence = sequence;
  a.generation_time = rsu::edge::host_now_ns();
  a.size = {4.89, 1.92, 1.70};
  a.pose = {10.0, 2.0, 0.0};
  a.pose_covariance = Eigen::Vector3d(0.25, 0.25, 0.01).asDiagonal();
  a.reply_to = {reply, kVehiclePort};
  return rsu::v2i::encode_v2i_message(a);
}

void publish(rsu::dds::Writer<Sample>& writer, std::uint64_t origin, const char* sender,
             std::vector<std::uint8_t> datagram) {
  Sample s{};
  s.origin_rsu_id = origin;
  s.sender_address = const_cast<char*>(sender);
  s.sender_port = sender != nullptr ? kVehiclePort : 0;
  s.datagram._buffer = datagram.data();
  s.datagram._length = static_cast<std::uint32_t>(datagram.size());
  s.datagram._maximum = s.datagram._length;
  s.datagram._release = false;
  writer.write(s);
}

// Waits (bounded) until `dir`/`name` exists.
bool wait_for_go(const std::string& dir, const char* name) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (!std::filesystem::exists(std::filesystem::path(dir) / name)) {
    if (std::chrono::steady_clock::now() > deadline) {
      std::fprintf(stderr, "peer_publisher: %s/%s did not appear within 30 s\n", dir.c_str(), name);
      return false;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  rsu::dds::ParticipantConfig pc;
  std::string topic;
  std::uint64_t rsu_id = 0;
  int flood = 5000;
  std::string go_dir;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string k = argv[i], v = argv[i + 1];
    if (k == "--domain")
      pc.domain_id = static_cast<std::uint32_t>(std::strtoul(v.c_str(), nullptr, 10));
    else if (k == "--cyclone-config")
      pc.cyclone_config = v;
    else if (k == "--topic")
      topic = v;
    else if (k == "--rsu-id")
      rsu_id = std::strtoull(v.c_str(), nullptr, 10);
    else if (k == "--flood")
      flood = std::atoi(v.c_str());
    else if (k == "--go-dir")
      go_dir = v;
    else
      usage("unknown option");
  }
  if (topic.empty() || rsu_id == 0 || go_dir.empty())
    usage("--topic, --rsu-id and --go-dir are required");

  const rsu::dds::Participant participant(pc);
  const rsu::dds::Topic t(participant, rsu::dds::ros_topic(topic), rsu_msgs_msg_dds__PeerAnnouncement__desc);
  // Reliable, so that this side does not drop its own samples; rsud's best-effort reader still matches.
  rsu::dds::Writer<Sample> writer(participant, t, {.history_depth = 64, .max_blocking_s = 1.0});
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (writer.matched_readers() == 0) {
    if (std::chrono::steady_clock::now() > deadline) {
      std::fprintf(stderr, "peer_publisher: no reader matched within 10 s\n");
      return 1;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  std::puts("matched");
  std::fflush(stdout);
  if (!wait_for_go(go_dir, "bad"))
    return 1;

  const std::vector<std::uint8_t> garbage = {0xde, 0xad, 0xbe, 0xef, 0xff, 0xff, 0xff, 0xff, 0xff, 0x01};
  for (int i = 0; i < 3; ++i)
    publish(writer, 77, "127.0.0.1", garbage);
  std::puts("published 3 garbage");
  for (std::uint32_t i = 1; i <= 3; ++i)
    publish(writer, 77, "127.0.0.1", announcement(5, i, "198.51.100.1"));
  std::puts("published 3 reply_to_mismatch");
  for (std::uint32_t i = 1; i <= 3; ++i)
    publish(writer, rsu_id, "127.0.0.1", announcement(6, i, "127.0.0.1"));
  std::puts("published 3 same_rsu_id");
  for (int i = 0; i < 3; ++i)
    publish(writer, 77, nullptr, announcement(7, 1, "127.0.0.1"));
  std::puts("published 3 no_sender");
  std::fflush(stdout);
  // rsud takes these before the flood can push them out of its reader's history (KEEP_LAST).
  if (!wait_for_go(go_dir, "flood"))
    return 1;
  for (int i = 0; i < flood; ++i)
    publish(writer, 78, "127.0.0.1", garbage);
  std::printf("published %d flood\n", flood);
  for (std::uint32_t i = 1; i <= 10; ++i) {
    publish(writer, 79, "127.0.0.1", announcement(9, i, "127.0.0.1"));
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  std::puts("published 10 valid");
  std::fflush(stdout);
  return 0;
}
