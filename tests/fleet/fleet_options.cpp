// SPDX-License-Identifier: Apache-2.0
#include "tests/fleet/fleet_options.h"

#include <arpa/inet.h>

#include <boost/program_options.hpp>

#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <sstream>
#include <stdexcept>

namespace rsu::fleet {
namespace po = boost::program_options;

namespace {

std::uint32_t ipv4(const std::string& text, const char* option) {
  in_addr a{};
  if (inet_pton(AF_INET, text.c_str(), &a) != 1)
    throw std::runtime_error(std::string(option) + ": \"" + text + "\" is not an IPv4 address");
  return ntohl(a.s_addr);
}

std::vector<std::string> split(const std::string& text, char separator) {
  std::vector<std::string> parts;
  std::stringstream in(text);
  for (std::string part; std::getline(in, part, separator);)
    parts.push_back(part);
  return parts;
}

double number(const std::string& text, const char* option) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || end == nullptr || *end != '\0')
    throw std::runtime_error(std::string(option) + ": \"" + text + "\" is not a number");
  return v;
}

std::uint32_t vehicle_id(const std::string& text, const char* option) {
  const double v = number(text, option);
  if (!(v >= 1 && v <= 4294967295.0) || v != static_cast<double>(static_cast<std::uint32_t>(v)))
    throw std::runtime_error(std::string(option) + ": \"" + text + "\" is not a vehicle id");
  return static_cast<std::uint32_t>(v);
}

v2i::BoxSize box_size(const std::string& text, const char* option) {
  const auto parts = split(text, ',');
  if (parts.size() != 3)
    throw std::runtime_error(std::string(option) + ": expected L,W,H, got \"" + text + "\"");
  return {number(parts[0], option), number(parts[1], option), number(parts[2], option)};
}

}  // namespace

