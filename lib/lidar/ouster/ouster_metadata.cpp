// SPDX-License-Identifier: Apache-2.0
// Ouster metadata JSON (see ouster_metadata.h). Field names, layouts and defaults are those of the
// public Ouster SDK (ouster-sdk, BSD-3-Clause) and the sensor firmware user manuals.
#include "lidar/ouster/ouster_metadata.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <limits>

#include <Eigen/LU>  // determinant

#include "io/yaml_field.h"
#include "lidar/ouster/ouster_packet.h"

namespace rsu::lidar::ouster {
namespace {

using io::YamlField;

struct LidarMode {
  std::string_view name;
  int columns;
  int hz;
};
// The modes of the OS0/OS1/OS2 firmware user manuals (lidar_mode).
constexpr std::array<LidarMode, 6> kLidarModes{{{"512x10", 512, 10},
                                                {"512x20", 512, 20},
                                                {"1024x10", 1024, 10},
                                                {"1024x20", 1024, 20},
                                                {"2048x10", 2048, 10},
                                                {"4096x5", 4096, 5}}};

constexpr std::array<std::pair<UdpProfile, std::string_view>, 3> kProfileNames{{
    {UdpProfile::legacy, "LEGACY"},
    {UdpProfile::rng19_rfl8_sig16_nir16, "RNG19_RFL8_SIG16_NIR16"},
    {UdpProfile::rng15_rfl8_nir8, "RNG15_RFL8_NIR8"},
}};

// The SDK's defaults for files that predate a field: beam origin offset by product line (the
// first-generation OS1's 12.163 mm otherwise) and the lidar-to-sensor transform of OS1/OS2.
double default_beam_origin_mm(const std::string& prod_line) {
  if (prod_line.starts_with("OS-0-")) {
    return 27.67;
  }
  if (prod_line.starts_with("OS-1-")) {
    return 15.806;
  }
  if (prod_line.starts_with("OS-2-")) {
    return 13.762;
  }
  return 12.163;
}

Eigen::Matrix4d default_lidar_to_sensor() {
  Eigen::Matrix4d t = Eigen::Matrix4d::Identity();
  t(0, 0) = -1.0;
  t(1, 1) = -1.0;
  t(2, 3) = 36.18;
  return t;
}

// Where each field lives: the top level in the flat layout, a named section in the nested one.
class Sections {
 public:
  Sections(const YamlField& root, MetadataLayout layout) : root_(root), layout_(layout) {}

  std::optional<YamlField> find(const char* nested_section, const char* key) const {
    if (layout_ == MetadataLayout::flat) {
      return root_.has(key) ? std::optional(root_.child(key)) : std::nullopt;
    }
    if (!root_.has(nested_section)) {
      return std::nullopt;
    }
    const YamlField section = root_.child(nested_section);
    if (!section.is_map()) {
      section.fail("expected a mapping");
    }
    return section.has(key) ? std::optional(section.child(key)) : std::nullopt;
  }

  YamlField require(const char* nested_section, const char* key) const {
    if (auto f = find(nested_section, key)) {
      return *f;
    }
    if (layout_ == MetadataLayout::nested && root_.has(nested_section)) {
      root_.child(nested_section).fail(std::string("missing required field \"") + key + "\"");
    }
    root_.fail(
        std::string("missing required field \"") +
        (layout_ == MetadataLayout::flat ? std::string(key) : std::string(nested_section) + "." + key) +
        "\"");
  }

  // data_format (flat) or lidar_data_format (nested); nullopt for firmware 1.x files.
  std::optional<YamlField> data_format() const {
    const char* key = layout_ == MetadataLayout::flat ? "data_format" : "lidar_data_format";
    if (!root_.has(key)) {
      return std::nullopt;
    }
    const YamlField f = root_.child(key);
    if (!f.is_map()) {
      f.fail("expected a mapping");
    }
    return f;
  }

