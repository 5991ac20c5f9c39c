// SPDX-License-Identifier: Apache-2.0
// RsuCore with an Ouster: the real low-bandwidth OS-1-128 capture (tests/data/real/ouster) through the
// decoder seam into the same packet order, frame assembly and background learning as a Velodyne's
// packets, every packet counted in the core's counters.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "core/rsu_core.h"
#include "core_counter.h"
#include "io/yaml_field.h"
#include "tests/lidar/real_data.h"

namespace rsu::core {
namespace {

using testing::counter;

RsuCoreConfig ouster_config(int learning_frames) {
  RsuCoreConfig c;
  c.rsu_id = 5;
  c.sensor_model = "os1-128";
  c.sensor_options.metadata_source = "OS-1-128_v2.3.0_1024x10.json";
  c.sensor_options.metadata_text =
      io::read_text_file(::rsu::lidar::test::real_data_path("ouster/" + c.sensor_options.metadata_source));
  c.mount = {0.0, 0.0, 2.0, 0.0, 0.0, 0.0};
  c.background.learning_frames = learning_frames;
  c.security.mode = v2i::SecurityMode::kInsecure;
  return c;
}

// Three Ouster frames (columns 0..1023 from the sensor's back) hold two whole rotations cut at the
// forward direction (rotation start 0): enough to learn a background of two frames, not of three. The
// capture's sensor counts time from its start (internal oscillator): stamped by arrival (the capture's
// record times, the recording host's clock), its packets serve.
TEST(OusterCore, RealCaptureLearnsTheBackgroundOnTheHostClock) {
  for (const int frames : {2, 3}) {
    SCOPED_TRACE(frames);
    RsuCoreConfig config = ouster_config(frames);
    config.time_source = TimeSource::kHostReceive;
    RsuCore core(config);
    EXPECT_EQ(core.lidar_decoder().model_name(), "os1-128");
    std::size_t payloads = 0;
    for (const lidar::UdpDatagram& d :
         ::rsu::lidar::test::read_capture("ouster/OS-1-128_v2.3.0_1024x10_lb_n3.pcap")) {
      ++payloads;
      core.on_lidar_packet(d.payload, d.time_ns);
    }
    EXPECT_EQ(core.background_ready(), frames == 2);
    EXPECT_EQ(core.lidar_stats().background_frames, 2U);
    EXPECT_EQ(core.lidar_decoder().packets_seen(), payloads);
    EXPECT_EQ(counter(core, "packet.accepted"), 192U);
    EXPECT_EQ(counter(core, "packet.imu"), 30U);
    EXPECT_EQ(counter(core, "packet.too_late"), 0U);
    EXPECT_EQ(counter(core, "packet.clock_offset"), 0U);
  }
}

// On the sensor's own time, the same packets are 1.65e9 s off the host's clock: refused by reason,
// with one notice saying so, never used silently.
TEST(OusterCore, UnsynchronisedOusterOnSensorTimeIsRefusedLoudly) {
  RsuCore core(ouster_config(2));  // time_source sensor (the default)
  for (const lidar::UdpDatagram& d :
       ::rsu::lidar::test::read_capture("ouster/OS-1-128_v2.3.0_1024x10_lb_n3.pcap")) {
    core.on_lidar_packet(d.payload, d.time_ns);
  }
  EXPECT_FALSE(core.background_ready());
  EXPECT_EQ(counter(core, "packet.clock_offset"), 192U);
  EXPECT_EQ(counter(core, "packet.imu"), 30U);
  const std::vector<std::string> notices = core.take_lidar_notices();
  ASSERT_FALSE(notices.empty());
  EXPECT_NE(notices.front().find("REFUSED (packet.clock_offset)"), std::string::npos) << notices.front();
}

}  // namespace
}  // namespace rsu::core
