// SPDX-License-Identifier: Apache-2.0
// A packet decoder for the configured sensor: the one seam between the LiDARs' packet formats (Velodyne:
// velodyne_decoder.h; Ouster: its own decoder) and everything downstream of them (RsuCore's frame and
// sector assembly and its release rule, rsu-decode, rsud's UDP and capture inputs), which never asks
// which sensor it is.
//
// The contract every decoder keeps:
//   - decode() takes one UDP payload as it arrived and never throws on its content. It says what the
//     payload was (PacketOutcome): sensor data (its points appended to `out`), an auxiliary packet of
//     the sensor that carries no points (a Velodyne position packet, an Ouster IMU packet), or refused
//     with a reason. Every payload is counted exactly once under one name of counters().
//   - Points are in the SENSOR frame (x forward, y left, z up, metres), in firing order, each with its
//     ring (laser / beam index, 0-based, the sensor's channel order), its own firing time on the
//     SENSOR's clock (ns; the caller moves it to the host clock if asked), its intensity (0..255), which
//     return it is (point.h) and its beam azimuth (clockwise seen from above, 0 at +x, [0, 2 pi): the
//     encoder azimuth at its firing plus its ring's azimuth offset, SweepGeometry).
//   - The time of a packet comes from the packet. `reference_ns` (the receive time, or a capture's
//     record time) only resolves what the packet leaves ambiguous (e.g. the hour of a Velodyne
//     timestamp) and is never a point's time.
//   - geometry() tells the downstream rules what they need to know about the sweep: how fast it turns
//     (as measured from the packets once they arrive), how far each ring's beam leads or lags the
//     encoder, where a rotation starts and the packet rhythm (for loss counting).
//   - Things the operator must hear once (a factory byte contradicting the configured model, a limited
//     field of view found) are queued as notices; the caller logs them. lib/ never logs.
// Pure: no clock, file or socket; decoders are single-threaded objects, one per sensor stream.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "common/time.h"
#include "lidar/point.h"
#include "lidar/sensor_model.h"

namespace rsu::lidar {

enum class PacketKind : std::uint8_t {
  data,       // points appended (possibly none: every firing without a return)
  auxiliary,  // the sensor's own packet without points (position, IMU): counted, may set the clock
  refused,    // not a usable packet of this sensor: counted by reason, nothing appended
};

struct PacketOutcome {
  PacketKind kind = PacketKind::refused;
  // refused: why, as counted in counters() ("wrong_size", ...); auxiliary: what it was ("position").
  std::string_view reason;
  // data: sensor time of the packet's first firing: its place in the stream.
  TimeNs first_ns = 0;
  // data: sensor time at which the sensor's next packet starts if none is lost: after this packet's
  // last firing, or, where the packet ends at the edge of a limited field of view, when the sweep
  // enters the field of view again. next_ns - first_ns is the packet's known duration.
  TimeNs next_ns = 0;

  bool is_data() const { return kind == PacketKind::data; }
};

// What the frame assembly and the release rule need to know about the sweep.
struct SweepGeometry {
  // Measured from the packets' azimuth progression once data arrived; the model's nominal rate before.
  double rotation_hz = 10.0;
  // Per ring: the beam azimuth minus the encoder azimuth at the ring's firing, radians (clockwise).
  std::vector<double> ring_azimuth_offset_rad;
  // Beam azimuths may run ahead of the encoder at their firing by up to this much beyond their ring
  // offset (the VLP-32C manual's precision-azimuth rule: sensor_model.h), radians.
  double azimuth_lead_rad = 0.0;
  // Where one rotation ends and the next begins (beam azimuth, clockwise from +x, radians).
  double rotation_start_azimuth_rad = 0.0;
  // The spacing of consecutive packets' first firings when none is lost.
  TimeNs packet_period_ns = 0;
};

// UDP ports the sensor sends on by default (rsud's capture input filters on them).
struct SensorPorts {
  std::uint16_t data = 0;
  std::uint16_t auxiliary = 0;  // 0: none
};

// Which returns of a multi-return sensor are used.
enum class ReturnSelection : std::uint8_t {
  both,       // every return, each tagged (point.h)
  strongest,  // the strongest of each firing
  last,       // the last of each firing
};
std::string_view to_string(ReturnSelection selection);
// "both", "strongest", "last"; nullopt otherwise.
std::optional<ReturnSelection> return_selection_by_name(std::string_view name);

class LidarDecoder {
 public:
  virtual ~LidarDecoder() = default;

  // One UDP payload (see the file comment). Points are appended to `out`, never removed.
  virtual PacketOutcome decode(std::span<const std::uint8_t> payload, TimeNs reference_ns,
                               std::vector<LidarPoint>& out) = 0;

  // Kept up to date packet by packet (cheap to call after every packet).
  virtual const SweepGeometry& geometry() const = 0;
  virtual SensorPorts default_ports() const = 0;
  // The model the points are decoded as (e.g. "vlp16").
  virtual std::string_view model_name() const = 0;
  // Every payload counted once, as ("<name>", count), zeros included, in a stable order: "accepted",
  // then the auxiliary kinds, then the refusal reasons. Informational counts that are not a packet's
  // outcome carry a "note." prefix and are not part of that sum.
  virtual std::vector<std::pair<std::string, std::uint64_t>> counters() const = 0;
  // Notices for the operator queued since the last call (each said once), oldest first.
  virtual std::vector<std::string> take_notices() = 0;

  // Payloads counted by counters() (those without the "note." prefix).
  std::uint64_t packets_seen() const;
};

// What selects and configures a decoder besides the model's name.
struct LidarDecoderOptions {
  // A Velodyne calibration (io/velodyne_calibration.h: the YAML the ROS and nebula drivers read) turned
  // into the model's tables; replaces the built-in tables of the named model. Unset: built-in tables.
  std::optional<SensorModel> calibrated_model;
  // The sensor's metadata as the sensor reports it (Ouster: the JSON of lidar.metadata), as text.
  std::string metadata_text;
  std::string metadata_source;  // its file name, for error messages
  ReturnSelection returns = ReturnSelection::both;
  // Where a rotation starts (scan phase, clockwise from +x), degrees.
  double rotation_start_azimuth_deg = 0.0;

  bool operator==(const LidarDecoderOptions&) const = default;
};

// The models make_lidar_decoder knows, as said in errors.
inline constexpr std::string_view kDecodableModels =
    "vlp16, vlp32c, hdl32e, or an Ouster: os0-, os1-, os2- with 16, 32, 64 or 128 beams (os1-128), or ouster "
    "(the model its metadata names)";

// The decoder for `model` ("vlp16", "vlp32c", "hdl32e", "os1-128", ...). An Ouster needs
// options.metadata_text. Throws std::invalid_argument naming the
// problem for an unknown model or unusable options.
std::unique_ptr<LidarDecoder> make_lidar_decoder(std::string_view model, const LidarDecoderOptions& options);
// Whether make_lidar_decoder knows `model` (for configuration checks before any file is read).
bool is_decodable_model(std::string_view model);
// The tables of the points the decoder for `model` with `options` gives (their lasers' elevations, the
// azimuth step): a Velodyne calibration's, an Ouster's from its metadata, else the named model's
// (sensor_model_by_name, which knows "genericN" too). nullopt for an unknown model or unreadable metadata.
std::optional<SensorModel> decoded_sensor_model(std::string_view model, const LidarDecoderOptions& options);

}  // namespace rsu::lidar