 private:
  const YamlField& root_;
  MetadataLayout layout_;
};

MetadataLayout detect_layout(const YamlField& root) {
  if (!root.is_map()) {
    root.fail("expected a JSON object (an Ouster metadata file)");
  }
  const bool nested = root.has("beam_intrinsics");
  const bool flat = root.has("beam_altitude_angles");
  if (nested && flat) {
    root.child("beam_altitude_angles")
        .fail("both the flat layout's beam tables and the nested layout's beam_intrinsics: which one?");
  }
  if (!nested && !flat) {
    root.fail(
        "missing required field \"beam_altitude_angles\" (flat layout) or \"beam_intrinsics\" (nested "
        "layout): not an Ouster metadata file?");
  }
  return nested ? MetadataLayout::nested : MetadataLayout::flat;
}

long long integer(const YamlField& f, long long lo, long long hi) {
  const double v = f.number();
  if (v != std::floor(v) || v < static_cast<double>(lo) || v > static_cast<double>(hi)) {
    f.fail("expected an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "], got " +
           std::to_string(v));
  }
  return static_cast<long long>(v);
}

int int_field(const YamlField& f, int lo, int hi) {
  return static_cast<int>(integer(f, lo, hi));
}

std::vector<double> numbers(const YamlField& f, std::size_t count, double limit) {
  const std::vector<YamlField> items = f.items();
  if (items.size() != count) {
    f.fail("expected " + std::to_string(count) + " numbers, got " + std::to_string(items.size()));
  }
  std::vector<double> out;
  out.reserve(count);
  for (const YamlField& item : items) {
    const double v = item.number();
    if (std::abs(v) > limit) {
      item.fail("expected a value within +-" + std::to_string(limit) + ", got " + std::to_string(v));
    }
    out.push_back(v);
  }
  return out;
}

Eigen::Matrix4d transform(const YamlField& f) {
  const std::vector<double> v = numbers(f, 16, 1e6);
  Eigen::Matrix4d t;
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) {
      t(r, c) = v[static_cast<std::size_t>(4 * r + c)];
    }
  }
  const Eigen::Matrix3d rot = t.topLeftCorner<3, 3>();
  const bool rigid = (rot.transpose() * rot - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() < 1e-3 &&
                     rot.determinant() > 0.0 && t.row(3).isApprox(Eigen::RowVector4d(0, 0, 0, 1));
  if (!rigid) {
    f.fail("expected a rigid transform (row-major 4x4: rotation, translation in mm, last row 0 0 0 1)");
  }
  return t;
}

void read_identity(const Sections& s, Metadata& m) {
  if (auto f = s.find("sensor_info", "prod_line")) {
    m.prod_line = f->text();
  }
  if (auto f = s.find("sensor_info", "prod_sn")) {
    m.serial = f->text();
    const bool digits = !m.serial.empty() && m.serial.size() <= 13 &&
                        std::all_of(m.serial.begin(), m.serial.end(), [](char c) { return std::isdigit(c); });
    if (digits && std::stoull(m.serial) < (1ULL << 40)) {
      m.serial_number = std::stoull(m.serial);  // the lidar packet header carries 40 bits of it
    }
  }
  if (auto f = s.find("sensor_info", "initialization_id")) {
    m.initialization_id = static_cast<std::uint32_t>(integer(*f, 0, (1 << 24) - 1));
  }
  if (auto f = s.find("sensor_info", "build_rev")) {
    m.firmware = f->text();
  }
}

void read_ports(const Sections& s, Metadata& m) {
  const auto port = [&](const char* key, std::uint16_t& out) {
    if (auto f = s.find("config_params", key)) {
      const int p = int_field(*f, 0, 65535);
      if (p != 0) {  // 0: the sensor was not sending when the file was written
        out = static_cast<std::uint16_t>(p);
        return;
      }
    }
    m.defaults_used.push_back(std::string(key) + " = " + std::to_string(out));
  };
  port("udp_port_lidar", m.udp_port_lidar);
  port("udp_port_imu", m.udp_port_imu);
}

const LidarMode& read_lidar_mode(const Sections& s, Metadata& m) {
  const YamlField f = s.require("config_params", "lidar_mode");
  m.lidar_mode = f.text();
  for (const LidarMode& mode : kLidarModes) {
    if (mode.name == m.lidar_mode) {
      m.columns_per_frame = mode.columns;
      m.frequency_hz = mode.hz;
      return mode;
    }
  }
  f.fail("unknown lidar_mode \"" + m.lidar_mode +
         "\" (expected 512x10, 512x20, 1024x10, 1024x20, 2048x10 or 4096x5)");
}

UdpProfile read_profile(const YamlField& f) {
  const std::string name = f.text();
  if (auto p = udp_profile_from_string(name)) {
    return *p;
  }
  f.fail("unsupported lidar profile \"" + name +
         "\" (decoded: LEGACY, RNG19_RFL8_SIG16_NIR16, RNG15_RFL8_NIR8)");
}

bool valid_beam_count(int n) {
  return n == 16 || n == 32 || n == 64 || n == 128;
}

