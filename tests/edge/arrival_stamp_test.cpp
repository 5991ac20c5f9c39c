// SPDX-License-Identifier: Apache-2.0
// The kernel's arrival stamp of a datagram (edge/arrival_stamp.h), on loopback UDP sockets: in the control
// data of recvmsg once asked for, and for the datagram read last by ioctl; both between the host clock
// before the send and after the read, and the stamp, not the read, when the datagram waited unread.
#include <gtest/gtest.h>

#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <thread>

#include "edge/arrival_stamp.h"
#include "edge/host_clock.h"

namespace rsu::edge {
namespace arrival_stamp_test {

class LoopbackPair : public ::testing::Test {
 protected:
  void SetUp() override {
    receiver_ = socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    sender_ = socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    ASSERT_GE(receiver_, 0);
    ASSERT_GE(sender_, 0);
    address_.sin_family = AF_INET;
    address_.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    address_.sin_port = 0;
    ASSERT_EQ(bind(receiver_, reinterpret_cast<const sockaddr*>(&address_), sizeof address_), 0);
    socklen_t length = sizeof address_;
    ASSERT_EQ(getsockname(receiver_, reinterpret_cast<sockaddr*>(&address_), &length), 0);
  }
  void TearDown() override {
    close(receiver_);
    close(sender_);
  }
  void send_one() {
    const std::array<char, 3> bytes{'a', 'b', 'c'};
    ASSERT_EQ(sendto(sender_, bytes.data(), bytes.size(), 0, reinterpret_cast<const sockaddr*>(&address_),
                     sizeof address_),
              static_cast<ssize_t>(bytes.size()));
  }
  // Reads one datagram with its control data; returns the stamp found there.
  std::optional<TimeNs> read_with_control() {
    std::array<std::uint8_t, 16> buffer{};
    const StampedRead read = read_stamped(receiver_, buffer);
    EXPECT_EQ(read.bytes, 3);
    return read.arrival;
  }

  // A datagram that waits unread for 50 ms is stamped before the wait, not when `read` reads it. Linux
  // turns its stamping on for the whole host a moment after the first socket asks (a deferred switch,
  // net_enable_timestamp); a datagram that arrives before gets the time it is read. So the first few may
  // be stamped late, never all: up to 10 are sent, and the last one's stamp must be its arrival.
  template <class Read>
  void expect_stamped_on_arrival(Read read) {
    TimeNs before = 0, waited = 0;
    std::optional<TimeNs> stamp;
    for (int attempt = 0; attempt < 10; ++attempt) {
      before = host_now_ns();
      send_one();
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
      waited = host_now_ns();
      stamp = read();
      if (stamp && *stamp < waited)
        break;
    }
    ASSERT_TRUE(stamp.has_value());
    EXPECT_GE(*stamp, before);
    EXPECT_LT(*stamp, waited);
  }

  int receiver_ = -1;
  int sender_ = -1;
  sockaddr_in address_{};
};

TEST_F(LoopbackPair, StampInTheControlDataIsTheArrivalNotTheRead) {
  ASSERT_TRUE(request_arrival_stamps(receiver_));
  expect_stamped_on_arrival([this] { return read_with_control(); });
}

TEST_F(LoopbackPair, NoStampWithoutAsking) {
  send_one();
  EXPECT_FALSE(read_with_control().has_value());
}

TEST_F(LoopbackPair, LastArrivalTurnsStampsOnThenStampsTheLastRead) {
  EXPECT_FALSE(last_arrival(receiver_).has_value());  // none read yet: turns the stamps on
  expect_stamped_on_arrival([this]() -> std::optional<TimeNs> {
    std::array<char, 16> buffer{};
    EXPECT_EQ(recv(receiver_, buffer.data(), buffer.size(), 0), 3);
    return last_arrival(receiver_);
  });
}

TEST(ArrivalStamp, BadSocketIsRefused) {
  EXPECT_FALSE(request_arrival_stamps(-1));
  EXPECT_FALSE(last_arrival(-1).has_value());
  msghdr empty{};
  EXPECT_FALSE(arrival_in(empty).has_value());
  std::array<std::uint8_t, 4> buffer{};
  const StampedRead read = read_stamped(-1, buffer);
  EXPECT_EQ(read.bytes, -1);
  EXPECT_FALSE(read.arrival.has_value());
}

}  // namespace arrival_stamp_test
}  // namespace rsu::edge
