// SPDX-License-Identifier: Apache-2.0
// rsud: the roadside-unit daemon. Localizes announced connected vehicles with the roadside LiDAR and
// sends them corrections (docs/design.md §1, issue #4). See --help; deploy/ holds the systemd unit and an
// example configuration.
#include <utility>  // before Asio: Boost 1.74's awaitable.hpp uses std::exchange under C++20

#include <spdlog/spdlog.h>
#include <boost/asio.hpp>
#include <boost/program_options.hpp>

#include <exception>
#include <filesystem>
#include <iostream>
#include <variant>

#include "core/rsu_core.h"
#include "daemon/config.h"
#include "daemon/logging.h"
#include "daemon/rsu_daemon.h"
#include "edge/address_text.h"
#include "io/capture_file.h"

#ifndef RSUD_VERSION
#define RSUD_VERSION "unknown"
#endif

namespace {

namespace po = boost::program_options;

// Everything --check-config can verify without binding sockets: the file, the combination (RsuCore
// accepts it), the addresses and that the files it names exist.
void check_config(const rsu::daemon::DaemonConfig& config) {
  const rsu::core::RsuCore core(config.core);  // throws std::invalid_argument when unusable
  auto check_address = [&](const std::string& text, const std::string& field) {
    rsu::edge::parse_ip_address(text, config.source + ": " + field);
  };
  check_address(config.v2i_listen_address, "v2i.listen_address");
  if (config.advertisement.enabled)
    check_address(config.advertisement.address, "v2i.advertisement.address");
  auto check_file = [&](const std::string& path, const std::string& field) {
    if (!std::filesystem::is_regular_file(path)) {
      throw std::runtime_error(config.source + ": " + field + ": no such file: " + path);
    }
  };
  for (const auto& f : config.background_pcd_files)
    check_file(f, "background.pcd_files");
  if (const auto* u = std::get_if<rsu::daemon::UdpInput>(&config.input)) {
    check_address(u->bind_address, "lidar.input.udp.bind_address");
  } else if (const auto* c = std::get_if<rsu::daemon::PcapInput>(&config.input)) {
    try {
      const rsu::io::CaptureFile capture(c->file);  // a missing, pcapng or foreign file is named
    } catch (const rsu::io::CaptureError& e) {
      throw std::runtime_error(config.source + ": lidar.input.pcap: " + e.what());
    }
  } else if (const auto* p = std::get_if<rsu::daemon::PcdInput>(&config.input)) {
    for (const auto& f : p->files)
      check_file(f, "lidar.input.pcd.files");
  }
}

}  // namespace

int main(int argc, char** argv) {
  po::options_description options(
      "rsud [options]\n\nRoadside-unit daemon: corrects announced vehicles' poses "
      "with the roadside LiDAR.\n\nOptions");
  options.add_options()("help,h", "show this help and exit")("version", "print the version and exit")(
      "config,c", po::value<std::string>()->default_value("/etc/rsud/rsud.yaml"),
      "configuration file (YAML)")(
      "check-config", "parse and validate the configuration, print a summary, exit 0 (valid) or 1")(
      "key", po::value<std::string>()->value_name("FILE"),
      "the RSU's secret key file, instead of security.key_file (the shipped systemd unit passes the "
      "credential it loaded: --key %d/rsu.key)");
  po::variables_map vm;
  try {
    po::store(po::parse_command_line(argc, argv, options), vm);
    po::notify(vm);
  } catch (const std::exception& e) {
    std::cerr << "rsud: " << e.what() << "\n" << options;
    return 2;
  }
  if (vm.count("help")) {
    std::cout << options;
    return 0;
  }
  if (vm.count("version")) {
    std::cout << "rsud " << RSUD_VERSION << "\n";
    return 0;
  }
  rsu::daemon::ConfigSource source{vm["config"].as<std::string>(), {}};
  if (vm.count("key"))
    source.key_file = vm["key"].as<std::string>();
  const std::string& path = source.path;

  rsu::daemon::DaemonConfig config;
  try {
    config = rsu::daemon::load_config(source);
    if (vm.count("check-config")) {
      check_config(config);
      std::cout << path << ": OK\n" << rsu::daemon::summarize(config);
      return 0;
    }
  } catch (const std::exception& e) {
    std::cerr << "rsud: configuration error: " << e.what() << "\n";
    return 1;
  }

  rsu::daemon::setup_logging(config.logging.level);
  spdlog::info("rsud {} starting with {}", RSUD_VERSION, path);
  {
    const std::string summary = rsu::daemon::summarize(config);
    std::size_t start = 0;
    while (start < summary.size()) {
      const std::size_t end = summary.find('\n', start);
      spdlog::info("  {}", summary.substr(start, end - start));
      start = end == std::string::npos ? summary.size() : end + 1;
    }
  }
  try {
    boost::asio::io_context io;
    rsu::daemon::RsuDaemon daemon(io, std::move(config), source);
    daemon.start();
    io.run();
    return daemon.exit_code();
  } catch (const std::exception& e) {
    spdlog::critical("{}", e.what());
    return 1;
  }
}
