// SPDX-License-Identifier: Apache-2.0
// rsu-decode: turns a LiDAR capture into one PCD file per rotation, through the same decoder seam
// (lib/lidar/lidar_decoder.h) and rotation assembly (lib/lidar/frame_assembler.h) rsud uses.
#include <boost/program_options.hpp>

#include <cstdio>
#include <exception>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "common/angles.h"
#include "io/capture_file.h"
#include "io/pcd_io.h"
#include "io/velodyne_calibration.h"
#include "io/yaml_field.h"
#include "lidar/frame_assembler.h"
#include "lidar/lidar_decoder.h"
#include "lidar/velodyne_packet.h"
#include "tools/cli/renamed_options.h"
#include "tools/cli/version.h"

namespace {

namespace po = boost::program_options;
namespace fs = std::filesystem;

constexpr const char* kAbout =
    "rsu-decode: decodes a LiDAR capture into one PCD file per rotation.\n"
    "\n"
    "usage: rsu-decode CAPTURE --out DIR [--model M] [--calibration F] [--metadata F] [options]\n"
    "\n"
    "CAPTURE is a classic pcap (tcpdump -w, Wireshark saved as pcap, VeloView); a pcapng file is refused\n"
    "with the command that converts it. The datagrams to the sensor's ports are decoded (Velodyne: 2368\n"
    "data, 8308 position packets), everything else is counted. Each rotation (from the scan phase round\n"
    "to it again) is written to DIR/rotation_NNNN.pcd with the fields x y z intensity ring time: metres\n"
    "in the sensor frame (x forward, y left, z up), the reflectivity (0-255), the laser's index in the\n"
    "packet's channel order, and nanoseconds since the rotation's first point. The first and last\n"
    "rotations of a capture are usually partial: they are written too, and marked so in the listing.\n"
    "Without --model the model is read from the first data packet's factory byte (Velodyne).\n"
    "\n"
    "options";

// The Velodyne model a data packet's factory byte names; empty if none of ours.
std::string model_of_product(std::uint8_t product) {
  switch (product) {
    case 0x21:
      return "hdl32e";
    case 0x22:
      return "vlp16";
    case 0x28:
      return "vlp32c";
    default:
      return {};
  }
}

std::string guess_model(const std::string& capture_path, std::uint16_t port) {
  rsu::io::CaptureFile capture(capture_path);
  rsu::lidar::UdpDatagram d;
  while (capture.next(d)) {
    if (d.dst.port == port && d.payload.size() == rsu::lidar::kPacketBytes) {
      const std::string model = model_of_product(d.payload[rsu::lidar::kProductIdOffset]);
      if (model.empty()) {
        throw std::runtime_error(
            "the first data packet's factory byte names no model rsu-decode knows: give --model");
      }
      std::cout << "model " << model << " (from the first data packet's factory byte)\n";
      return model;
    }
  }
  throw std::runtime_error("no Velodyne data packet on port " + std::to_string(port) +
                           ": give --model (and --metadata for an Ouster)");
}

struct Options {
  std::string capture;
  std::string out;
  std::string model;
  std::string calibration;
  std::string metadata;
  rsu::lidar::ReturnSelection returns = rsu::lidar::ReturnSelection::both;
  double scan_phase_deg = 0.0;
  std::uint16_t port = 0;
};

int decode(const Options& o) {
  rsu::lidar::LidarDecoderOptions sensor;
  sensor.returns = o.returns;
  sensor.rotation_start_azimuth_deg = o.scan_phase_deg;
  const std::string model = o.model.empty()
                                ? guess_model(o.capture, o.port != 0 ? o.port : rsu::lidar::kVelodyneDataPort)
                                : o.model;
  if (!o.calibration.empty()) {
    const auto base = rsu::lidar::sensor_model_by_name(model);
    if (!base)
      throw std::runtime_error("--calibration: the " + model + " takes no Velodyne calibration file");
    sensor.calibrated_model =
        rsu::io::apply_velodyne_calibration(*base, rsu::io::read_text_file(o.calibration), o.calibration);
  }
  if (!o.metadata.empty()) {
    sensor.metadata_text = rsu::io::read_text_file(o.metadata);
    sensor.metadata_source = o.metadata;
  }
  const std::unique_ptr<rsu::lidar::LidarDecoder> decoder = rsu::lidar::make_lidar_decoder(model, sensor);
  const rsu::lidar::SensorPorts ports = decoder->default_ports();
  const std::uint16_t data_port = o.port != 0 ? o.port : ports.data;

  rsu::lidar::FrameAssemblerConfig assembly;
  assembly.emit_partial_frames = true;  // a capture's first and last rotations are listed too
  assembly.cut_azimuth_deg = rsu::rad_to_deg(decoder->geometry().rotation_start_azimuth_rad);
  assembly.rotation_hz = decoder->geometry().rotation_hz;
  rsu::lidar::FrameAssembler assembler(assembly);

  fs::create_directories(o.out);
  int written = 0;
  auto write = [&](std::vector<rsu::lidar::LidarFrame>&& frames, bool at_end) {
    for (std::size_t i = 0; i < frames.size(); ++i) {
      const rsu::lidar::LidarFrame& frame = frames[i];
      char name[32];
      std::snprintf(name, sizeof name, "rotation_%04d.pcd", written);
      rsu::io::write_rotation_pcd((fs::path(o.out) / name).string(), frame.points, frame.start_ns);
      // Whole: not the first rotation, and not closed by the end of the capture.
      const bool partial = written == 0 || at_end;
      std::printf("%s  %7zu points  %7.2f ms%s\n", name, frame.points.size(),
                  static_cast<double>(frame.end_ns - frame.start_ns) * 1e-6, partial ? "  (partial)" : "");
      ++written;
    }
  };

  rsu::io::CaptureFile capture(o.capture);
  rsu::lidar::UdpDatagram d;
  std::vector<rsu::lidar::LidarPoint> points;
  std::uint64_t other = 0;
  while (capture.next(d)) {
    if (d.dst.port != data_port && (ports.auxiliary == 0 || d.dst.port != ports.auxiliary)) {
      ++other;
      continue;
    }
    points.clear();
    if (decoder->decode(d.payload, d.time_ns, points).is_data()) {
      assembler.set_rotation_hz(decoder->geometry().rotation_hz);
      write(assembler.add(points), false);
    }
  }
  write(assembler.flush(), true);
  for (const std::string& notice : decoder->take_notices())
    std::cout << "note: " << notice << "\n";

  std::cout << written << " rotations written to " << o.out << "; " << capture.records() << " records: ";
  std::string counts;
  for (const auto& [name, value] : decoder->counters()) {
    if (value != 0 && !name.starts_with("note."))
      counts += (counts.empty() ? "" : ", ") + name + " " + std::to_string(value);
  }
  const rsu::lidar::PcapSkipped skipped = capture.skipped();
  std::cout << (counts.empty() ? "no packet of the sensor" : counts) << "; " << other
            << " datagrams to other ports, "
            << skipped.not_ipv4 + skipped.not_udp + skipped.fragmented + skipped.malformed
            << " records not UDP or unusable\n";
  if (capture.error() != rsu::lidar::PcapError::none) {
    std::cerr << "rsu-decode: " << o.capture << " ends where it stops being readable ("
              << rsu::lidar::to_string(capture.error()) << "): a capture cut off mid-record\n";
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (rsu::tools::cli::print_version_if_asked(argc, argv, "rsu-decode"))
    return 0;
  rsu::tools::cli::accept_renamed_options(argc, argv, {{"scan-phase", "scan-phase-deg"}}, "rsu-decode");
  Options o;
  std::string returns = "both";
  po::options_description visible(kAbout);
  visible.add_options()("help,h", "show this help and exit")("version", rsu::tools::cli::kVersionHelp)(
      "out,o", po::value<std::string>(&o.out), "folder for the rotation_NNNN.pcd files (created)")(
      "model,m", po::value<std::string>(&o.model),
      "the sensor: vlp16, vlp32c, hdl32e (default: from the packets), or an Ouster (os1-128, ..., with "
      "--metadata)")("calibration", po::value<std::string>(&o.calibration),
                     "Velodyne calibration YAML (as the ROS velodyne and nebula drivers read it)")(
      "metadata", po::value<std::string>(&o.metadata), "the sensor's metadata file (Ouster JSON)")(
      "returns", po::value<std::string>(&returns),
      "of a dual-return sensor: both (default), strongest, last")(
      "scan-phase-deg", po::value<double>(&o.scan_phase_deg),
      "azimuth (deg, clockwise from +x) where a rotation starts")(
      "port", po::value<std::uint16_t>(&o.port), "the sensor's data port (default: the sensor's own)");
  po::options_description hidden;
  hidden.add_options()("capture", po::value<std::string>(&o.capture));
  po::options_description all;
  all.add(visible).add(hidden);
  po::positional_options_description positional;
  positional.add("capture", 1);
  po::variables_map vm;
  try {
    po::store(po::command_line_parser(argc, argv).options(all).positional(positional).run(), vm);
    po::notify(vm);
  } catch (const std::exception& e) {
    std::cerr << "rsu-decode: " << e.what() << "\n\n" << visible;
    return 2;
  }
  if (vm.count("help")) {
    std::cout << visible;
    return 0;
  }
  const auto selection = rsu::lidar::return_selection_by_name(returns);
  if (o.capture.empty() || o.out.empty() || !selection || o.scan_phase_deg < 0 || o.scan_phase_deg >= 360) {
    std::cerr << "rsu-decode: "
              << (o.capture.empty() ? "a CAPTURE is required"
                  : o.out.empty()   ? "--out DIR is required"
                  : !selection      ? "--returns must be both, strongest or last"
                                    : "--scan-phase-deg must be within [0, 360)")
              << "\n\n"
              << visible;
    return 2;
  }
  o.returns = *selection;
  try {
    return decode(o);
  } catch (const std::exception& e) {
    std::cerr << "rsu-decode: " << e.what() << "\n";
    return 1;
  }
}