// The packet format: from data_format, or (firmware 1.x, no data_format) from lidar_mode and the
// number of beams, as the SDK does.
void read_data_format(const Sections& s, Metadata& m) {
  const LidarMode& mode = read_lidar_mode(s, m);
  m.column_window_first = 0;
  m.column_window_last = mode.columns - 1;
  const std::optional<YamlField> df = s.data_format();
  if (!df) {
    const YamlField angles = s.require("beam_intrinsics", "beam_altitude_angles");
    m.pixels_per_column = static_cast<int>(angles.items().size());
    if (!valid_beam_count(m.pixels_per_column)) {
      angles.fail("expected 16, 32, 64 or 128 beams, got " + std::to_string(m.pixels_per_column));
    }
    m.columns_per_packet = 16;
    m.defaults_used.emplace_back("data_format: from lidar_mode, 16 columns per packet, every column, LEGACY");
    return;
  }
  const YamlField cpf = df->required("columns_per_frame");
  if (int_field(cpf, 1, 65535) != mode.columns) {
    cpf.fail("contradicts lidar_mode " + m.lidar_mode);
  }
  const YamlField cpp = df->required("columns_per_packet");
  m.columns_per_packet = int_field(cpp, 1, mode.columns);
  if (mode.columns % m.columns_per_packet != 0) {
    cpp.fail("must divide columns_per_frame " + std::to_string(mode.columns));
  }
  const YamlField ppc = df->required("pixels_per_column");
  m.pixels_per_column = int_field(ppc, 1, 1024);
  if (!valid_beam_count(m.pixels_per_column)) {
    ppc.fail("expected 16, 32, 64 or 128");
  }
  if (df->has("column_window")) {
    const YamlField w = df->child("column_window");
    const std::vector<YamlField> ends = w.items();
    if (ends.size() != 2) {
      w.fail("expected [first, last]");
    }
    m.column_window_first = int_field(ends[0], 0, mode.columns - 1);
    m.column_window_last = int_field(ends[1], 0, mode.columns - 1);
  }
  if (df->has("udp_profile_lidar")) {
    m.profile = read_profile(df->child("udp_profile_lidar"));
  } else {
    m.defaults_used.emplace_back("udp_profile_lidar = LEGACY");
  }
  if (packet_layout(m.profile, m.pixels_per_column, m.columns_per_packet).packet_bytes > kMaxUdpPayload) {
    cpp.fail("a lidar packet of this many columns exceeds the largest UDP datagram");
  }
}

void read_beams(const Sections& s, Metadata& m) {
  const auto rows = static_cast<std::size_t>(m.pixels_per_column);
  m.beam_altitude_deg = numbers(s.require("beam_intrinsics", "beam_altitude_angles"), rows, 90.0);
  m.beam_azimuth_deg = numbers(s.require("beam_intrinsics", "beam_azimuth_angles"), rows, 180.0);
  if (auto f = s.find("beam_intrinsics", "beam_to_lidar_transform")) {
    const Eigen::Matrix4d t = transform(*f);
    m.beam_origin_x_mm = t(0, 3);
    m.beam_origin_z_mm = t(2, 3);
  } else if (auto n = s.find("beam_intrinsics", "lidar_origin_to_beam_origin_mm")) {
    m.beam_origin_x_mm = n->number();
  } else {
    m.beam_origin_x_mm = default_beam_origin_mm(m.prod_line);
    m.defaults_used.push_back("lidar_origin_to_beam_origin_mm = " + std::to_string(m.beam_origin_x_mm));
  }
  if (std::abs(m.beam_origin_x_mm) > 1000.0 || std::abs(m.beam_origin_z_mm) > 1000.0) {
    s.require("beam_intrinsics", "beam_altitude_angles")
        .fail("beam origin more than 1 m from the lidar origin");
  }
  if (auto f = s.find("lidar_intrinsics", "lidar_to_sensor_transform")) {
    m.lidar_to_sensor = transform(*f);
  } else {
    m.lidar_to_sensor = default_lidar_to_sensor();
    m.defaults_used.emplace_back("lidar_to_sensor_transform = the OS1/OS2 default (z 36.18 mm)");
  }
}

}  // namespace

std::string_view to_string(UdpProfile profile) {
  for (const auto& [p, name] : kProfileNames) {
    if (p == profile) {
      return name;
    }
  }
  return "unknown";
}

std::optional<UdpProfile> udp_profile_from_string(std::string_view text) {
  for (const auto& [p, name] : kProfileNames) {
    if (name == text) {
      return p;
    }
  }
  return std::nullopt;
}

int Metadata::columns_in_window() const {
  return column_window_first <= column_window_last
             ? column_window_last - column_window_first + 1
             : columns_per_frame - column_window_first + column_window_last + 1;
}

bool Metadata::in_window(int measurement_id) const {
  if (measurement_id < 0 || measurement_id >= columns_per_frame) {
    return false;
  }
  return column_window_first <= column_window_last
             ? measurement_id >= column_window_first && measurement_id <= column_window_last
             : measurement_id >= column_window_first || measurement_id <= column_window_last;
}

std::string Metadata::model_name() const {
  // "OS-1-32-G" -> generation "1", beams "32".
  std::vector<std::string> parts;
  std::string part;
  for (const char c : prod_line + "-") {
    if (c == '-') {
      parts.push_back(part);
      part.clear();
    } else {
      part += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    }
  }
  if (parts.size() >= 3 && parts[0] == "os") {
    return "os" + parts[1] + "-" + parts[2];
  }
  return "ouster-" + std::to_string(pixels_per_column);
}

Metadata parse_metadata(const std::string& text, const std::string& source_name) {
  const YamlField root(io::parse_yaml(text, source_name), "", source_name, 1);
  Metadata m;
  m.layout = detect_layout(root);
  const Sections sections(root, m.layout);
  read_identity(sections, m);
  read_data_format(sections, m);
  read_beams(sections, m);
  read_ports(sections, m);
  return m;
}

}  // namespace rsu::lidar::ouster
