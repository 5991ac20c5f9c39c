// SPDX-License-Identifier: Apache-2.0
#include "daemon/rsu_daemon.h"

#include <malloc.h>
#include <spdlog/spdlog.h>

#include <csignal>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <stdexcept>

#include "daemon/dds_edge.h"
#include "daemon/metrics_text.h"
#include "daemon/peer_bus.h"
#include "daemon/systemd_notify.h"
#include "daemon/udp_socket.h"
#include "daemon/v2i_receiver.h"
#include "daemon/worker_thread.h"
#include "edge/address_text.h"
#include "edge/arrival_stamp.h"
#include "edge/host_clock.h"
#include "io/background_state.h"
#include "io/pcd_io.h"
#include "io/text_file.h"

namespace rsu::daemon {

namespace asio = boost::asio;

namespace {

std::chrono::steady_clock::duration seconds(double s) {
  return std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(s));
}

}  // namespace

RsuDaemon::RsuDaemon(asio::io_context& io, DaemonConfig config, ConfigSource source)
    : io_(io),
      config_(std::move(config)),
      source_(std::move(source)),
      core_(config_.core),
      bad_input_(config_.logging.bad_input_log_first, seconds(config_.logging.summary_interval_s)),
      v2i_socket_(io),
      lidar_socket_(io),
      auxiliary_socket_(io),
      signals_(io, SIGHUP, SIGTERM, SIGINT),
      housekeeping_timer_(io),
      watchdog_timer_(io),
      advertise_timer_(io),
      stats_timer_(io),
      input_timer_(io),
      object_list_timer_(io),
      metrics_timer_(io),
      sensor_model_(config_.core.sensor_options.calibrated_model
                        ? config_.core.sensor_options.calibrated_model
                        : lidar::sensor_model_by_name(config_.core.sensor_model)) {}

RsuDaemon::~RsuDaemon() = default;

template <typename Step>
core::LidarStepResult RsuDaemon::timed(Step step) {
  const auto began = steady::now();
  core::LidarStepResult result = step();
  lidar_step_seconds_.observe(std::chrono::duration<double>(steady::now() - began).count());
  return result;
}

TimeNs RsuDaemon::clock_now() const {
  return replaying_ ? replay_now_ : edge::host_now_ns();
}

void RsuDaemon::start() {
  const udp::endpoint v2i(edge::parse_ip_address(config_.v2i_listen_address, "v2i.listen_address"),
                          config_.v2i_port);
  bind_udp(v2i_socket_, v2i, "V2I");
  // Room for bursts of announcements while a cluster is being corrected.
  v2i_receive_buffer_bytes_ = request_receive_buffer(v2i_socket_, config_.v2i_receive_buffer_bytes, "V2I");
  boost::system::error_code ignored;
  if (config_.advertisement.enabled)
    v2i_socket_.set_option(asio::socket_base::broadcast(true), ignored);
  spdlog::info("listening for V2I announcements on {}:{}", v2i.address().to_string(), v2i.port());
  warn_if_insecure();

  spdlog::info("LiDAR mount from {}", config_.mount_source);
  for (const std::string& warning : config_.state_warnings)
    spdlog::warn("state directory: {}", warning);
  if (!config_.background_pcd_files.empty())
    load_background_pcd();
  else
    load_saved_background();
  start_dds();
  start_input();
  if (config_.mount_check_thread && !replaying_) {
    // 4 rotations: 0.2-0.4 s of a LiDAR's, a lag well within the second the fixes must stop in; never
    // the batch that builds the reference.
    mount_checks_ = std::make_unique<WorkerThread<core::MountRotations, core::MountChecks>>(
        io_, "rsud-mount", core::check_mount_rotations,
        [this](core::MountChecks&& checks) {
          core_.record_mount_checks(checks);  // its notices logged with the next LiDAR result
        },
        WorkerThread<core::MountRotations, core::MountChecks>::Bound{
            4, [](const core::MountRotations& r) { return r.rotations.size(); },
            [](const core::MountRotations& r) { return r.source.has_value(); }});
  }
  if (config_.prepare_thread && config_.core.prepare_fixes && !replaying_) {
    // 8 steps' worth: a few packets. An older preparation is of no use: its vehicles are released by now.
    preparation_ = std::make_unique<WorkerThread<core::Preparation, core::Prepared>>(
        io_, "rsud-prepare", core::prepare,
        [this](core::Prepared&& prepared) {
          core_.record_prepared(std::move(prepared));
          submit_preparation();  // the vehicles its fits would release
        },
        WorkerThread<core::Preparation, core::Prepared>::Bound{8});
  }

  signals_.async_wait([this](const boost::system::error_code& ec, int signal_number) {
    if (!ec)
      on_signal(signal_number);
  });
  every(housekeeping_timer_, std::chrono::milliseconds(500), &RsuDaemon::on_housekeeping);
  if (const auto interval = watchdog_ping_interval()) {
    spdlog::info("systemd watchdog enabled: pinging every {} ms", interval->count() / 1000);
    every(watchdog_timer_, *interval, &RsuDaemon::on_watchdog);
  }
  if (config_.advertisement.enabled) {
    every(advertise_timer_, seconds(config_.advertisement.interval_s), &RsuDaemon::on_advertise);
  }
  if (config_.logging.stats_interval_s > 0) {
    every(stats_timer_, seconds(config_.logging.stats_interval_s), &RsuDaemon::on_stats);
  }
  if (!config_.metrics.textfile.empty()) {
    spdlog::info("Prometheus metrics in {} every {} s", config_.metrics.textfile, config_.metrics.interval_s);
    every(metrics_timer_, seconds(config_.metrics.interval_s), &RsuDaemon::on_metrics);
  }
  start_v2i_reception();
  become_ready_if_possible();
  if (!ready_) {
    spdlog::info(
        "learning the background from the first {} whole LiDAR rotations (no vehicles should be in view)",
        config_.core.background.learning_frames);
    notify_status("learning the background");
  }
}

