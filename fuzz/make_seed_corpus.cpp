// SPDX-License-Identifier: Apache-2.0
// Writes the seed corpora of the fuzz harnesses into <dir>/<harness>/ (fuzz/corpus/ in the repository):
// valid V2I datagrams signed with fuzz_keys.h's keys (plus one unsigned), valid VLP-16 and VLP-32C
// packets from the encoder,
// a small capture and a small PCD, and packets of the real Ouster captures (tests/data/real/ouster) in
// ouster_packet_fuzzer's framing. The configuration and scenario seeds are the shipped files
// (deploy/rsud.yaml, scenarios/*.yaml) and the Ouster metadata seeds the real metadata files, copied by
// hand; the Velodyne seeds also hold packets of the real Velodyne captures (tests/data/real), the pcap
// seeds the first records of two of them, and the calibration seeds nebula's factory files. Usage:
// fuzz_seed_corpus <dir>.
#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <span>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include "common/time.h"
#include "fuzz_keys.h"
#include "io/pcd_io.h"
#include "lidar/firing_schedule.h"
#include "lidar/pcap.h"
#include "lidar/velodyne_packet.h"
#include "v2i/message_signer.h"
#include "v2i/wire_codec.h"

namespace {

namespace fs = std::filesystem;
using Bytes = std::vector<std::uint8_t>;

// Matches the harnesses' receive time (1'718'000'000 s) so that the seeds pass validation.
constexpr rsu::TimeNs kNow = 1'718'000'000LL * rsu::kNsPerSecond;

void write_file(const fs::path& path, std::span<const std::uint8_t> bytes) {
  fs::create_directories(path.parent_path());
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

void put_u16(Bytes& out, std::uint32_t v) {
  out.push_back(static_cast<std::uint8_t>(v & 0xFF));
  out.push_back(static_cast<std::uint8_t>((v >> 8) & 0xFF));
}

rsu::v2i::VehicleAnnouncement announcement(std::uint64_t id, std::uint32_t sequence, rsu::TimeNs t) {
  rsu::v2i::VehicleAnnouncement a;
  a.vehicle_id = id;
  a.sequence = sequence;
  a.generation_time = t;
  a.size = {4.89, 1.92, 1.70};
  a.reference_offset = {-1.35, 0.0};
  a.pose = {12.5, -3.25, 0.4};
  a.pose_covariance << 0.04, 0.01, 0.0, 0.01, 0.05, 0.0, 0.0, 0.0, 0.001;
  a.speed_mps = 8.5;
  a.yaw_rate_rps = 0.02;
  a.reply_to = {"192.0.2.17", 47001};
  return a;
}

void write_v2i(const fs::path& dir) {
  rsu::v2i::MessageSigner vehicle(rsu::fuzz::fuzz_vehicle_key());
  rsu::v2i::MessageSigner rsu_signer(rsu::fuzz::fuzz_rsu_key());
  write_file(dir / "announcement", vehicle.encode(announcement(7, 1, kNow), kNow));
  write_file(dir / "announcement_unsigned", rsu::v2i::encode_v2i_message(announcement(7, 1, kNow)));
  rsu::v2i::VehicleAnnouncement minimal = announcement(8, 2, kNow);
  minimal.speed_mps.reset();
  minimal.yaw_rate_rps.reset();
  minimal.reply_to = {"2001:db8::17", 47003};
  write_file(dir / "announcement_minimal", vehicle.encode(minimal, kNow));

  rsu::v2i::Correction c;
  c.rsu_id = 3;
  c.vehicle_id = 7;
  c.sequence = 4;
  c.sweep_time = kNow;
  c.pose = {12.1, -3.0, 0.41};
  c.pose_covariance = Eigen::Matrix3d::Identity() * 0.01;
  c.quality = {.points_used = 240,
               .faces_seen = 2,
               .range_m = 13.0,
               .yaw_resolution = rsu::v2i::YawResolution::kGeometry,
               .confidence = 0.9};
  c.announcement_sequence = 1;
  write_file(dir / "correction", rsu_signer.encode(c, kNow));

  rsu::v2i::RsuAdvertisement ad;
  ad.rsu_id = 3;
  ad.lidar_pose = {0.0, 0.0, 2.5, 0.0, 0.0, 0.3};
  ad.coverage_radius_m = 50.0;
  ad.correction_port = 4500;
  ad.announcement_port = 4500;
  write_file(dir / "advertisement", rsu_signer.encode(ad, kNow));

  rsu::v2i::AnnouncementRefusal refusal;
  refusal.rsu_id = 3;
  refusal.vehicle_id = 7;
  refusal.announcement_sequence = 1;
  refusal.reason = rsu::v2i::RefusalReason::kReplyToMismatch;
  refusal.detail = "port";
  write_file(dir / "refusal", rsu_signer.encode(refusal, kNow));

  rsu::v2i::FixWithheld withheld;
  withheld.rsu_id = 3;
  withheld.vehicle_id = 7;
  withheld.announcement_sequence = 1;
  withheld.sweep_time = kNow;
  withheld.reason = rsu::v2i::FixWithheldReason::kPositionUnbounded;
  withheld.position_sigma_m = 0.73;
  withheld.max_position_sigma_m = 0.5;
  withheld.packets_lost_nearby = true;
  write_file(dir / "fix_withheld", rsu_signer.encode(withheld, kNow));
}

// rsu_datagram framing: { u8 source, u16 ms since the previous, u16 length, bytes }.
void add_record(Bytes& out, std::uint8_t source, std::uint32_t dt_ms, const Bytes& datagram) {
  out.push_back(source);
  put_u16(out, dt_ms);
  put_u16(out, static_cast<std::uint32_t>(datagram.size()));
  out.insert(out.end(), datagram.begin(), datagram.end());
}

void write_rsu(const fs::path& dir) {
  Bytes one;
  rsu::v2i::MessageSigner first(rsu::fuzz::fuzz_vehicle_key());
  add_record(one, 0, 0, first.encode(announcement(7, 1, kNow), kNow));
  write_file(dir / "one_announcement", one);

  // Two vehicles at 10 Hz (signed by one key), a repeated sequence, a replayed datagram, the same
  // datagram relayed as by a peer (selector bit 7), an unsigned one, then silence long enough to expire.
  Bytes stream;
  rsu::v2i::MessageSigner signer(rsu::fuzz::fuzz_vehicle_key());
  Bytes last;
  for (std::uint32_t k = 0; k < 5; ++k) {
    const rsu::TimeNs t = kNow + static_cast<rsu::TimeNs>(k) * 100 * rsu::kNsPerMs;
    add_record(stream, 0, k == 0 ? 0 : 50, signer.encode(announcement(7, k + 1, t), t));
    last = signer.encode(announcement(9, k + 1, t + 50 * rsu::kNsPerMs), t + 50 * rsu::kNsPerMs);
    add_record(stream, 0, 50, last);
  }
  const rsu::TimeNs t5 = kNow + 450 * rsu::kNsPerMs;
  add_record(stream, 0, 0, signer.encode(announcement(9, 5, t5), t5));
  add_record(stream, 0, 0, last);     // replayed
  add_record(stream, 0x80, 0, last);  // relayed by a peer as well
  add_record(stream, 0, 0, rsu::v2i::encode_v2i_message(announcement(9, 6, t5)));  // unsigned
  const rsu::TimeNs t6 = kNow + 3450 * rsu::kNsPerMs;
  add_record(stream, 1, 3000, signer.encode(announcement(7, 6, t6), t6));
  write_file(dir / "two_vehicles", stream);
}

// Packets of a spinning sensor with every range a smooth function of the firing, as a scene would give.
std::vector<Bytes> packets(const rsu::lidar::SensorModel& model, rsu::TimeNs t0, int count,
                           std::int64_t first) {
  const rsu::lidar::FiringSchedule schedule(model, t0);
  std::vector<Bytes> out;
  for (int k = 0; k < count; ++k) {
    rsu::lidar::PacketReturns r;
    r.blocks = schedule.packet(first + k);
    for (const rsu::lidar::Firing& f : schedule.firings(r.blocks)) {
      const auto b = static_cast<std::size_t>(f.block);
      const auto c = static_cast<std::size_t>(f.channel);
      r.distance_raw[b][c] =
          (c % 7 == 3) ? 0 : rsu::lidar::quantize_distance(model, 5.0 + 0.5 * static_cast<double>(c));
      r.reflectivity[b][c] = static_cast<std::uint8_t>(10 * c);
    }
    Bytes bytes(rsu::lidar::kPacketBytes);
    rsu::lidar::encode_packet(
        model, r, std::span<std::uint8_t, rsu::lidar::kPacketBytes>(bytes.data(), rsu::lidar::kPacketBytes));
    out.push_back(std::move(bytes));
  }
  return out;
}

void write_velodyne(const fs::path& dir) {
  struct Case {
    const char* name;
    rsu::lidar::SensorModel model;
    std::uint8_t flags;
    std::uint32_t step_us;
    int count;
  };
  // Packet periods: VLP-16 1327 us, VLP-32C 664 us. The VLP-16 stream crosses its first frame cut.
  // Flags as velodyne_packet_fuzzer.cpp reads them (bits 0-1 model, bit 2 partial frames).
  const Case cases[] = {{"vlp16_packets", rsu::lidar::make_vlp16(), 0, 1327, 4},
                        {"vlp32c_packets", rsu::lidar::make_vlp32c(), 1, 664, 4},
                        {"vlp16_partial_frames", rsu::lidar::make_vlp16(), 4, 1327, 3}};
  for (const Case& c : cases) {
    Bytes input{c.flags};
    put_u16(input, c.step_us);
    put_u16(input, 0);  // 1206-byte payloads
    for (const Bytes& p : packets(c.model, kNow, c.count, 0))
      input.insert(input.end(), p.begin(), p.end());
    write_file(dir / c.name, input);
  }
}

void write_pcap(const fs::path& dir) {
  Bytes file = rsu::lidar::pcap_global_header();
  const rsu::lidar::UdpEndpoint sensor{rsu::lidar::ipv4_address(192, 168, 1, 201), 2368};
  const rsu::lidar::UdpEndpoint host{rsu::lidar::ipv4_address(192, 168, 1, 100),
                                     rsu::lidar::kVelodyneDataPort};
  rsu::TimeNs t = kNow;
  for (const Bytes& p : packets(rsu::lidar::make_vlp16(), kNow, 2, 0)) {
    rsu::lidar::append_udp_record(file, t, sensor, host, p);
    t += 1327 * rsu::kNsPerUs;
  }
  write_file(dir / "two_vlp16_packets.pcap", file);
  const Bytes small{1, 2, 3, 4};
  Bytes tiny = rsu::lidar::pcap_global_header();
  rsu::lidar::append_udp_record(tiny, kNow, sensor, host, small);
  write_file(dir / "small_datagram.pcap", tiny);
}

void write_pcd(const fs::path& dir) {
  fs::create_directories(dir);
  std::vector<rsu::lidar::LidarPoint> points;
  for (int i = 0; i < 6; ++i) {
    rsu::lidar::LidarPoint p;
    p.x = 1.0F + static_cast<float>(i);
    p.y = -0.5F * static_cast<float>(i);
    p.z = 0.25F;
    p.intensity = static_cast<float>(10 * i);
    p.ring = static_cast<std::uint16_t>(i);
    p.azimuth_rad = 0.1F * static_cast<float>(i);
    p.time_ns = kNow + i * rsu::kNsPerUs;
    points.push_back(p);
  }
  rsu::io::write_pcd((dir / "six_points.pcd").string(), points);
  // An ASCII PCD with only x y z, as other tools write them.
  const std::string ascii =
      "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\n"
      "COUNT 1 1 1\nWIDTH 3\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 3\nDATA ascii\n1 2 3\n4 5 6\n7 8 "
      "nan\n";
  write_file(dir / "ascii_xyz.pcd",
             std::span(reinterpret_cast<const std::uint8_t*>(ascii.data()), ascii.size()));
}

// A real Ouster packet cut down to its first `columns` columns of `pixels` pixels: the same bytes, in a
// smaller format of the same profile (header and footer of `edge` bytes each, `tail` bytes after each
// column's pixels: the LEGACY status).
Bytes cut_packet(const Bytes& packet, std::size_t edge, std::size_t column_header, std::size_t pixel,
                 std::size_t tail, std::size_t pixels_from, std::size_t pixels, std::size_t columns) {
  const std::size_t column_from = column_header + pixels_from * pixel + tail;
  Bytes out(packet.begin(), packet.begin() + static_cast<std::ptrdiff_t>(edge));
  for (std::size_t c = 0; c < columns; ++c) {
    const auto col = packet.begin() + static_cast<std::ptrdiff_t>(edge + c * column_from);
    out.insert(out.end(), col, col + static_cast<std::ptrdiff_t>(column_header + pixels * pixel));
    const auto status = col + static_cast<std::ptrdiff_t>(column_from - tail);
    out.insert(out.end(), status, status + static_cast<std::ptrdiff_t>(tail));
  }
  out.insert(out.end(), packet.end() - static_cast<std::ptrdiff_t>(edge), packet.end());
  return out;
}

Bytes real_file(const std::string& name) {
  std::ifstream in(fs::path(RSU_SOURCE_DIR) / "tests/data/real" / name, std::ios::binary);
  if (!in)
    throw std::runtime_error(name + ": cannot open");
  return Bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// The payloads of a real Velodyne capture sent to `port`, from the n-th on, `count` of them.
std::vector<Bytes> real_payloads(const std::string& capture, std::uint16_t port, std::size_t from,
                                 std::size_t count) {
  std::vector<Bytes> out;
  for (const rsu::lidar::UdpDatagram& d : rsu::lidar::parse_pcap(real_file(capture)).datagrams) {
    if (d.dst.port != port)
      continue;
    if (from > 0) {
      --from;
      continue;
    }
    if (out.size() == count)
      break;
    out.push_back(d.payload);
  }
  return out;
}

// velodyne_packet_fuzzer's framing: flags (bits 0-1 model, 3-4 returns), u16 step (us), u16 size code.
void write_velodyne_real(const fs::path& dir) {
  const auto seed = [&](const char* name, std::uint8_t flags, std::uint32_t step_us, std::uint32_t size_code,
                        const std::vector<Bytes>& payloads) {
    Bytes input{flags};
    put_u16(input, step_us);
    put_u16(input, size_code);
    for (const Bytes& p : payloads)
      input.insert(input.end(), p.begin(), p.end());
    write_file(dir / name, input);
  };
  seed("vlp16_dual_real", 0, 664, 0, real_payloads("nebula_vlp16_dual_4scans.pcap", 2368, 0, 6));
  seed("vlp16_dual_strongest_real", 1 << 3, 664, 0,
       real_payloads("nebula_vlp16_dual_4scans.pcap", 2368, 6, 4));
  seed("vlp32c_field_of_view_gap_real", 1, 664, 0, real_payloads("nebula_vlp32c_5scans.pcap", 2368, 74, 4));
  seed("hdl32e_real", 2, 553, 0, real_payloads("rlu_hdl32e_driving_876pkts.pcap", 2368, 0, 6));
  seed("hdl32e_position_gprmc_real", 2, 5000, 1,
       real_payloads("rlu_hdl32e_driving_876pkts.pcap", 8308, 0, 3));
  seed("vlp16_early_firmware_real", 0, 1327, 0, real_payloads("rlu_vlp16_earlyfw_84pkts.pcap", 2368, 0, 4));
}

// The first records of two real captures, as they are on disk (global header included).
void write_pcap_real(const fs::path& dir) {
  const auto first_records = [](const std::string& capture, std::size_t records) {
    const Bytes file = real_file(capture);
    std::size_t at = 24;
    for (std::size_t i = 0; i < records && at + 16 <= file.size(); ++i) {
      const std::size_t captured =
          file[at + 8] | (file[at + 9] << 8) | (file[at + 10] << 16) | (std::size_t{file[at + 11]} << 24);
      at += 16 + captured;
    }
    return Bytes(file.begin(), file.begin() + static_cast<std::ptrdiff_t>(std::min(at, file.size())));
  };
  // 12 records: data packets and position packets whose IPv4 length is wrong (early VLP-16 firmware).
  write_file(dir / "vlp16_early_firmware_real.pcap", first_records("rlu_vlp16_earlyfw_84pkts.pcap", 12));
  write_file(dir / "vlp32c_real.pcap", first_records("nebula_vlp32c_5scans.pcap", 6));
}

// velodyne_calibration_fuzzer's framing: the model byte (0 VLP-16, 1 VLP-32C), then the file.
void write_calibration(const fs::path& dir) {
  for (const auto& [name, model, file] : {std::tuple{"vlp16_factory", 0, "nebula_calibration/VLP16.yaml"},
                                          std::tuple{"vlp32c_factory", 1, "nebula_calibration/VLP32.yaml"}}) {
    Bytes seed{static_cast<std::uint8_t>(model)};
    const Bytes text = real_file(file);
    seed.insert(seed.end(), text.begin(), text.end());
    write_file(dir / name, seed);
  }
}

// Ouster: the format byte of ouster_packet_fuzzer.cpp, then u16-length records of packets from the
// real captures (as recorded, or cut down to the harness's smaller formats 2 and 3).
void write_ouster(const fs::path& dir) {
  const auto datagrams = [](const char* capture) {
    std::ifstream in(fs::path(RSU_SOURCE_DIR) / "tests/data/real/ouster" / capture, std::ios::binary);
    const Bytes bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    return rsu::lidar::parse_pcap(bytes).datagrams;
  };
  const auto seed = [&](const char* name, std::uint8_t format, const std::vector<Bytes>& packets) {
    Bytes out{format};
    for (const Bytes& p : packets) {
      put_u16(out, static_cast<std::uint32_t>(p.size()));
      out.insert(out.end(), p.begin(), p.end());
    }
    write_file(dir / name, out);
  };
  // The n-th datagram of a capture sent to `port` (7502 lidar, 7503 IMU).
  const auto packet = [&](const char* capture, std::uint16_t port, std::size_t n) {
    for (const rsu::lidar::UdpDatagram& d : datagrams(capture)) {
      if (d.dst.port == port && n-- == 0) {
        return d.payload;
      }
    }
    throw std::runtime_error(std::string(capture) + ": too few packets");
  };
  const char* legacy = "OS-1-32-G_v2.1.1_1024x10.pcap";
  const char* rng15 = "OS-1-128_v2.3.0_1024x10_lb_n3.pcap";
  const char* rng19 = "OS-2-128-U1_v2.3.0_1024x10.pcap";
  seed("os1_32_legacy", 0, {packet(legacy, 7502, 0), packet(legacy, 7502, 1)});
  seed("os1_128_rng15_and_imu", 1, {packet(rng15, 7502, 0), packet(rng15, 7503, 0)});
  seed("os2_128_rng19_cut_to_16_beams", 2, {cut_packet(packet(rng19, 7502, 0), 32, 12, 12, 0, 128, 16, 16)});
  seed("os1_32_legacy_cut_to_16_beams", 3, {cut_packet(packet(legacy, 7502, 0), 0, 16, 12, 4, 32, 16, 8)});
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: fuzz_seed_corpus <corpus dir>\n";
    return 2;
  }
  const fs::path root = argv[1];
  write_v2i(root / "v2i_datagram");
  write_rsu(root / "rsu_datagram");
  write_velodyne(root / "velodyne_packet");
  write_velodyne_real(root / "velodyne_packet");
  write_pcap(root / "pcap");
  write_pcap_real(root / "pcap");
  write_calibration(root / "velodyne_calibration");
  write_pcd(root / "pcd");
  write_ouster(root / "ouster_packet");
  std::cout << "seed corpora written to " << root << "\n";
  return 0;
}
