// Fuzzes the Velodyne packet decoder (lib/lidar/velodyne_packet.h) for the VLP-16 and the VLP-32C and
// the frame assembly behind it (lib/lidar/frame_assembler.h): whatever arrives on port 2368 must be
// accepted or rejected with a counted reason, and the points it yields cut into rotations.
//
// Input: u8 flags (bit 0: VLP-32C, bit 1: emit partial frames), u16 LE receive-time step between
// packets in microseconds, then 1206-byte packets (a shorter tail is fed as one more packet).
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <vector>

#include "common/time.h"
#include "fuzz_input.h"
#include "lidar/frame_assembler.h"
#include "lidar/velodyne_packet.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  rsu::fuzz::FuzzInput in(data, size);
  const std::uint8_t flags = in.u8();
  const rsu::TimeNs step_ns = static_cast<rsu::TimeNs>(in.u16()) * 1000;

  rsu::PacketDecoder decoder((flags & 1) != 0 ? rsu::make_vlp32c() : rsu::make_vlp16());
  rsu::FrameAssemblerConfig assembler_config;
  assembler_config.emit_partial_frames = (flags & 2) != 0;
  rsu::FrameAssembler assembler(assembler_config);

  // Receive times near a real date; the packet's own timestamp gives the hour's microseconds.
  rsu::TimeNs now = 1'718'000'000LL * rsu::kNsPerSecond;
  std::vector<rsu::LidarPoint> points;
  std::uint64_t fed = 0;
  while (!in.empty()) {
    points.clear();
    (void)rsu::to_string(decoder.decode(in.take(rsu::kPacketBytes), now, points));
    ++fed;
    (void)assembler.add(points);
    now += step_ns;
  }
  (void)assembler.flush();
  if (decoder.stats().packets() != fed) {
    std::abort();  // every packet is counted once, accepted or with its reason
  }
  return 0;
}