void RsuDaemon::become_ready_if_possible() {
  if (ready_ || !core_.background_ready())
    return;
  ready_ = true;
  notify_ready();
  spdlog::info("ready: serving corrections (rsu_id {})", config_.core.rsu_id);
}

void RsuDaemon::every(asio::steady_timer& timer, steady::duration period, void (RsuDaemon::*tick)()) {
  timer.expires_after(period);
  timer.async_wait([this, &timer, period, tick](const boost::system::error_code& ec) {
    if (ec || stopping_)
      return;
    (this->*tick)();
    every(timer, period, tick);
  });
}

// ---- LiDAR input ----------------------------------------------------------------------------------

void RsuDaemon::start_input() {
  if (const auto* u = std::get_if<UdpInput>(&config_.input)) {
    const lidar::SensorPorts ports = core_.lidar_decoder().default_ports();
    const auto address = edge::parse_ip_address(u->bind_address, "lidar.input.udp.bind_address");
    const udp::endpoint endpoint(address, u->port != 0 ? u->port : ports.data);
    bind_udp(lidar_socket_, endpoint, "LiDAR");
    // Room for the packets that arrive while a rotation's work (a fix, the mount check) holds the loop:
    // the kernel's default (net.core.rmem_default, 208 KiB on Debian) holds about a dozen of an OS1-128's
    // 24.8 KB packets, 10 ms of its stream.
    lidar_receive_buffer_bytes_ = request_receive_buffer(lidar_socket_, u->receive_buffer_bytes, "LiDAR");
    spdlog::info("receiving {} packets on {}:{}", core_.lidar_decoder().model_name(),
                 endpoint.address().to_string(), endpoint.port());
    receive_lidar(lidar_socket_, lidar_buffer_, lidar_sender_);
    if (u->auxiliary_port != 0) {
      const udp::endpoint auxiliary(address, u->auxiliary_port);
      bind_udp(auxiliary_socket_, auxiliary, "LiDAR auxiliary (position packets)");
      spdlog::info("receiving its position packets on {}:{}", auxiliary.address().to_string(),
                   auxiliary.port());
      receive_lidar(auxiliary_socket_, auxiliary_buffer_, auxiliary_sender_);
    }
  } else if (std::holds_alternative<PcapInput>(config_.input)) {
    start_capture();
  } else if (const auto* p = std::get_if<PcdInput>(&config_.input)) {
    for (const std::string& file : p->files) {
      try {
        pcd_frames_.push_back(io::read_pcd(file));
      } catch (const std::exception& e) {
        throw std::runtime_error(std::string("lidar.input.pcd: ") + e.what());
      }
    }
    spdlog::info("replaying {} PCD frame(s) at {} Hz", pcd_frames_.size(), p->rate_hz);
    every(input_timer_, seconds(1.0 / p->rate_hz), &RsuDaemon::on_pcd_frame);
  } else if (const auto* d = std::get_if<DdsPointCloud2Input>(&config_.input)) {
    dds_->start_input(
        *d, sensor_model_ ? std::span<const double>(sensor_model_->elevation_deg) : std::span<const double>(),
        [this](std::span<const lidar::LidarPoint> points, bool whole) {
          if (stopping_)
            return;
          handle_lidar_result(timed([&] {
            return whole ? core_.on_lidar_frame(points, clock_now())
                         : core_.on_lidar_points(points, clock_now());
          }));
        });
  }
}

// ---- DDS ------------------------------------------------------------------------------------------

void RsuDaemon::start_dds() {
  if (!config_.dds.enabled)
    return;
  dds_ = std::make_unique<DdsEdge>(io_, config_.dds, config_.core.rsu_id, bad_input_);
  if (config_.dds.peers.enabled) {
    peers_ = std::make_unique<PeerBus>(
        io_, dds_->participant(), config_.dds.peers, config_.core.rsu_id, bad_input_,
        [this](std::span<const std::uint8_t> datagram, const core::PeerProvenance& from) {
          on_peer_announcement(datagram, from);
        });
  }
  if (!config_.dds.object_list_topic.empty()) {
    // Once per rotation (issue 6: the object list each rotation).
    every(object_list_timer_, seconds(1.0 / core_.lidar_decoder().geometry().rotation_hz),
          &RsuDaemon::on_object_list);
  }
}

void RsuDaemon::on_object_list() {
  dds_->publish_object_list(clock_now());
}

void RsuDaemon::receive_lidar(udp::socket& socket, std::array<std::uint8_t, 65536>& buffer,
                              udp::endpoint& sender) {
  socket.async_receive_from(
      asio::buffer(buffer), sender,
      [this, &socket, &buffer, &sender](const boost::system::error_code& ec, std::size_t bytes) {
        if (ec == asio::error::operation_aborted || stopping_)
          return;
        if (!ec) {
          const TimeNs read = clock_now();
          // The kernel's stamp of its arrival (SIOCGSTAMPNS: none for the first packet, which turns them
          // on): how long it waited in the socket for the loop (metrics: lidar_socket_wait_seconds).
          if (const std::optional<TimeNs> arrival = edge::last_arrival(socket.native_handle())) {
            stepped_packet_ = PacketTimes{*arrival, read};
            lidar_socket_wait_seconds_.observe(to_seconds(read - *arrival));
          }
          on_lidar_payload(std::span<const std::uint8_t>(buffer.data(), bytes), read,
                           sender.address().to_string());
          stepped_packet_.reset();
        } else {
          spdlog::debug("LiDAR socket: {}", ec.message());
        }
        receive_lidar(socket, buffer, sender);
      });
}

void RsuDaemon::on_lidar_payload(std::span<const std::uint8_t> payload, TimeNs arrival,
                                 const std::string& from) {
  const auto result = timed([&] { return core_.on_lidar_packet(payload, arrival); });
  if (result.packet.kind == lidar::PacketKind::data) {
    if (const core::SensorClockReport clock = core_.sensor_clock(); clock.known)
      sensor_clock_offset_seconds_.observe(to_seconds(clock.offset_ns));
  }
  if (result.packet.kind == lidar::PacketKind::refused) {
    ++lidar_packets_rejected_;
    bad_input_.report("lidar_packet:" + std::string(result.packet.reason),
                      std::to_string(payload.size()) + " bytes from " + from);
  }
  handle_lidar_result(result);
}

