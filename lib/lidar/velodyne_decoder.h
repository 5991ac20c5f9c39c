// SPDX-License-Identifier: Apache-2.0
// The Velodyne decoder (VLP-16, VLP-32C, HDL-32E; lidar_decoder.h is the contract it keeps): packets
// of one configured sensor into points.
//
//   - Data packets (1206 bytes) in strongest, last or dual-return mode. Dual: both echoes of a firing,
//     each tagged (point.h: the last block's echo is the last; the other block's is the strongest when
//     its reflectivity is higher, else the second strongest and the last one is also the strongest);
//     when both blocks report the same distance there was one echo, decoded once, tagged as both. The
//     ReturnSelection keeps both or one of them; single-return packets are used as they come.
//   - The model the operator configured wins over a contradicting factory byte (early VLP-16 firmware
//     reports 0x21, the HDL-32E's): the packets are decoded as configured, counted, and one notice
//     names both. Unknown product bytes are refused.
//   - The rotation rate is measured from the packets' azimuth progression (any rpm the sensors run,
//     300-1200), not assumed: it times the firings after a field-of-view gap (firing_schedule.h) and is
//     what geometry() reports.
//   - Position packets (512 bytes, port 8308) are auxiliary: counted as "position", never as broken
//     data. When one carries a valid $GPRMC whose time agrees with its own timestamp (the sensor's
//     clock follows the GPS), the data packets' hour is taken from the GPS date and time instead of
//     the caller's reference time.
// Never throws on packet content; a packet with any structural error is refused whole and counted.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "lidar/firing_schedule.h"
#include "lidar/lidar_decoder.h"
#include "lidar/sensor_model.h"
#include "lidar/velodyne_packet.h"

namespace rsu::lidar {

struct VelodyneStats {
  // One per payload: the outcome.
  std::uint64_t accepted = 0;
  std::uint64_t position = 0;
  std::array<std::uint64_t, 8> refused{};  // indexed by DecodeResult (accepted unused)
  // Informational.
  std::uint64_t product_overridden = 0;  // accepted packets whose factory byte names another model
  std::uint64_t points = 0;              // points appended
  std::uint64_t no_return = 0;           // firings without an echo
  std::uint64_t echoes_dropped = 0;      // echoes a dual-return selection left out (duplicates excluded)
  std::uint64_t field_of_view_gaps = 0;  // packets spanning the gap of a limited field of view
  std::uint64_t gps_hours = 0;           // data packets whose hour came from the GPS ($GPRMC)

  std::uint64_t refused_count(DecodeResult r) const { return refused[static_cast<std::size_t>(r)]; }
  std::uint64_t rejected() const;
  std::uint64_t packets() const { return accepted + position + rejected(); }
};

class VelodyneDecoder final : public LidarDecoder {
 public:
  // Throws std::invalid_argument if the model has no packet format or is invalid.
  explicit VelodyneDecoder(const SensorModel& model, ReturnSelection returns = ReturnSelection::both,
                           double rotation_start_azimuth_deg = 0.0);

  PacketOutcome decode(std::span<const std::uint8_t> payload, TimeNs reference_ns,
                       std::vector<LidarPoint>& out) override;
  const SweepGeometry& geometry() const override { return geometry_; }
  SensorPorts default_ports() const override { return {kVelodyneDataPort, kVelodynePositionPort}; }
  std::string_view model_name() const override { return model_.name; }
  std::vector<std::pair<std::string, std::uint64_t>> counters() const override;
  std::vector<std::string> take_notices() override;

  // The last data packet's outcome in detail (accepted for a position packet).
  DecodeResult last_result() const { return last_result_; }
  const VelodyneStats& stats() const { return stats_; }
  const SensorModel& model() const { return model_; }
  // The measured rotation rate, degrees per microsecond (the model's nominal rate before any packet).
  double degrees_per_us() const { return degrees_per_us_; }

 private:
  PacketOutcome refuse(DecodeResult result);
  PacketOutcome on_position_packet(const PositionPacket& packet, TimeNs reference_ns);
  // The sensor's GPS time near `reference_ns` (the caller's clock), while a recent $GPRMC gives it.
  std::optional<TimeNs> gps_reference(TimeNs reference_ns) const;
  void measure_rate(const PacketTiming& timing);
  void update_geometry();
  void append_points(std::vector<LidarPoint>& out);
  void note_product(std::uint8_t product);
  void note_field_of_view();
  LidarPoint make_point(const Firing& f, std::uint16_t raw, std::uint8_t reflectivity,
                        std::uint8_t echo) const;

  SensorModel model_;
  ReturnSelection returns_;
  double rotation_start_rad_;
  std::vector<double> cos_elevation_;  // per laser, precomputed once
  std::vector<double> sin_elevation_;
  VelodyneStats stats_;
  DecodeResult last_result_ = DecodeResult::accepted;
  double degrees_per_us_;
  bool rate_measured_ = false;
  bool last_dual_ = false;
  SweepGeometry geometry_;
  // The GPS clock: the UTC time of the last valid $GPRMC that agreed with its packet's timestamp, and
  // the caller's reference time when it came.
  std::optional<TimeNs> gps_utc_;
  TimeNs gps_reference_ns_ = 0;
  std::vector<std::string> notices_;
  bool product_noticed_ = false;
  bool field_of_view_noticed_ = false;
  bool gps_noticed_ = false;
  PacketReturns returns_scratch_;  // reused packet after packet
  std::vector<Firing> firings_;    // scratch
};

}  // namespace rsu::lidar
