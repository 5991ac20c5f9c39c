// SPDX-License-Identifier: Apache-2.0
// rsud's run time: a thin Boost.Asio shell around core::RsuCore (lib/core). One io_context on one
// thread, which alone touches RsuCore; worker threads (worker_thread.h): the mount check (it registers
// each rotation against the mount's immutable reference) and with perception.prepare_thread the
// preparation of fits and fixes ahead of their release (core::prepare); and with v2i.verifier_thread the V2I
// receiver thread (v2i_receiver.h: it reads the announcement socket and checks signatures ahead). The
// io_context has: sockets (V2I announcements in / corrections out, Velodyne packets in), timers (registry
// expiry, watchdog, advertisement, log summaries, PCD replay pacing) and signals (SIGHUP reload, SIGTERM /
// SIGINT drain). Everything it decides is RsuCore's; this file only moves bytes, reads the clock and logs.
#pragma once

#include <utility>  // before Asio: Boost 1.74's awaitable.hpp uses std::exchange under C++20

#include <boost/asio.hpp>

#include <array>
#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <ostream>
#include <span>
#include <string>
#include <vector>

#include "common/counter_list.h"
#include "common/histogram.h"
#include "core/rsu_core.h"
#include "daemon/bad_input_log.h"
#include "daemon/config.h"
#include "io/capture_file.h"
#include "lidar/sensor_model.h"

namespace rsu::daemon {

class DdsEdge;
class PeerBus;
template <class Job, class Result>
class WorkerThread;
class V2iReceiver;

class RsuDaemon {
 public:
  // `source` is read again on SIGHUP.
  RsuDaemon(boost::asio::io_context& io, DaemonConfig config, ConfigSource source);
  ~RsuDaemon();

  // Binds the sockets, loads the background (if configured) and arms the timers and signals. Throws
  // std::runtime_error with a message fit for the log (e.g. the port is in use, a PCD file is missing).
  void start();
  int exit_code() const { return exit_code_; }

 private:
  using udp = boost::asio::ip::udp;
  using steady = std::chrono::steady_clock;

  void receive_v2i();
  // The announcement socket read by the receiver thread (v2i.verifier_thread) or by receive_v2i().
  void start_v2i_reception();
  // Datagrams the receiver thread handed over: a bounded batch per turn, so that LiDAR packets interleave.
  void on_v2i_arrival();
  // Receives the LiDAR's datagrams on `socket` (the data port, or the auxiliary one) into `buffer`.
  void receive_lidar(udp::socket& socket, std::array<std::uint8_t, 65536>& buffer, udp::endpoint& sender);
  // One datagram of the LiDAR, live or replayed, arrived at `arrival` (the run's clock).
  void on_lidar_payload(std::span<const std::uint8_t> payload, TimeNs arrival, const std::string& from);
  // `received`: the kernel's stamp of its arrival (udp_socket.h), if any.
  void on_v2i_datagram(std::span<const std::uint8_t> datagram, const udp::endpoint& sender,
                       const v2i::SignatureCheck* checked, std::optional<TimeNs> received);
  void on_peer_announcement(std::span<const std::uint8_t> datagram, const core::PeerProvenance& from);
  void handle_lidar_result(const core::LidarStepResult& result);
  // RsuCore's pending preparation (fits and fixes ahead of their release) to its thread.
  void submit_preparation();
  void send_corrections(const std::vector<core::OutgoingCorrection>& corrections);
  void send_withheld_notices(const std::vector<core::OutgoingNotice>& notices);
  // One datagram to a vehicle; a failure is reported as `what` (rate-limited) and returns false.
  bool send_to_vehicle(const v2i::UdpEndpoint& destination, std::span<const std::uint8_t> bytes,
                       const std::string& what);
  void become_ready_if_possible();

  void every(boost::asio::steady_timer& timer, steady::duration period, void (RsuDaemon::*tick)());
  void on_housekeeping();
  void on_watchdog();
  void on_advertise();
  void on_stats();
  void on_pcd_frame();
  void on_object_list();
  void start_dds();