// ---- capture replay -------------------------------------------------------------------------------

void RsuDaemon::start_capture() {
  const auto& input = std::get<PcapInput>(config_.input);
  try {
    capture_ = std::make_unique<io::CaptureFile>(input.file);
  } catch (const io::CaptureError& e) {
    throw std::runtime_error(std::string("lidar.input.pcap: ") + e.what());
  }
  const lidar::SensorPorts ports = core_.lidar_decoder().default_ports();
  capture_data_port_ = input.port != 0 ? input.port : ports.data;
  capture_auxiliary_port_ = input.auxiliary_port != 0 ? input.auxiliary_port : ports.auxiliary;
  if (!next_capture_datagram()) {
    throw std::runtime_error("lidar.input.pcap: " + input.file + ": no UDP datagram in the capture");
  }
  replaying_ = true;
  replay_now_ = capture_next_->time_ns;
  capture_first_ns_ = capture_next_->time_ns;
  clock_started_ = replay_now_;
  next_replay_housekeeping_ = replay_now_;
  pass_started_ = steady::now();
  spdlog::info(
      "replaying {} at {} pace; the run's clock is the capture's; {} datagrams to ports {} and {} go to the "
      "{} decoder",
      input.file, input.pace == PcapInput::Pace::kMax ? "maximum" : "the recorded", config_.core.sensor_model,
      capture_data_port_, capture_auxiliary_port_, config_.core.sensor_model);
  asio::post(io_, [this] { replay_step(); });
}

bool RsuDaemon::next_capture_datagram() {
  lidar::UdpDatagram d;
  if (!capture_->next(d)) {
    capture_next_.reset();
    return false;
  }
  capture_next_ = std::move(d);
  return true;
}

void RsuDaemon::replay_datagram(const lidar::UdpDatagram& datagram) {
  replay_now_ = datagram.time_ns + replay_shift_;
  capture_last_ns_ = datagram.time_ns;
  // The output-changing housekeeping on the capture's clock, every 500 ms of it.
  while (replay_now_ >= next_replay_housekeeping_) {
    housekeep(next_replay_housekeeping_);
    next_replay_housekeeping_ += 500 * kNsPerMs;
  }
  const std::uint16_t port = datagram.dst.port;
  if (port != capture_data_port_ && (capture_auxiliary_port_ == 0 || port != capture_auxiliary_port_)) {
    ++capture_counts_.other_datagrams;
    return;
  }
  ++capture_counts_.lidar_datagrams;
  const std::uint32_t ip = datagram.src.ip;
  on_lidar_payload(datagram.payload, replay_now_,
                   std::to_string(ip >> 24) + "." + std::to_string((ip >> 16) & 0xFF) + "." +
                       std::to_string((ip >> 8) & 0xFF) + "." + std::to_string(ip & 0xFF));
}

void RsuDaemon::replay_step() {
  if (stopping_)
    return;
  const auto& input = std::get<PcapInput>(config_.input);
  const bool max_pace = input.pace == PcapInput::Pace::kMax;
  // A bounded batch per turn of the event loop, so that signals, V2I and timers are served meanwhile.
  for (int i = 0; i < 500 && capture_next_; ++i) {
    if (!max_pace) {
      const auto due = pass_started_ + std::chrono::nanoseconds(capture_next_->time_ns - capture_first_ns_);
      if (due > steady::now()) {
        input_timer_.expires_at(due);
        input_timer_.async_wait([this](const boost::system::error_code& ec) {
          if (!ec)
            replay_step();
        });
        return;
      }
    }
    const lidar::UdpDatagram datagram = std::move(*capture_next_);
    next_capture_datagram();
    replay_datagram(datagram);
    if (!capture_next_ && input.loop && capture_->error() == lidar::PcapError::none) {
      // Again from the start, the clock moved on by whole hours so that it never runs backwards and
      // the sensor's microseconds-past-the-hour resolve as before.
      const TimeNs span = capture_last_ns_ - capture_first_ns_ + kNsPerSecond;
      const TimeNs hour = 3600 * kNsPerSecond;
      replay_shift_ += (span + hour - 1) / hour * hour;
      ++capture_counts_.loops;
      capture_->rewind();
      if (next_capture_datagram()) {
        capture_first_ns_ = capture_next_->time_ns;
        pass_started_ = steady::now();
      }
    }
  }
  if (capture_next_) {
    asio::post(io_, [this] { replay_step(); });
    return;
  }
  finish_capture();
}

void RsuDaemon::finish_capture() {
  const lidar::PcapSkipped skipped = capture_->skipped();
  if (capture_->error() != lidar::PcapError::none) {
    spdlog::warn("the capture {} ends where it stops being readable ({}): a recording cut off mid-record",
                 capture_->path(), to_string(capture_->error()));
  }
  spdlog::info(
      "capture replayed: {} records, {} datagrams to the LiDAR's ports, {} to other ports, {} not IPv4, {} "
      "not "
      "UDP, {} unusable fragments, {} malformed; {} packets accepted by the decoder",
      capture_->records(), capture_counts_.lidar_datagrams, capture_counts_.other_datagrams, skipped.not_ipv4,
      skipped.not_udp, skipped.fragmented, skipped.malformed, [this] {
        for (const auto& [name, value] : core_.lidar_decoder().counters()) {
          if (name == "accepted")
            return value;
        }
        return std::uint64_t{0};
      }());
  drain_and_stop();
}