FleetOptions parse_fleet_options(int argc, char** argv) {
  po::options_description options(
      "rsu-fleet --rsu IP:PORT --scenario FILE --epoch-ns NS [options]\n"
      "A fleet of connected vehicles in one process, for load, fault and association tests: the\n"
      "scenario's vehicles announce their true poses (moved by --pose-error-m) at the common clock,\n"
      "synthetic ones (--extra) announce static poses beyond the LiDAR's coverage. Vehicle k sends from\n"
      "its own socket on address base + k and receives its corrections there. Prints a summary line.\n"
      "Options");
  options.add_options()("help,h", "show this help")("rsu", po::value<std::string>(), "rsud's V2I IP:PORT")(
      "scenario", po::value<std::string>(), "scenario YAML file (as streamed by rsu-sim stream)")(
      "epoch-ns", po::value<long long>(), "host-clock time of scenario time 0 (as given to rsu-sim stream)")(
      "connected", po::value<std::string>(),
      "comma-separated scenario vehicle ids that announce (default: all)")(
      "extra", po::value<int>()->default_value(0),
      "synthetic vehicles beyond the coverage (ids from 100001)")(
      "rate-hz", po::value<double>()->default_value(10.0), "announcements per second per vehicle")(
      "seconds", po::value<double>()->default_value(10.0), "how long to run")(
      "address-base", po::value<std::string>()->default_value("127.1.0.1"),
      "vehicle k binds to this IPv4 address + k (loopback: any 127.x.y.z works)")(
      "clock-offset-ms", po::value<double>()->default_value(0.0),
      "the vehicles' clock error: added to every generation time")(
      "pose-error-m", po::value<double>()->default_value(0.3),
      "the announced pose is the truth moved by this much along +x and -y")(
      "size", po::value<std::vector<std::string>>(), "ID:L,W,H announced instead of the scenario's shape")(
      "size-change", po::value<std::vector<std::string>>(),
      "ID:AT_S:L,W,H announce this size from scenario time AT_S on")(
      "corrections", po::value<std::string>(), "file: one line per correction received")(
      "signed", po::value<std::string>(),
      "TRUST_LIST: sign every announcement with the vehicle's own test key (derived from its id and "
      "--key-seed: tests only) and write the vehicles' trust list to TRUST_LIST first")(
      "key-seed", po::value<unsigned long long>()->default_value(1), "seed of the derived test keys")(
      "write-trust-list-only", "with --signed: write the trust list and exit (before rsud reads it)");
  po::variables_map vm;
  po::store(po::parse_command_line(argc, argv, options), vm);
  po::notify(vm);
  if (vm.count("help")) {
    std::cout << options;
    std::exit(0);
  }
  FleetOptions o;
  if (!vm.count("rsu") || !vm.count("scenario") || !vm.count("epoch-ns"))
    throw std::runtime_error("--rsu, --scenario and --epoch-ns are required (see --help)");
  const std::string rsu = vm["rsu"].as<std::string>();
  const auto colon = rsu.rfind(':');
  if (colon == std::string::npos)
    throw std::runtime_error("--rsu must be IP:PORT");
  ipv4(rsu.substr(0, colon), "--rsu");
  o.rsu_address = rsu.substr(0, colon);
  const double port = number(rsu.substr(colon + 1), "--rsu");
  if (!(port >= 1 && port <= 65535))
    throw std::runtime_error("--rsu: port out of range");
  o.rsu_port = static_cast<std::uint16_t>(port);
  o.scenario = vm["scenario"].as<std::string>();
  o.epoch_ns = static_cast<TimeNs>(vm["epoch-ns"].as<long long>());
  if (vm.count("connected")) {
    for (const std::string& id : split(vm["connected"].as<std::string>(), ','))
      o.connected.push_back(vehicle_id(id, "--connected"));
  }
  o.extra_vehicles = vm["extra"].as<int>();
  o.rate_hz = vm["rate-hz"].as<double>();
  o.seconds = vm["seconds"].as<double>();
  if (o.extra_vehicles < 0 || o.extra_vehicles > 100000)
    throw std::runtime_error("--extra must be within [0, 100000]");
  if (!(o.rate_hz > 0 && o.rate_hz <= 100))
    throw std::runtime_error("--rate-hz must be within (0, 100]");
  if (!(o.seconds > 0 && o.seconds <= 3600))
    throw std::runtime_error("--seconds must be within (0, 3600]");
  o.address_base = ipv4(vm["address-base"].as<std::string>(), "--address-base");
  o.clock_offset_ns = from_seconds(vm["clock-offset-ms"].as<double>() * 1e-3);
  o.pose_error_m = vm["pose-error-m"].as<double>();
  if (vm.count("size")) {
    for (const std::string& s : vm["size"].as<std::vector<std::string>>()) {
      const auto parts = split(s, ':');
      if (parts.size() != 2)
        throw std::runtime_error("--size: expected ID:L,W,H, got \"" + s + "\"");
      o.announced_size[vehicle_id(parts[0], "--size")] = box_size(parts[1], "--size");
    }
  }
  if (vm.count("size-change")) {
    for (const std::string& s : vm["size-change"].as<std::vector<std::string>>()) {
      const auto parts = split(s, ':');
      if (parts.size() != 3)
        throw std::runtime_error("--size-change: expected ID:AT_S:L,W,H, got \"" + s + "\"");
      o.size_change[vehicle_id(parts[0], "--size-change")] = {from_seconds(number(parts[1], "--size-change")),
                                                              box_size(parts[2], "--size-change")};
    }
  }
  if (vm.count("corrections"))
    o.corrections_path = vm["corrections"].as<std::string>();
  if (vm.count("signed"))
    o.trust_list_path = vm["signed"].as<std::string>();
  o.key_seed = vm["key-seed"].as<unsigned long long>();
  o.write_trust_list_only = vm.count("write-trust-list-only") > 0;
  if (o.write_trust_list_only && o.trust_list_path.empty())
    throw std::runtime_error("--write-trust-list-only needs --signed TRUST_LIST");
  return o;
}

}  // namespace rsu::fleet
