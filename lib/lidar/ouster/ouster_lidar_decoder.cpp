// SPDX-License-Identifier: Apache-2.0
// The Ouster decoder behind the decoder seam (see ouster_lidar_decoder.h).
#include "lidar/ouster/ouster_lidar_decoder.h"

#include <array>
#include <cmath>
#include <stdexcept>

#include "common/angles.h"
#include "io/yaml_field.h"

namespace rsu::lidar::ouster {
namespace {

constexpr std::array<PacketResult, 9> kRefusals = {
    PacketResult::wrong_size,        PacketResult::not_lidar_packet, PacketResult::wrong_serial,
    PacketResult::wrong_init_id,     PacketResult::bad_timestamp,    PacketResult::bad_measurement_id,
    PacketResult::frame_id_mismatch, PacketResult::frame_behind,     PacketResult::column_behind,
};

std::string joined(const std::vector<std::string>& parts) {
  std::string out;
  for (const std::string& p : parts) {
    out += (out.empty() ? "" : "; ") + p;
  }
  return out;
}

}  // namespace

OusterLidarDecoder::OusterLidarDecoder(Metadata metadata, std::string metadata_source,
                                       double rotation_start_azimuth_deg, DecoderConfig config)
    : decoder_(std::move(metadata), config),
      reader_(decoder_.metadata().profile, decoder_.metadata().pixels_per_column,
              decoder_.metadata().columns_per_packet),
      source_(std::move(metadata_source)) {
  if (!std::isfinite(rotation_start_azimuth_deg)) {
    throw std::invalid_argument("Ouster decoder: the rotation start azimuth must be finite");
  }
  const Metadata& m = decoder_.metadata();
  model_name_ = m.model_name();
  const double column_s = 1.0 / (m.frequency_hz * static_cast<double>(m.columns_per_frame));
  column_ns_ = static_cast<TimeNs>(std::llround(column_s * 1e9));
  geometry_.rotation_hz = m.frequency_hz;
  for (const double deg : m.beam_azimuth_deg) {
    geometry_.ring_azimuth_offset_rad.push_back(deg_to_rad(deg));
  }
  geometry_.azimuth_lead_rad = 0.0;  // every pixel of a column fires at the column's encoder angle
  geometry_.rotation_start_azimuth_rad = wrap_angle_positive(deg_to_rad(rotation_start_azimuth_deg));
  geometry_.packet_period_ns = std::llround(m.columns_per_packet * column_s * 1e9);
  if (!m.defaults_used.empty()) {
    notices_.push_back(source_ +
                       ": fields the file lacks, the Ouster SDK's defaults used: " + joined(m.defaults_used));
  }
}

SensorPorts OusterLidarDecoder::default_ports() const {
  return {decoder_.metadata().udp_port_lidar, decoder_.metadata().udp_port_imu};
}

TimeNs OusterLidarDecoder::next_packet_ns(const PacketInfo& info) const {
  const Metadata& m = decoder_.metadata();
  const int w = m.columns_per_frame;
  int steps = 1;
  if (!m.in_window((info.last_column + 1) % w)) {
    // Leaving the azimuth window: the next valid column is the window's first, a turn later.
    steps = ((m.column_window_first - info.last_column) % w + w) % w;
    steps = steps == 0 ? w : steps;
  }
  return info.last_time_ns + steps * column_ns_;
}

void OusterLidarDecoder::note_refusal(PacketResult result, std::span<const std::uint8_t> payload) {
  const Metadata& m = decoder_.metadata();
  if (result == PacketResult::wrong_serial && !told_serial_) {
    told_serial_ = true;
    notices_.push_back("Ouster packets from serial number " +
                       std::to_string(reader_.header(payload).serial_number) + ", but " + source_ +
                       " describes serial number " + m.serial +
                       ": refused (wrong_serial): another sensor sends to this port");
  }
  if (result == PacketResult::wrong_init_id && !told_init_id_) {
    told_init_id_ = true;
    notices_.push_back("Ouster packets of initialization " +
                       std::to_string(reader_.header(payload).initialization_id) + ", but " + source_ +
                       " describes initialization " + std::to_string(m.initialization_id.value_or(0)) +
                       ": the sensor was re-initialised; its packets are refused (wrong_init_id) until its "
                       "metadata is read again");
  }
}

PacketOutcome OusterLidarDecoder::decode(std::span<const std::uint8_t> payload, TimeNs /*reference_ns*/,
                                         std::vector<LidarPoint>& out) {
  // The packets carry complete timestamps: the reference time resolves nothing.
  const PacketResult result = decoder_.decode(payload, out);
  if (result == PacketResult::imu_packet) {
    return PacketOutcome{PacketKind::auxiliary, "imu", 0, 0};
  }
  if (result != PacketResult::accepted) {
    note_refusal(result, payload);
    return PacketOutcome{PacketKind::refused, to_string(result), 0, 0};
  }
  const PacketInfo& info = decoder_.last_packet();
  if (info.first_column < 0) {
    ++empty_packets_;
    return PacketOutcome{PacketKind::auxiliary, "no_valid_column", 0, 0};
  }
  return PacketOutcome{PacketKind::data, "accepted", info.first_time_ns, next_packet_ns(info)};
}

std::vector<std::pair<std::string, std::uint64_t>> OusterLidarDecoder::counters() const {
  const DecoderStats& s = decoder_.stats();
  std::vector<std::pair<std::string, std::uint64_t>> out = {
      {"accepted", s.accepted - empty_packets_}, {"imu", s.imu_packets}, {"no_valid_column", empty_packets_}};
  for (const PacketResult r : kRefusals) {
    out.emplace_back(std::string(to_string(r)), s.of(r));
  }
  for (const auto& [name, value] : {std::pair{"note.columns_decoded", s.columns_decoded},
                                    {"note.columns_invalid", s.columns_invalid},
                                    {"note.columns_skipped", s.columns_skipped},
                                    {"note.frames", s.frames},
                                    {"note.frames_complete", s.frames_complete},
                                    {"note.frame_id_jumps", s.frame_id_jumps},
                                    {"note.points", s.points},
                                    {"note.no_return", s.no_return},
                                    {"note.too_close", s.too_close}}) {
    out.emplace_back(name, value);
  }
  return out;
}

std::vector<std::string> OusterLidarDecoder::take_notices() {
  return std::exchange(notices_, {});
}

bool is_ouster_model(std::string_view model) {
  if (model == "ouster") {
    return true;
  }
  for (const std::string_view generation : {"os0-", "os1-", "os2-"}) {
    for (const std::string_view beams : {"16", "32", "64", "128"}) {
      if (model.size() == generation.size() + beams.size() && model.starts_with(generation) &&
          model.ends_with(beams)) {
        return true;
      }
    }
  }
  return false;
}

std::unique_ptr<LidarDecoder> make_ouster_decoder(std::string_view model, const std::string& metadata_text,
                                                  const std::string& metadata_source,
                                                  double rotation_start_azimuth_deg) {
  if (metadata_text.empty()) {
    throw std::invalid_argument(
        "LiDAR model " + std::string(model) +
        " needs the sensor's metadata JSON (lidar.metadata), which describes its beams "
        "and packet format");
  }
  Metadata metadata;
  try {
    metadata = parse_metadata(metadata_text, metadata_source);
  } catch (const io::YamlError& e) {
    throw std::invalid_argument(e.what());
  }
  if (model != "ouster" && model != metadata.model_name()) {
    throw std::invalid_argument("LiDAR model " + std::string(model) + ", but " + metadata_source +
                                " describes an " + metadata.model_name() + " (" + metadata.prod_line +
                                "): the metadata of another sensor?");
  }
  return std::make_unique<OusterLidarDecoder>(std::move(metadata), metadata_source,
                                              rotation_start_azimuth_deg);
}

}  // namespace rsu::lidar::ouster