void RsuDaemon::on_pcd_frame() {
  if (pcd_frames_.empty())
    return;
  // Each replayed frame is given the host clock: its last point is "now", the rest keep their spacing.
  std::vector<lidar::LidarPoint> frame = pcd_frames_[next_pcd_frame_ % pcd_frames_.size()];
  ++next_pcd_frame_;
  if (frame.empty())
    return;
  TimeNs last = frame.front().time_ns;
  for (const lidar::LidarPoint& p : frame)
    last = std::max(last, p.time_ns);
  const TimeNs shift = clock_now() - last;
  for (lidar::LidarPoint& p : frame)
    p.time_ns += shift;
  handle_lidar_result(timed([&] { return core_.on_lidar_frame(frame, clock_now()); }));
}

void RsuDaemon::load_background_pcd() {
  std::vector<std::vector<lidar::LidarPoint>> frames;
  for (const std::string& file : config_.background_pcd_files) {
    try {
      frames.push_back(io::read_pcd(file));
    } catch (const std::exception& e) {
      throw std::runtime_error(std::string("background.pcd_files: ") + e.what());
    }
  }
  core_.load_background(frames);
  spdlog::info("background loaded from {} PCD file(s)", frames.size());
}

void RsuDaemon::load_saved_background() {
  if (config_.state.directory.empty() || !config_.state.persist_background)
    return;
  const auto refuse = [this](const std::string& why) {
    ++state_counts_.background_refused;
    spdlog::warn("saved background not used: {}; learning it again", why);
  };
  std::optional<io::PersistedBackground> saved;
  try {
    saved = io::load_background_state(config_.state.directory);
  } catch (const io::BackgroundStateError& e) {
    return refuse(e.what());
  }
  if (!saved) {
    spdlog::info("no saved background in {}", config_.state.directory);
    return;
  }
  if (saved->sensor_model != config_.core.sensor_model)
    return refuse("learned with a " + saved->sensor_model + ", the LiDAR is a " + config_.core.sensor_model);
  if (!(saved->mount == config_.core.mount))
    return refuse("learned under another mount (the mount was changed or recalibrated since)");
  core_.load_background(saved->frames, true);  // checked before it serves (RsuCore::mount_unverified_)
  ++state_counts_.background_loaded;
  spdlog::info("background loaded from {} ({} rotations saved by an earlier run)", config_.state.directory,
               saved->frames.size());
}

void RsuDaemon::save_learned_background() {
  if (config_.state.directory.empty() || !config_.state.persist_background)
    return;
  const auto began = steady::now();
  try {
    io::save_background_state(
        config_.state.directory,
        io::PersistedBackground{config_.core.sensor_model, config_.core.mount, core_.background_frames()});
    ++state_counts_.background_saved;
    spdlog::info("background saved in {} ({:.0f} ms): a restart serves at once", config_.state.directory,
                 std::chrono::duration<double, std::milli>(steady::now() - began).count());
  } catch (const io::BackgroundStateError& e) {
    ++state_counts_.background_save_failed;
    spdlog::warn("background not saved (a restart will learn it again): {}", e.what());
  }
}

void RsuDaemon::handle_lidar_result(const core::LidarStepResult& result) {
  for (const std::string& notice : core_.take_lidar_notices()) {
    spdlog::warn("LiDAR: {}", notice);
    last_clock_warning_ = steady::now();  // the periodic reminder waits a minute after any notice
  }
  if (result.background_became_ready) {
    spdlog::info("background learned from {} whole rotations", core_.lidar_stats().background_frames);
    save_learned_background();
    become_ready_if_possible();
  }
  send_corrections(result.corrections);
  send_withheld_notices(result.withheld_notices);
  // What the step prepares for the next releases, once its corrections are on the wire: here, or on its
  // own thread (perception.prepare_thread; never in a capture replay, whose counters must not depend on
  // the host's timing).
  if (preparation_)
    submit_preparation();
  else
    core_.prepare_pending();
  // The mount check of the rotations just completed, once their corrections are on the wire: on its own
  // thread (live input), or here (a capture replay, whose output must not depend on the host's timing).
  if (mount_checks_) {
    core::MountRotations rotations = core_.take_mount_rotations();
    if (rotations.reference || rotations.source)
      mount_checks_->submit(std::move(rotations));
  } else {
    core_.check_mount_pending();
  }
}

void RsuDaemon::submit_preparation() {
  core::Preparation preparation = core_.take_preparation();
  if (!preparation.empty())
    preparation_->submit(std::move(preparation));
}

bool RsuDaemon::send_to_vehicle(const v2i::UdpEndpoint& destination, std::span<const std::uint8_t> bytes,
                                const std::string& what) {
  boost::system::error_code ec;
  const auto address = asio::ip::make_address(destination.address, ec);
  if (!ec) {
    const udp::endpoint to(address, static_cast<unsigned short>(destination.port));
    v2i_socket_.send_to(asio::buffer(bytes.data(), bytes.size()), to, 0, ec);
  }
  if (ec) {
    bad_input_.report(
        what, "to " + destination.address + ":" + std::to_string(destination.port) + ": " + ec.message());
  }
  return !ec;
}

void RsuDaemon::send_corrections(const std::vector<core::OutgoingCorrection>& corrections) {
  if (dds_)
    dds_->publish(corrections);
  for (const core::OutgoingCorrection& c : corrections) {
    // Stamped as it is handed to the socket: a stamp after the send could come after the vehicle's
    // receipt whenever rsud is descheduled in between (the metrics test failed so on a loaded machine).
    const TimeNs sent = clock_now();
    if (!send_to_vehicle(c.destination, c.bytes, "correction_send")) {
      ++correction_sends_failed_;
      continue;
    }
    ++corrections_sent_;
    correction_latency_seconds_.observe(to_seconds(sent - c.correction.sweep_time));
    if (stepped_packet_) {  // released by a live packet's step: the latency's three parts
      correction_sweep_wait_seconds_.observe(to_seconds(stepped_packet_->arrival - c.correction.sweep_time));
      correction_socket_wait_seconds_.observe(to_seconds(stepped_packet_->read - stepped_packet_->arrival));
      correction_step_seconds_.observe(to_seconds(sent - stepped_packet_->read));
    }
    spdlog::debug(
        "correction #{} to vehicle {} at {}:{}: ({:.3f}, {:.3f}) m, yaw {:.4f} rad, {} points, {} faces",
        c.correction.sequence, c.correction.vehicle_id, c.destination.address, c.destination.port,
        c.correction.pose.x, c.correction.pose.y, c.correction.pose.yaw, c.correction.quality.points_used,
        c.correction.quality.faces_seen);
  }
}

