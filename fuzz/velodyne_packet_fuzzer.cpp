// SPDX-License-Identifier: Apache-2.0
// Fuzzes the Velodyne decoder (lib/lidar/velodyne_decoder.h, through the decoder seam
// lib/lidar/lidar_decoder.h) for the VLP-16, VLP-32C and HDL-32E in every return selection, and the
// frame assembly behind it (lib/lidar/frame_assembler.h): whatever arrives on ports 2368 / 8308 must be
// data, a position packet or refused with a counted reason, and the points it yields cut into
// rotations.
//
// Input: u8 flags (bits 0-1: model vlp16 / vlp32c / hdl32e / vlp16, bit 2: emit partial frames, bits
// 3-4: returns both / strongest / last / both), u16 LE receive-time step between packets in
// microseconds, u16 LE payload size (the low bit chooses 1206 or 512 bytes when the value is 0 or 1,
// otherwise the value itself, up to 2048), then payloads of that size (a shorter tail is fed as one
// more payload).
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <vector>

#include "common/time.h"
#include "fuzz_input.h"
#include "lidar/frame_assembler.h"
#include "lidar/lidar_decoder.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  rsu::fuzz::FuzzInput in(data, size);
  const std::uint8_t flags = in.u8();
  const rsu::TimeNs step_ns = static_cast<rsu::TimeNs>(in.u16()) * 1000;
  const std::uint16_t size_code = in.u16();
  const std::size_t payload_size = size_code <= 1 ? (size_code == 0 ? 1206 : 512) : (size_code % 2048) + 1;

  constexpr std::array<const char*, 4> kModels = {"vlp16", "vlp32c", "hdl32e", "vlp16"};
  constexpr std::array<rsu::lidar::ReturnSelection, 4> kReturns = {
      rsu::lidar::ReturnSelection::both, rsu::lidar::ReturnSelection::strongest,
      rsu::lidar::ReturnSelection::last, rsu::lidar::ReturnSelection::both};
  rsu::lidar::LidarDecoderOptions options;
  options.returns = kReturns[(flags >> 3) & 3];
  const auto decoder = rsu::lidar::make_lidar_decoder(kModels[flags & 3], options);
  rsu::lidar::FrameAssemblerConfig assembler_config;
  assembler_config.emit_partial_frames = (flags & 4) != 0;
  rsu::lidar::FrameAssembler assembler(assembler_config);

  // Receive times near a real date; the packet's own timestamp gives the hour's microseconds.
  rsu::TimeNs now = 1'718'000'000LL * rsu::kNsPerSecond;
  std::vector<rsu::lidar::LidarPoint> points;
  std::uint64_t fed = 0;
  while (!in.empty()) {
    points.clear();
    const rsu::lidar::PacketOutcome outcome = decoder->decode(in.take(payload_size), now, points);
    if (outcome.kind != rsu::lidar::PacketKind::data && !points.empty()) {
      std::abort();  // only data packets yield points
    }
    ++fed;
    assembler.set_rotation_hz(decoder->geometry().rotation_hz);
    (void)assembler.add(points);
    now += step_ns;
  }
  (void)assembler.flush();
  (void)decoder->take_notices();
  if (decoder->packets_seen() != fed) {
    std::abort();  // every payload is counted once, as data, position or with its reason
  }
  return 0;
}
