// rsud's run time: a thin Boost.Asio shell around core::RsuCore (lib/rsu). One thread, one
// io_context: sockets (V2I announcements in / corrections out, Velodyne packets in), timers (registry
// expiry, watchdog, advertisement, log summaries, PCD replay / simulator pacing) and signals (SIGHUP
// reload, SIGTERM / SIGINT drain). Everything it decides is RsuCore's; this file only moves bytes,
// reads the clock and logs.
#pragma once

#include <utility>  // before Asio: Boost 1.74's awaitable.hpp uses std::exchange under C++20

#include <boost/asio.hpp>

#include <array>
#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "daemon/bad_input_log.h"
#include "daemon/config.h"
#include "lidar/sensor_model.h"
#include "rsu/rsu_core.h"

namespace rsu::sim {
class LidarSimulator;
struct Scenario;
}  // namespace rsu::sim

namespace rsu::daemon {

class DdsEdge;
class PeerBus;

class RsuDaemon {
 public:
  // `config_path` is re-read on SIGHUP.
  RsuDaemon(boost::asio::io_context& io, DaemonConfig config, std::string config_path);
  ~RsuDaemon();

  // Binds the sockets, loads the background (if configured) and arms the timers and signals. Throws
  // std::runtime_error with a message fit for the log (e.g. the port is in use, a PCD file is missing).
  void start();
  int exit_code() const { return exit_code_; }

 private:
  using udp = boost::asio::ip::udp;
  using steady = std::chrono::steady_clock;

  void receive_v2i();
  void receive_lidar();
  void on_v2i_datagram(std::size_t bytes);
  void on_peer_announcement(std::span<const std::uint8_t> datagram, const core::PeerProvenance& from);
  void handle_lidar_result(const core::LidarStepResult& result);
  void send_corrections(const std::vector<core::OutgoingCorrection>& corrections);
  void become_ready_if_possible();

  void every(boost::asio::steady_timer& timer, steady::duration period, void (RsuDaemon::*tick)());
  void on_housekeeping();
  void on_watchdog();
  void on_advertise();
  void on_stats();
  void on_pcd_frame();
  void on_simulator_tick();
  void on_object_list();
  void start_dds();

  void start_input();
  void load_background_pcd();
  void start_simulator();
  void on_signal(int signal_number);
  void reload();
  void drain_and_stop();
  void write_stats_file() const;
  void log_counters(bool only_nonzero) const;
  // Insecure mode is for local development only: said loudly at start-up and every minute after.
  void warn_if_insecure();

  boost::asio::io_context& io_;
  DaemonConfig config_;
  std::string config_path_;
  core::RsuCore core_;
  BadInputLog bad_input_;

  udp::socket v2i_socket_;
  udp::socket lidar_socket_;
  std::array<std::uint8_t, 65536> v2i_buffer_{};  // any UDP datagram fits: truncation cannot happen
  std::array<std::uint8_t, 65536> lidar_buffer_{};
  udp::endpoint v2i_sender_;
  udp::endpoint lidar_sender_;

  boost::asio::signal_set signals_;
  boost::asio::steady_timer housekeeping_timer_;
  boost::asio::steady_timer watchdog_timer_;
  boost::asio::steady_timer advertise_timer_;
  boost::asio::steady_timer stats_timer_;
  boost::asio::steady_timer input_timer_;
  boost::asio::steady_timer object_list_timer_;

  std::optional<SensorModel> sensor_model_;  // the Velodyne tables in use (none for other sensors)
  std::unique_ptr<DdsEdge> dds_;             // when dds.enabled (after bad_input_: it reports there)
  std::unique_ptr<PeerBus> peers_;           // when dds.peers.enabled (after dds_: it uses its participant)
  std::uint32_t peers_seen_ = 0;             // other RSUs on the peer bus at the last housekeeping

  // PCD replay
  std::vector<std::vector<LidarPoint>> pcd_frames_;
  std::size_t next_pcd_frame_ = 0;
  // Simulator input
  std::unique_ptr<sim::Scenario> scenario_;
  std::unique_ptr<sim::LidarSimulator> simulator_;
  std::int64_t next_sim_packet_ = 0;
  TimeNs sim_clock_offset_ = 0;

  bool ready_ = false;
  bool stopping_ = false;
  int exit_code_ = 0;
  std::uint64_t corrections_sent_ = 0;
  std::uint64_t correction_sends_failed_ = 0;
  std::uint64_t lidar_packets_rejected_ = 0;
  steady::time_point started_ = steady::now();
  steady::time_point last_insecure_warning_{};
};

}  // namespace rsu::daemon