void RsuDaemon::send_withheld_notices(const std::vector<core::OutgoingNotice>& notices) {
  for (const core::OutgoingNotice& n : notices) {
    if (!send_to_vehicle(n.destination, n.bytes, "withheld_notice_send")) {
      ++withheld_notice_sends_failed_;
      continue;
    }
    spdlog::debug("vehicle {} told its fix of sweep {} is withheld: {}", n.notice.vehicle_id,
                  n.notice.sweep_time, v2i::to_string(n.notice.reason));
  }
}

// ---- V2I ------------------------------------------------------------------------------------------

void RsuDaemon::start_v2i_reception() {
  // Each datagram's arrival, stamped by the kernel: its time windows are judged from it, not from when
  // a loop that fell behind got to it (the receiver thread reads it from the control data).
  if (!config_.v2i_verifier_thread) {
    edge::last_arrival(v2i_socket_.native_handle());  // turns the stamps on (none yet)
    receive_v2i();
    return;
  }
  request_arrival_stamps(v2i_socket_.native_handle(), "V2I");
  // 10 s of 1000 vehicles at 10 Hz may wait for the loop; beyond that it has stalled, not fallen behind.
  constexpr std::size_t kMaxWaiting = 100000;
  v2i_receiver_ = std::make_unique<V2iReceiver>(
      v2i_socket_.native_handle(), io_, [this] { on_v2i_arrival(); },
      config_.core.security.mode == v2i::SecurityMode::kSigned, config_.core.trust_list, kMaxWaiting,
      receiver_time_window(), core::announcement_security(config_.core).verify_within);
  spdlog::info("V2I announcements read and their signatures checked on a thread of their own");
}

std::optional<v2i::security::ReplayConfig> RsuDaemon::receiver_time_window() const {
  // The receiver thread reads the host's clock; replaying a capture, rsud runs on the capture's.
  if (replaying_)
    return std::nullopt;
  return config_.core.security.replay;
}

void RsuDaemon::on_v2i_arrival() {
  if (stopping_)
    return;
  // At 10 000 announcements/s, 256 are ~25 ms of them and well under a millisecond of this thread.
  constexpr std::size_t kPerTurn = 256;
  const std::vector<ReceivedDatagram> batch = v2i_receiver_->take(kPerTurn);
  for (const ReceivedDatagram& d : batch) {
    if (stopping_)
      return;
    on_v2i_datagram(d.bytes, d.sender, d.signature ? &*d.signature : nullptr, d.received);
  }
  if (batch.size() == kPerTurn)
    asio::post(io_, [this] { on_v2i_arrival(); });
}

void RsuDaemon::receive_v2i() {
  v2i_socket_.async_receive_from(
      asio::buffer(v2i_buffer_), v2i_sender_, [this](const boost::system::error_code& ec, std::size_t bytes) {
        if (ec == asio::error::operation_aborted || stopping_)
          return;
        if (!ec) {
          on_v2i_datagram(std::span<const std::uint8_t>(v2i_buffer_.data(), bytes), v2i_sender_, nullptr,
                          edge::last_arrival(v2i_socket_.native_handle()));
        } else {
          // e.g. an ICMP error for an earlier correction: not fatal.
          spdlog::debug("V2I socket: {}", ec.message());
        }
        receive_v2i();
      });
}

void RsuDaemon::on_v2i_datagram(std::span<const std::uint8_t> datagram, const udp::endpoint& sender,
                                const v2i::SignatureCheck* checked, std::optional<TimeNs> received) {
  asio::ip::address address = sender.address();
  if (address.is_v6() && address.to_v6().is_v4_mapped()) {
    address = asio::ip::make_address_v4(asio::ip::v4_mapped, address.to_v6());
  }
  const core::SourceEndpoint source{address.to_string(), sender.port()};
  const TimeNs now = clock_now();
  // The kernel's arrival stamp is on the host's clock: replaying a capture, rsud runs on the capture's.
  if (replaying_)
    received.reset();
  const core::DatagramOutcome outcome = core_.on_datagram(datagram, source, now, checked, received);
  if (!outcome.refusal_notice.empty()) {
    // Back to where the datagram came from (never to its reply_to: docs/v2i.md).
    boost::system::error_code ec;
    v2i_socket_.send_to(asio::buffer(outcome.refusal_notice), sender, 0, ec);
    if (ec) {
      ++refusal_sends_failed_;
      bad_input_.report("refusal_send",
                        "to " + source.address + ":" + std::to_string(source.port) + ": " + ec.message());
    }
  }
  if (outcome.accepted()) {
    if (outcome.upsert == v2i::UpsertOutcome::kAdded) {
      spdlog::info("vehicle {} registered from {}:{}", outcome.vehicle_id, source.address, source.port);
    }
    // Only what came from the vehicle itself is shared: a peer's announcement never goes round again.
    if (peers_)
      peers_->share(datagram, source, now);
    return;
  }
  // A repeated sequence number is what a retransmitting vehicle does, and a signed datagram verified
  // already is also what a vehicle announcing to several RSUs looks like once a peer shared its copy
  // first (README, "Several RSUs on one bus"): counted, not warned about.
  // Nor is an announcement from beyond the verification radius (a vehicle in radio range, out of sight).
  if (outcome.stage == core::DatagramStage::kBeyondVerification ||
      (outcome.stage == core::DatagramStage::kRegistry &&
       outcome.upsert == v2i::UpsertOutcome::kDuplicateSequence) ||
      (outcome.stage == core::DatagramStage::kAuthentication &&
       outcome.auth == v2i::AuthVerdict::kDuplicate)) {
    return;
  }
  std::string detail =
      std::to_string(datagram.size()) + " bytes from " + source.address + ":" + std::to_string(source.port);
  if (outcome.vehicle_id != 0)
    detail += ", vehicle " + std::to_string(outcome.vehicle_id);
  bad_input_.report(outcome.reason(), detail);
}

