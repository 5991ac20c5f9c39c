// SPDX-License-Identifier: Apache-2.0
// An Ouster sensor's metadata JSON (OS0 / OS1 / OS2), as the sensor's HTTP API and the Ouster SDK
// write it next to a recording: the beam geometry, the frame and packet format and the UDP profile
// the lidar packets are decoded with. The caller reads the file and passes its text in.
//
// Two layouts exist, both read here:
//   flat (firmware before 2.4, SDK before 0.10; "legacy" in the SDK): beam_altitude_angles,
//     beam_azimuth_angles, lidar_origin_to_beam_origin_mm, lidar_to_sensor_transform, lidar_mode,
//     prod_line, prod_sn, ... at the top level and the packet format under data_format;
//   nested (SDK 0.10 and later): the same fields under beam_intrinsics, lidar_intrinsics,
//     config_params, sensor_info and lidar_data_format.
// Fields this decoder does not need are ignored. Fields that older firmware does not write get the
// SDK's documented defaults, listed in Metadata::defaults_used: lidar_origin_to_beam_origin_mm by
// product line, lidar_to_sensor_transform, the data format from lidar_mode (firmware 1.x), the
// LEGACY profile and ports 7502 / 7503.
//
// JSON is read with the project's YAML reader (JSON is YAML flow syntax), so every error names the
// file, the line and the field:  os.json:12: beam_intrinsics.beam_altitude_angles[3]: expected a number
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

namespace rsu::lidar::ouster {

// The lidar packet profiles decoded here (the metadata's udp_profile_lidar). Dual-return and
// FuSa/zone profiles are refused with an error naming them.
enum class UdpProfile {
  legacy,                  // LEGACY: 16-byte column header, 12-byte pixels, 4-byte column status
  rng19_rfl8_sig16_nir16,  // RNG19_RFL8_SIG16_NIR16: 32-byte packet header/footer, 12-byte pixels
  rng15_rfl8_nir8,         // RNG15_RFL8_NIR8 ("low bandwidth"): 4-byte pixels, range in 8 mm units
};
std::string_view to_string(UdpProfile profile);  // the metadata's spelling, e.g. "RNG15_RFL8_NIR8"
std::optional<UdpProfile> udp_profile_from_string(std::string_view text);

enum class MetadataLayout { flat, nested };

constexpr std::uint16_t kDefaultLidarPort = 7502;
constexpr std::uint16_t kDefaultImuPort = 7503;

struct Metadata {
  MetadataLayout layout = MetadataLayout::flat;
  std::string prod_line;                           // "OS-1-128"; empty when the file does not say
  std::string serial;                              // prod_sn as written
  std::optional<std::uint64_t> serial_number;      // prod_sn when it is a number
  std::optional<std::uint32_t> initialization_id;  // sensor_info.initialization_id (firmware 2.2+)
  std::string firmware;                            // build_rev, e.g. "v2.3.0"

  std::string lidar_mode;     // "1024x10"
  int columns_per_frame = 0;  // 512, 1024, 2048 or 4096 measurement ids per rotation
  int frequency_hz = 0;       // rotations per second: 10, 20 (5 in 4096x5)
  int columns_per_packet = 0;
  int pixels_per_column = 0;    // beams: 16, 32, 64 or 128
  int column_window_first = 0;  // measurement ids the sensor sends, inclusive; wraps past the last
  int column_window_last = 0;   // column when first > last (an azimuth window across 0)
  UdpProfile profile = UdpProfile::legacy;

  // Per pixel row, top beam first (the packet's order): elevation above the horizontal and the
  // beam's azimuth offset from the column's encoder angle, degrees, as the sensor reports them.
  std::vector<double> beam_altitude_deg;
  std::vector<double> beam_azimuth_deg;
  // Beam origin relative to the lidar origin, mm: x along the encoder direction (the metadata's
  // lidar_origin_to_beam_origin_mm, or beam_to_lidar_transform(0, 3)) and z (beam_to_lidar_transform(2, 3)).
  double beam_origin_x_mm = 0.0;
  double beam_origin_z_mm = 0.0;
  // Ouster's lidar frame (x towards the connector) to its sensor frame (x away from the connector,
  // y left, z up, origin on the base): rotation and translation, mm.
  Eigen::Matrix4d lidar_to_sensor = Eigen::Matrix4d::Identity();

  std::uint16_t udp_port_lidar = kDefaultLidarPort;
  std::uint16_t udp_port_imu = kDefaultImuPort;

  std::vector<std::string> defaults_used;  // fields the file lacked, with the default taken

  int columns_in_window() const;
  bool in_window(int measurement_id) const;
  // Our model name from the product line: "OS-1-32-G" -> "os1-32", "OS-0-128" -> "os0-128";
  // "ouster-<beams>" when the file names no product line.
  std::string model_name() const;
};

// Throws io::YamlError "<source>:<line>: <field>: <what>" for a file that is not JSON/YAML, lacks a
// required field, has a field of the wrong type or outside its range, beam tables whose length is not
// pixels_per_column, a lidar_mode other than 512x10, 512x20, 1024x10, 1024x20, 2048x10 or 4096x5, a
// data format that contradicts it, an unsupported profile, or a lidar_to_sensor_transform that is not
// a rigid transform.
Metadata parse_metadata(const std::string& text, const std::string& source_name);

}  // namespace rsu::lidar::ouster