  void start_input();
  // Capture replay (lidar.input.pcap): the run's clock is the capture's (file comment of config.h).
  void start_capture();
  void replay_step();
  void replay_datagram(const lidar::UdpDatagram& datagram);
  bool next_capture_datagram();
  void finish_capture();
  // What the periodic housekeeping does that changes the output (registry expiry, DDS bookkeeping):
  // on the host's timer, or on the capture's clock during a replay so that a replay stays the same.
  void housekeep(TimeNs now);
  void load_background_pcd();
  // The state directory (io/background_state.h): the background an earlier run learned, loaded when it
  // belongs to this sensor and mount; saved when learning ends.
  void load_saved_background();
  void save_learned_background();
  void on_signal(int signal_number);
  void reload();
  void drain_and_stop();
  // Everything rsud counts and measures, in one list (the stats file and the metrics print it).
  CounterList stats();
  void write_stats_file();
  void write_metrics();
  void on_metrics();
  // A LiDAR input step through the core, its processing time observed.
  template <typename Step>
  core::LidarStepResult timed(Step step);
  static void warn_of_kernel_drops(const char* what, boost::asio::ip::udp::socket& socket,
                                   std::uint64_t& reported);
  static void report_kernel_drops(CounterList& out, const char* area, boost::asio::ip::udp::socket& socket);
  // The run's clock: the host's, or during a capture replay the capture's.
  TimeNs clock_now() const;
  // The time window the V2I receiver thread checks ahead within (none while replaying a capture).
  std::optional<v2i::security::ReplayConfig> receiver_time_window() const;
  void log_counters(bool only_nonzero) const;
  // Insecure mode is for local development only: said loudly at start-up and every minute after.
  void warn_if_insecure();

  boost::asio::io_context& io_;
  DaemonConfig config_;
  ConfigSource source_;
  core::RsuCore core_;
  BadInputLog bad_input_;

  udp::socket v2i_socket_;
  udp::socket lidar_socket_;
  udp::socket auxiliary_socket_;  // the LiDAR's packets without points (Velodyne position packets)
  std::array<std::uint8_t, 65536> v2i_buffer_{};  // any UDP datagram fits: truncation cannot happen
  std::array<std::uint8_t, 65536> lidar_buffer_{};
  std::array<std::uint8_t, 65536> auxiliary_buffer_{};
  udp::endpoint v2i_sender_;
  udp::endpoint lidar_sender_;
  udp::endpoint auxiliary_sender_;

  boost::asio::signal_set signals_;
  boost::asio::steady_timer housekeeping_timer_;
  boost::asio::steady_timer watchdog_timer_;
  boost::asio::steady_timer advertise_timer_;
  boost::asio::steady_timer stats_timer_;
  boost::asio::steady_timer input_timer_;
  boost::asio::steady_timer object_list_timer_;
  boost::asio::steady_timer metrics_timer_;

  std::optional<lidar::SensorModel> sensor_model_;  // the Velodyne tables in use (none for other sensors)
  std::unique_ptr<V2iReceiver> v2i_receiver_;       // when v2i.verifier_thread (after the socket it reads)
  // Live input: the mount check, and the preparation of fits and fixes, off the loop (worker_thread.h).
  std::unique_ptr<WorkerThread<core::MountRotations, core::MountChecks>> mount_checks_;
  std::unique_ptr<WorkerThread<core::Preparation, core::Prepared>> preparation_;
  std::unique_ptr<DdsEdge> dds_;    // when dds.enabled (after bad_input_: it reports there)
  std::unique_ptr<PeerBus> peers_;  // when dds.peers.enabled (after dds_: it uses its participant)
  std::uint32_t peers_seen_ = 0;    // other RSUs on the peer bus at the last housekeeping

  struct StateCounts {
    std::uint64_t background_loaded = 0;
    std::uint64_t background_refused = 0;  // unusable, or another sensor or mount: learned again
    std::uint64_t background_saved = 0;
    std::uint64_t background_save_failed = 0;
  };
  StateCounts state_counts_;
  struct AdvertisementCounts {
    std::uint64_t sent = 0;
    std::uint64_t saying_fixes_withheld = 0;  // of them, those that said fixes are withheld (and why)
  };
  AdvertisementCounts advertisements_;