void RsuDaemon::on_peer_announcement(std::span<const std::uint8_t> datagram,
                                     const core::PeerProvenance& from) {
  if (stopping_)
    return;
  const core::DatagramOutcome outcome = core_.on_peer_announcement(datagram, from, clock_now());
  if (outcome.accepted()) {
    if (outcome.upsert == v2i::UpsertOutcome::kAdded) {
      spdlog::info("vehicle {} registered from RSU {} (it heard the vehicle at {}:{})", outcome.vehicle_id,
                   from.origin_rsu_id, from.sender.address, from.sender.port);
    }
    return;
  }
  // Not news (the vehicle announced here too, or another peer shared it first): counted only.
  if (outcome.stage == core::DatagramStage::kNotFresher ||
      outcome.stage == core::DatagramStage::kBeyondVerification ||
      (outcome.stage == core::DatagramStage::kRegistry &&
       outcome.upsert == v2i::UpsertOutcome::kDuplicateSequence)) {
    return;
  }
  std::string detail = std::to_string(datagram.size()) + " bytes shared by RSU " +
                       std::to_string(from.origin_rsu_id) + " from " + from.sender.address + ":" +
                       std::to_string(from.sender.port);
  if (outcome.stage == core::DatagramStage::kFromSelf)
    detail += ": another RSU on the bus has this RSU's rsu_id (rsu_id must be unique)";
  else if (outcome.vehicle_id != 0)
    detail += ", vehicle " + std::to_string(outcome.vehicle_id);
  bad_input_.report("peer:" + outcome.reason(), detail);
}

// ---- timers ---------------------------------------------------------------------------------------

void RsuDaemon::housekeep(TimeNs now) {
  const std::size_t expired = core_.expire(now);
  if (dds_)
    dds_->forget_quiet_vehicles(now);
  if (expired > 0)
    spdlog::info("{} silent vehicle(s) expired from the registry", expired);
}

void RsuDaemon::on_housekeeping() {
  if (!replaying_)
    housekeep(clock_now());  // a replay does it on the capture's clock (replay_datagram)
  if (peers_ && peers_->peers() != peers_seen_) {
    peers_seen_ = peers_->peers();
    spdlog::info("peer bus: {} other RSU(s) share announcements", peers_seen_);
  }
  bad_input_.maybe_summarize(steady::now());
  if (steady::now() - last_insecure_warning_ >= std::chrono::minutes(1))
    warn_if_insecure();
  // The sensor clock beyond the tolerance: said when it happened (a notice), then once a minute.
  const core::SensorClockReport clock = core_.sensor_clock();
  if (clock.beyond_tolerance && steady::now() - last_clock_warning_ >= std::chrono::minutes(1)) {
    last_clock_warning_ = steady::now();
    std::uint64_t refused = 0;
    for (const auto& [name, value] : core_.counters()) {
      if (name == "packet.clock_offset")
        refused = value;
    }
    spdlog::warn("LiDAR clock still {:.3f} s off the host's (tolerance {} ms): {}",
                 to_seconds(clock.offset_ns), config_.core.clock_tolerance / kNsPerMs,
                 config_.core.time_source == core::TimeSource::kSensor
                     ? std::to_string(refused) + " packets refused so far"
                     : std::string("its points stamped by arrival"));
  }
}

void RsuDaemon::warn_if_insecure() {
  if (config_.core.security.mode != v2i::SecurityMode::kInsecure)
    return;
  last_insecure_warning_ = steady::now();
  spdlog::warn(
      "*** INSECURE MODE: announcements are NOT verified and corrections are NOT signed; anyone "
      "can register any vehicle id and forge or replay messages. For local development only: set "
      "security.mode: signed with key_file and trust_list_file. ***");
}

void RsuDaemon::on_watchdog() {
  notify_watchdog();
}

void RsuDaemon::on_advertise() {
  const std::vector<std::uint8_t> bytes = core_.advertisement(clock_now());
  boost::system::error_code ec;
  const auto address = asio::ip::make_address(config_.advertisement.address, ec);
  if (!ec)
    v2i_socket_.send_to(asio::buffer(bytes), udp::endpoint(address, config_.advertisement.port), 0, ec);
  if (ec) {
    bad_input_.report("advertisement_send", ec.message());
    return;
  }
  ++advertisements_.sent;
  if (core_.fixes_withheld() != v2i::FixesWithheld::kNone)
    ++advertisements_.saying_fixes_withheld;  // the vehicles are told why no corrections come
}

void RsuDaemon::on_stats() {
  log_counters(true);
  warn_of_kernel_drops("V2I", v2i_socket_, v2i_kernel_drops_);
  warn_of_kernel_drops("LiDAR", lidar_socket_, lidar_kernel_drops_);
  write_stats_file();
}

void RsuDaemon::warn_of_kernel_drops(const char* what, udp::socket& socket, std::uint64_t& reported) {
  if (!socket.is_open())
    return;
  const auto drops = kernel_drops(socket.native_handle());
  if (!drops || *drops <= reported)
    return;
  spdlog::warn(
      "{} socket: the kernel dropped {} datagram(s) since the last summary ({} in all): rsud did not "
      "read them in time (raise the receive buffer, or see what kept the loop busy)",
      what, *drops - reported, *drops);
  reported = *drops;
}

void RsuDaemon::log_counters(bool only_nonzero) const {
  std::string line;
  CounterList list;
  core_.report(list);
  for (const Stat& stat : list.stats()) {
    if (stat.kind == StatKind::kMeasured)
      line += fmt::format(" {}={}", stat.name, stat.measured);
    else if (!only_nonzero || stat.count != 0)
      line += fmt::format(" {}={}", stat.name, stat.count);
  }
  spdlog::info("stats: corrections_sent={} correction_sends_failed={}{}", corrections_sent_,
               correction_sends_failed_, line);
  if (dds_)
    spdlog::info("stats: {}", dds_->stats_line());
  if (peers_)
    spdlog::info("stats: {}", peers_->stats_line());
}

