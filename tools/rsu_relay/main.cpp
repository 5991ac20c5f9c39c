// SPDX-License-Identifier: Apache-2.0
// rsu-relay: the V2I link between a vehicle and its RSUs, on loopback, made as bad as a radio link can
// be (delay, jitter, loss, reordering, each direction, seeded) or as a faulty RSU would make it
// (corrections biased, overconfident, or another vehicle's, signed again with the RSU's key). Neither
// rsud nor rsu-vehicle is changed for it: the vehicle announces to the relay and names the relay's
// address as the one to answer to.
#include <utility>  // before Asio: Boost 1.74's awaitable.hpp uses std::exchange under C++20

#include <boost/asio/io_context.hpp>
#include <boost/asio/signal_set.hpp>
#include <boost/program_options.hpp>

#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>

#include "edge/address_text.h"
#include "io/text_file.h"
#include "tools/cli/version.h"
#include "tools/rsu_relay/relay.h"
#include "v2i/security/key_text.h"

namespace rsu::tools {
namespace {

namespace po = boost::program_options;

constexpr const char* kAbout =
    "rsu-relay: relays V2I datagrams between a vehicle and its RSUs (loopback tests and experiments),\n"
    "impairing the link and, if asked, tampering with the corrections.\n"
    "\n"
    "usage: rsu-relay --vehicle ADDR:PORT --listen ADDR:PORT --rsu HOST:PORT [--listen .. --rsu ..]\n"
    "                 [--rsu-side ADDR] [impairments] [faults] [--rsu-key RSU.key | --insecure]\n"
    "\n"
    "The vehicle announces to --listen instead of the RSU (the i-th --listen relays to the i-th --rsu)\n"
    "and is started with --reply-address equal to --rsu-side (default 127.0.0.2). The\n"
    "relay binds that address at the vehicle's own port (from --vehicle), sends the announcements to the\n"
    "RSU from there, so that rsud (which answers only to the address an announcement came from) sends its\n"
    "corrections back to the relay, which passes them on to --vehicle. Use two loopback addresses, e.g.\n"
    "the vehicle on 127.0.0.1 and the relay on 127.0.0.2.\n"
    "\n"
    "Impairments (uplink: vehicle -> RSU, downlink: RSU -> vehicle; the plain option sets both, the\n"
    "--uplink-/--downlink- one overrides it): a fixed delay plus a uniform jitter within +-jitter, a\n"
    "fraction lost, a fraction held back and sent after the next datagram of that direction (or after\n"
    "100 ms if none comes). Every draw is keyed by --seed, the direction and the datagram's index.\n"
    "\n"
    "Faults (downlink corrections swept at or after --tamper-from-ns): a position bias, a scaled\n"
    "covariance, bursts of another vehicle's pose. Corrections are then all signed again with --rsu-key\n"
    "(the RSU's secret key, which a test owns), at the RSU's own generation time.\n"
    "\n"
    "Runs until SIGINT or SIGTERM, then prints its counters (and writes --stats FILE) and exits 0.\n"
    "Exit 2 on a usage error.\n"
    "\n"
    "options";

struct Options {
  RelayConfig relay;
  std::string stats_path;
};

double fraction(const po::variables_map& vm, const std::string& name) {
  const double v = vm[name].as<double>();
  if (!(v >= 0.0 && v < 1.0)) {
    throw po::error("--" + name + " must be within [0, 1)");
  }
  return v;
}

double non_negative(const po::variables_map& vm, const std::string& name) {
  const double v = vm[name].as<double>();
  if (!(v >= 0.0 && v <= 60'000.0)) {
    throw po::error("--" + name + " must be within [0, 60000]");
  }
  return v;
}

// The impairment of one direction: the plain option, overridden by the direction's own.
LinkImpairment link_of(const po::variables_map& vm, const std::string& direction) {
  const auto pick = [&](const std::string& name) {
    return vm.count(direction + name) ? direction + name : name.substr(1);
  };
  LinkImpairment link;
  link.delay_ms = non_negative(vm, pick("-delay-ms"));
  link.jitter_ms = non_negative(vm, pick("-jitter-ms"));
  link.loss = fraction(vm, pick("-loss"));
  link.reorder = fraction(vm, pick("-reorder"));
  return link;
}

void add_link_options(po::options_description& d) {
  d.add_options()("delay-ms", po::value<double>()->default_value(0.0), "added latency, ms")(
      "jitter-ms", po::value<double>()->default_value(0.0), "uniform jitter within +-this, ms")(
      "loss", po::value<double>()->default_value(0.0), "fraction of datagrams lost, [0, 1)")(
      "reorder", po::value<double>()->default_value(0.0), "fraction held back behind the next one, [0, 1)");
  for (const char* direction : {"uplink", "downlink"}) {
    for (const char* name : {"-delay-ms", "-jitter-ms", "-loss", "-reorder"}) {
      d.add_options()((std::string(direction) + name).c_str(), po::value<double>(),
                      (std::string("the same, ") + direction + " only").c_str());
    }
  }
}

std::string read_file(const std::string& path) {
  try {
    return io::read_whole_file(path);
  } catch (const io::FileError& e) {
    throw po::error(e.what());
  }
}

// Empty when --help was given (and printed).
std::optional<Options> parse_options(int argc, char** argv) {
  po::options_description d(kAbout);
  std::vector<std::string> listen, rsus;
  std::string vehicle, rsu_side, rsu_key;
  double burst_period_s = 0.0, burst_length_s = 0.0;
  long long tamper_from_ns = 0;
  Options o;
  d.add_options()("help,h", "show this help")("version", rsu::tools::cli::kVersionHelp)(
      "vehicle", po::value<std::string>(&vehicle)->required(),
      "ADDR:PORT where the vehicle receives corrections")(
      "listen", po::value<std::vector<std::string>>(&listen)->required(),
      "ADDR:PORT taking the vehicle's announcements for the matching --rsu (repeat)")(
      "rsu", po::value<std::vector<std::string>>(&rsus)->required(),
      "HOST:PORT of an RSU's V2I port (repeat)")(
      "rsu-side", po::value<std::string>(&rsu_side)->default_value("127.0.0.2"),
      "the relay's RSU-side address (the vehicle's --reply-address; see above)")(
      "seed", po::value<std::uint64_t>(&o.relay.seed)->default_value(1), "seed of every impairment draw")(
      "bias-x-m", po::value<double>()->default_value(0.0), "fault: add this to each correction's x, m")(
      "bias-y-m", po::value<double>()->default_value(0.0), "fault: add this to each correction's y, m")(
      "covariance-scale", po::value<double>(&o.relay.tamper.covariance_scale)->default_value(1.0),
      "fault: multiply each correction's covariance by this (0.04: sigma x0.2)")(
      "burst-offset-x-m", po::value<double>()->default_value(0.0),
      "fault: a wrong-vehicle burst's offset in x, m")(
      "burst-offset-y-m", po::value<double>()->default_value(0.0), "... and in y, m")(
      "burst-period-s", po::value<double>(&burst_period_s)->default_value(0.0),
      "a burst starts every this long")(
      "burst-length-s", po::value<double>(&burst_length_s)->default_value(0.0), "and lasts this long")(
      "tamper-from-ns", po::value<long long>(&tamper_from_ns),
      "faults apply to corrections swept at or after this time (common clock, ns; default: all)")(
      "rsu-key", po::value<std::string>(&rsu_key), "the RSU's secret key file, to sign altered corrections")(
      "insecure", "the RSU is in insecure mode: altered corrections go unsigned")(
      "tamper-log", po::value<std::string>(&o.relay.tamper_log_path),
      "write every correction forwarded (and whether it was altered) to FILE (CSV)")(
      "stats", po::value<std::string>(&o.stats_path), "write the counters to FILE at the end");
  add_link_options(d);
  po::variables_map vm;
  po::store(po::parse_command_line(argc, argv, d), vm);
  if (vm.count("help")) {
    std::cout << d << "\n";
    return std::nullopt;
  }
  po::notify(vm);
  RelayConfig& r = o.relay;
  r.vehicle = edge::parse_udp_endpoint(vehicle);
  for (const std::string& text : listen) {
    r.listen.push_back(edge::parse_udp_endpoint(text));
  }
  for (const std::string& text : rsus) {
    r.rsus.push_back(edge::parse_udp_endpoint(text));
  }
  if (r.listen.size() != r.rsus.size()) {
    throw po::error("give one --listen per --rsu");
  }
  r.rsu_side_address = edge::parse_ip_address(rsu_side, "--rsu-side");
  r.link = {link_of(vm, "uplink"), link_of(vm, "downlink")};
  TamperConfig& t = r.tamper;
  t.bias_m = {vm["bias-x-m"].as<double>(), vm["bias-y-m"].as<double>()};
  t.burst_offset_m = {vm["burst-offset-x-m"].as<double>(), vm["burst-offset-y-m"].as<double>()};
  if (!(t.covariance_scale > 0.0) || burst_period_s < 0.0 || burst_length_s < 0.0 ||
      burst_length_s > burst_period_s) {
    throw po::error("--covariance-scale must be positive and 0 <= --burst-length-s <= --burst-period-s");
  }
  t.burst_period = from_seconds(burst_period_s);
  t.burst_length = from_seconds(burst_length_s);
  if (vm.count("tamper-from-ns")) {
    t.from = tamper_from_ns;
  }
  if (t.any() && vm.count("insecure") == 0) {
    if (rsu_key.empty()) {
      throw po::error("faults need --rsu-key (or --insecure) to sign the altered corrections");
    }
    r.rsu_key = v2i::security::parse_secret_key_text(read_file(rsu_key), rsu_key);
  }
  return o;
}

void write_stats(std::FILE* out, const RelayStats& s) {
  const char* names[] = {"uplink", "downlink"};
  for (std::size_t d = 0; d < 2; ++d) {
    const ImpairedDirectionStats& x = s.direction[d];
    std::fprintf(
        out, "%s.received %llu\n%s.forwarded %llu\n%s.dropped %llu\n%s.reordered %llu\n%s.send_errors %llu\n",
        names[d], static_cast<unsigned long long>(x.received), names[d],
        static_cast<unsigned long long>(x.forwarded), names[d], static_cast<unsigned long long>(x.dropped),
        names[d], static_cast<unsigned long long>(x.reordered), names[d],
        static_cast<unsigned long long>(s.send_errors[d]));
  }
  std::fprintf(out, "corrections %llu\ncorrections.altered %llu\ncorrections.burst %llu\n",
               static_cast<unsigned long long>(s.corrections),
               static_cast<unsigned long long>(s.corrections_altered),
               static_cast<unsigned long long>(s.corrections_burst));
}

int run(const Options& o) {
  boost::asio::io_context io;
  Relay relay(io, o.relay);
  boost::asio::signal_set signals(io, SIGINT, SIGTERM);
  signals.async_wait([&](const boost::system::error_code&, int) { io.stop(); });
  std::fprintf(stderr, "rsu-relay: ready: %s\n", relay.describe().c_str());
  io.run();
  std::fprintf(stderr, "rsu-relay: stopped:\n");
  write_stats(stderr, relay.stats());
  if (!o.stats_path.empty()) {
    std::FILE* f = std::fopen(o.stats_path.c_str(), "w");
    if (f == nullptr) {
      std::fprintf(stderr, "rsu-relay: --stats: %s: cannot open: %s\n", o.stats_path.c_str(),
                   io::errno_text().c_str());
      return 1;
    }
    write_stats(f, relay.stats());
    std::fclose(f);
  }
  return 0;
}

}  // namespace
}  // namespace rsu::tools

int main(int argc, char** argv) {
  if (rsu::tools::cli::print_version_if_asked(argc, argv, "rsu-relay"))
    return 0;
  std::optional<rsu::tools::Options> options;
  try {
    options = rsu::tools::parse_options(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rsu-relay: %s (see --help)\n", e.what());
    return 2;
  }
  if (!options) {
    return 0;
  }
  try {
    return rsu::tools::run(*options);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rsu-relay: %s\n", e.what());
    return 1;
  }
}
