// SPDX-License-Identifier: Apache-2.0
// The decoder seam (see lidar_decoder.h): names, counts and the factory.
#include "lidar/lidar_decoder.h"

#include <stdexcept>

#include "lidar/ouster/ouster_geometry.h"
#include "lidar/ouster/ouster_lidar_decoder.h"
#include "lidar/ouster/ouster_metadata.h"
#include "lidar/velodyne_decoder.h"

namespace rsu::lidar {

std::string_view to_string(ReturnSelection selection) {
  switch (selection) {
    case ReturnSelection::both:
      return "both";
    case ReturnSelection::strongest:
      return "strongest";
    case ReturnSelection::last:
      return "last";
  }
  return "unknown";
}

std::optional<ReturnSelection> return_selection_by_name(std::string_view name) {
  for (const ReturnSelection s : {ReturnSelection::both, ReturnSelection::strongest, ReturnSelection::last}) {
    if (name == to_string(s)) {
      return s;
    }
  }
  return std::nullopt;
}

std::uint64_t LidarDecoder::packets_seen() const {
  std::uint64_t n = 0;
  for (const auto& [name, count] : counters()) {
    if (!name.starts_with("note.")) {
      n += count;
    }
  }
  return n;
}

bool is_decodable_model(std::string_view model) {
  const auto velodyne = sensor_model_by_name(model);
  return (velodyne && velodyne->has_packet_format()) || ouster::is_ouster_model(model);
}

std::optional<SensorModel> decoded_sensor_model(std::string_view model, const LidarDecoderOptions& options) {
  if (options.calibrated_model)
    return options.calibrated_model;
  if (ouster::is_ouster_model(model) && !options.metadata_text.empty()) {
    try {
      // The minimum range plays no part in the tables.
      return ouster::sensor_model(ouster::parse_metadata(options.metadata_text, options.metadata_source),
                                  0.0);
    } catch (const std::exception&) {
      return std::nullopt;  // make_lidar_decoder says why
    }
  }
  return sensor_model_by_name(model);
}

std::unique_ptr<LidarDecoder> make_lidar_decoder(std::string_view model, const LidarDecoderOptions& options) {
  if (const auto velodyne = sensor_model_by_name(model); velodyne && velodyne->has_packet_format()) {
    const SensorModel& tables = options.calibrated_model ? *options.calibrated_model : *velodyne;
    return std::make_unique<VelodyneDecoder>(tables, options.returns, options.rotation_start_azimuth_deg);
  }
  if (ouster::is_ouster_model(model)) {
    if (options.calibrated_model) {
      throw std::invalid_argument("a Velodyne calibration does not apply to an Ouster (" +
                                  std::string(model) + ")");
    }
    return ouster::make_ouster_decoder(model, options.metadata_text, options.metadata_source,
                                       options.rotation_start_azimuth_deg);
  }
  throw std::invalid_argument("unknown LiDAR model \"" + std::string(model) + "\" (expected " +
                              std::string(kDecodableModels) + ")");
}

}  // namespace rsu::lidar