CounterList RsuDaemon::stats() {
  CounterList out;
  // A replay's uptime is on the capture's clock, as everything else it writes.
  out.add_measured("", "uptime_s",
                   replaying_ ? to_seconds(clock_now() - clock_started_)
                              : std::chrono::duration<double>(steady::now() - started_).count());
  out.add_level("", "ready", ready_ ? 1 : 0);
  out.add("", "corrections_sent", corrections_sent_);
  out.add("", "correction_sends_failed", correction_sends_failed_);
  out.add("", "lidar_packets_rejected", lidar_packets_rejected_);
  out.add("state", "background_loaded", state_counts_.background_loaded);
  out.add("state", "background_refused", state_counts_.background_refused);
  out.add("state", "background_saved", state_counts_.background_saved);
  out.add("state", "background_save_failed", state_counts_.background_save_failed);
  out.add_level("state", "mount_from_calibration", config_.mount_source != "lidar.mount" ? 1 : 0);
  out.add("", "refusal_sends_failed", refusal_sends_failed_);
  out.add("", "withheld_notice_sends_failed", withheld_notice_sends_failed_);
  out.add("advertisement", "sent", advertisements_.sent);
  out.add("advertisement", "saying_fixes_withheld", advertisements_.saying_fixes_withheld);
  core_.report(out);
  // Datagrams the kernel dropped before rsud could read them (its socket buffer was full): what was
  // sent is what rsud counted plus these.
  report_kernel_drops(out, "v2i", v2i_socket_);
  out.add_level("v2i", "receive_buffer_bytes", v2i_receive_buffer_bytes_);  // as the kernel granted it
  if (v2i_receiver_) {
    // Received but not handed to the core: the loop had stalled with this many waiting.
    out.add("v2i", "receiver_queue_full", v2i_receiver_->dropped_full());
    out.add("v2i", "receiver_errors", v2i_receiver_->receive_errors());
    out.add_level("v2i", "receiver_waiting_max", v2i_receiver_->waiting_max());
  }
  // Rotations the mount check thread dropped unchecked: it lagged 4 rotations behind (starved of CPU).
  out.add("mount", "rotations_dropped_busy", mount_checks_ ? mount_checks_->dropped() : 0);
  // Preparations the preparation thread dropped unrun (8 waiting): their releases computed their fixes.
  out.add("lidar", "preparations_dropped_busy", preparation_ ? preparation_->dropped() : 0);
  report_kernel_drops(out, "lidar", lidar_socket_);
  if (lidar_socket_.is_open())
    out.add_level("lidar", "receive_buffer_bytes", lidar_receive_buffer_bytes_);
  if (capture_) {
    const lidar::PcapSkipped skipped = capture_->skipped();
    out.add("capture", "records", capture_->records());
    out.add("capture", "lidar_datagrams", capture_counts_.lidar_datagrams);
    out.add("capture", "other_datagrams", capture_counts_.other_datagrams);
    out.add("capture", "not_ipv4", skipped.not_ipv4);
    out.add("capture", "not_udp", skipped.not_udp);
    out.add("capture", "fragmented", skipped.fragmented);
    out.add("capture", "malformed", skipped.malformed);
    out.add("capture", "reassembled", capture_->reassembled());
    out.add("capture", "ip_lengths_repaired", capture_->ip_lengths_repaired());
    out.add("capture", "loops", capture_counts_.loops);
    out.add_level("capture", "cut_off", capture_->error() != lidar::PcapError::none ? 1 : 0);
  }
  if (dds_)
    dds_->report(out);
  if (peers_)
    peers_->report(out);
  // The allocator's view of the heap (glibc, every arena and its mmapped blocks): what live allocations
  // hold, and what it holds from the kernel, in use or kept free for reuse. A resident size that steps
  // up while the first stays flat is memory the allocator kept after a peak, not a leak (issue 16, RSS
  // flat under the signed load).
  const struct mallinfo2 heap = mallinfo2();
  out.add_level("process", "heap_in_use_bytes", heap.uordblks + heap.hblkhd);
  out.add_level("process", "heap_held_bytes", heap.arena + heap.hblkhd);
  return out;
}

void RsuDaemon::write_stats_file() {
  if (config_.stats_file.empty())
    return;
  std::ostringstream text;
  const CounterList list = stats();
  for (const Stat& stat : list.stats()) {
    text << stat.name << " ";
    if (stat.kind == StatKind::kMeasured)
      text << stat.measured << "\n";
    else
      text << stat.count << "\n";
  }
  try {
    io::write_file_atomically(config_.stats_file, text.str(), 0644);
  } catch (const io::FileError& e) {
    bad_input_.report("stats_file_write", e.what());
  }
}

void RsuDaemon::on_metrics() {
  write_metrics();
}

void RsuDaemon::write_metrics() {
  if (config_.metrics.textfile.empty())
    return;
  const NamedHistogram histograms[] = {
      {"lidar_step_seconds",
       "Host time rsud's core took for one LiDAR input: a packet, a DDS batch or a whole frame, its "
       "clustering, fits and corrections included",
       &lidar_step_seconds_},
      {"correction_latency_seconds",
       "From the time the LiDAR swept the vehicle to the correction's send (handed to the socket), on the "
       "run's clock",
       &correction_latency_seconds_},
      {"correction_sweep_wait_seconds",
       "Of a correction released by a live LiDAR packet's step: from the time the LiDAR swept the vehicle "
       "to that packet's arrival (the kernel's stamp): the sweep's release rule, the sensor and the wire",
       &correction_sweep_wait_seconds_},
      {"correction_socket_wait_seconds",
       "Of a correction released by a live LiDAR packet's step: that packet's wait in rsud's socket, from "
       "its arrival to rsud's read (behind earlier packets' work)",
       &correction_socket_wait_seconds_},
      {"correction_step_seconds",
       "Of a correction released by a live LiDAR packet's step: from rsud's read of that packet to the "
       "correction's send (handed to the socket)",
       &correction_step_seconds_},
      {"lidar_socket_wait_seconds",
       "Per live LiDAR packet: its wait in rsud's socket, from its arrival (the kernel's stamp) to rsud's "
       "read",
       &lidar_socket_wait_seconds_},
      {"sensor_clock_offset_seconds",
       "The LiDAR's clock behind the host's (host - sensor, transit included), as estimated at each data "
       "packet",
       &sensor_clock_offset_seconds_},
  };
  try {
    io::write_file_atomically(config_.metrics.textfile, prometheus_text(stats(), histograms), 0644);
  } catch (const io::FileError& e) {
    bad_input_.report("metrics_write", e.what());
  }
}