  // PCD replay
  std::vector<std::vector<lidar::LidarPoint>> pcd_frames_;
  std::size_t next_pcd_frame_ = 0;
  // Capture replay
  struct CaptureCounts {
    std::uint64_t lidar_datagrams = 0;  // to the sensor's ports: given to the decoder
    std::uint64_t other_datagrams = 0;  // to any other port: counted only
    std::uint64_t loops = 0;
  };
  std::unique_ptr<io::CaptureFile> capture_;
  std::optional<lidar::UdpDatagram> capture_next_;  // read, not yet replayed (recorded pace)
  std::uint16_t capture_data_port_ = 0;
  std::uint16_t capture_auxiliary_port_ = 0;
  CaptureCounts capture_counts_;
  bool replaying_ = false;
  TimeNs replay_now_ = 0;            // the capture's clock: the replayed record's time + replay_shift_
  TimeNs replay_shift_ = 0;          // whole hours added per loop, so that time never runs backwards
  TimeNs capture_first_ns_ = 0;      // the first record of the current pass (recorded pace)
  TimeNs capture_last_ns_ = 0;       // the last record replayed
  steady::time_point pass_started_;  // host time the current pass began (recorded pace)
  TimeNs next_replay_housekeeping_ = 0;
  TimeNs clock_started_ = 0;  // the run's clock at start (uptime)

  bool ready_ = false;
  bool stopping_ = false;
  int exit_code_ = 0;
  std::uint64_t corrections_sent_ = 0;
  std::uint64_t correction_sends_failed_ = 0;
  std::uint64_t lidar_packets_rejected_ = 0;
  std::uint64_t refusal_sends_failed_ = 0;
  std::uint64_t withheld_notice_sends_failed_ = 0;
  // The metrics' histograms (seconds). Bounds: a packet takes microseconds, a batch that fits vehicles
  // milliseconds; a correction leaves well within a rotation (0.1 s) of its sweep; a sensor on the
  // host's clock is behind by its transit (sub-millisecond), one that is not by anything.
  static std::vector<double> latency_bounds() {
    return {1e-4, 2.5e-4, 5e-4, 1e-3, 2e-3, 3e-3, 4e-3, 5e-3, 7.5e-3,
            0.01, 0.02,   0.03, 0.05, 0.1,  0.2,  0.5,  1.0};
  }
  Histogram lidar_step_seconds_{
      {1e-5, 2.5e-5, 5e-5, 1e-4, 2.5e-4, 5e-4, 1e-3, 2.5e-3, 5e-3, 0.01, 0.025, 0.05, 0.1, 0.25, 1.0}};
  // Its buckets are fine around the 5 ms that correction latency is judged by (issue 16), and so are its
  // three parts' from a live LiDAR packet (the correction_* below; they add up to it): the sweep's
  // release rule and the sensor, the packet's wait in the socket behind the loop, rsud's step and send.
  Histogram correction_latency_seconds_{latency_bounds()};
  Histogram correction_sweep_wait_seconds_{latency_bounds()};
  Histogram correction_socket_wait_seconds_{latency_bounds()};
  Histogram correction_step_seconds_{latency_bounds()};
  Histogram lidar_socket_wait_seconds_{latency_bounds()};
  Histogram sensor_clock_offset_seconds_{{-1.0, -0.1, -0.01, -0.005, -0.002, -0.001, -5e-4, -1e-4, 0.0, 1e-4,
                                          5e-4, 1e-3, 2e-3, 5e-3, 0.01, 0.1, 1.0}};
  // The live LiDAR packet being stepped: its arrival, stamped by the kernel, and when rsud read it.
  struct PacketTimes {
    TimeNs arrival = 0;
    TimeNs read = 0;
  };
  std::optional<PacketTimes> stepped_packet_;
  std::uint64_t v2i_kernel_drops_ = 0;  // as last warned about
  std::uint64_t lidar_kernel_drops_ = 0;
  // The receive buffers the kernel granted (request_receive_buffer; 0: not read back).
  std::size_t v2i_receive_buffer_bytes_ = 0;
  std::size_t lidar_receive_buffer_bytes_ = 0;
  steady::time_point started_ = steady::now();
  steady::time_point last_insecure_warning_{};
  steady::time_point last_clock_warning_{};
};

}  // namespace rsu::daemon