void RsuDaemon::report_kernel_drops(CounterList& out, const char* area, udp::socket& socket) {
  if (!socket.is_open())
    return;
  if (const auto drops = kernel_drops(socket.native_handle()))
    out.add(area, "kernel_drops", *drops);
}

// ---- signals --------------------------------------------------------------------------------------

void RsuDaemon::on_signal(int signal_number) {
  if (signal_number == SIGHUP) {
    reload();
    signals_.async_wait([this](const boost::system::error_code& ec, int n) {
      if (!ec)
        on_signal(n);
    });
    return;
  }
  spdlog::info("{} received: draining", signal_number == SIGTERM ? "SIGTERM" : "SIGINT");
  drain_and_stop();
}

void RsuDaemon::reload() {
  notify_reloading();
  spdlog::info("SIGHUP: reloading {}", source_.path);
  try {
    DaemonConfig next = load_config(source_);
    const core::ReloadSummary summary = core_.reload(next.core, clock_now());
    spdlog::info("configuration reloaded: {} of {} registered vehicle(s) kept, background {}",
                 summary.vehicles_after, summary.vehicles_before,
                 summary.background_kept ? "kept" : "to be learned again");
    spdlog::info("security {}: trust list of {} key(s) in effect", v2i::to_string(next.core.security.mode),
                 next.core.trust_list.size());
    const bool inputs_changed =
        next.v2i_listen_address != config_.v2i_listen_address || next.v2i_port != config_.v2i_port ||
        next.v2i_verifier_thread != config_.v2i_verifier_thread ||
        next.mount_check_thread != config_.mount_check_thread ||
        next.prepare_thread != config_.prepare_thread || next.input.index() != config_.input.index() ||
        next.dds.enabled != config_.dds.enabled || next.dds.peers.enabled != config_.dds.peers.enabled ||
        next.dds.peers.topic != config_.dds.peers.topic ||
        (std::holds_alternative<UdpInput>(next.input) &&
         (std::get<UdpInput>(next.input).port != std::get<UdpInput>(config_.input).port ||
          std::get<UdpInput>(next.input).bind_address != std::get<UdpInput>(config_.input).bind_address));
    if (inputs_changed)
      spdlog::warn("socket addresses or the LiDAR input changed: they take effect after a restart");
    // Sockets, input and the DDS participant stay as they are; everything else follows the new file.
    next.input = config_.input;
    next.dds = config_.dds;
    next.v2i_listen_address = config_.v2i_listen_address;
    next.v2i_port = config_.v2i_port;
    next.v2i_verifier_thread = config_.v2i_verifier_thread;
    next.mount_check_thread = config_.mount_check_thread;
    next.prepare_thread = config_.prepare_thread;
    config_ = std::move(next);
    if (v2i_receiver_)
      v2i_receiver_->set_trust(config_.core.security.mode == v2i::SecurityMode::kSigned,
                               config_.core.trust_list, receiver_time_window(),
                               core::announcement_security(config_.core).verify_within);
    spdlog::set_level(spdlog::level::from_str(config_.logging.level));
    bad_input_.set_limits(config_.logging.bad_input_log_first, seconds(config_.logging.summary_interval_s));
    warn_if_insecure();
    if (!summary.background_kept && !config_.background_pcd_files.empty())
      load_background_pcd();
    else if (!summary.background_kept)
      load_saved_background();
    if (config_.mount_source != "lidar.mount")
      spdlog::info("LiDAR mount from {}", config_.mount_source);
    for (const std::string& warning : config_.state_warnings)
      spdlog::warn("state directory: {}", warning);
    if (!core_.background_ready()) {
      ready_ = false;
      spdlog::info("learning the background again from {} whole rotations",
                   config_.core.background.learning_frames);
    }
  } catch (const std::exception& e) {
    spdlog::error("reload rejected, keeping the previous configuration: {}", e.what());
  }
  // Tell systemd the reload is over either way (it waits for READY=1 after RELOADING=1).
  notify_ready();
}

void RsuDaemon::drain_and_stop() {
  if (stopping_)
    return;
  stopping_ = true;
  notify_stopping();
  // Pending clusters (a vehicle the sweep was still on) are corrected and sent now, not lost.
  const core::LidarStepResult last = core_.flush(clock_now());
  send_corrections(last.corrections);
  send_withheld_notices(last.withheld_notices);
  log_counters(true);
  write_stats_file();
  write_metrics();
  spdlog::info("stopped: {} corrections sent ({} drained at shutdown)", corrections_sent_,
               last.corrections.size());
  boost::system::error_code ignored;
  signals_.cancel(ignored);
  if (v2i_receiver_)
    v2i_receiver_->stop();  // before its socket is closed
  v2i_socket_.close(ignored);
  lidar_socket_.close(ignored);
  auxiliary_socket_.close(ignored);
  for (auto* t : {&housekeeping_timer_, &watchdog_timer_, &advertise_timer_, &stats_timer_, &input_timer_,
                  &object_list_timer_, &metrics_timer_})
    t->cancel();
  exit_code_ = 0;
  io_.stop();
}

}  // namespace rsu::daemon
