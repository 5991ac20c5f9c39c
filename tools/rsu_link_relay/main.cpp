// rsu-link-relay: the V2I link between a vehicle and an RSU on loopback, impaired in both directions
// (delay, jitter, loss, reordering; seeded), for the link-impairment experiment
// (eval/corridor/run_link_impairment.py). Neither rsud nor rsu-vehicle is changed for it: the vehicle
// announces to the relay and names the relay's RSU-side address as the one to answer to.
//
// Its options are the link options of the vehicle-side fault-injection relay (issue 18's rsu-relay),
// a subset of them, so that the experiment runs with either; this one only impairs.
#include <utility>  // before Asio: Boost 1.74's awaitable.hpp uses std::exchange under C++20

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/udp.hpp>
#include <boost/asio/signal_set.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/program_options.hpp>

#include <array>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <optional>
#include <string>

#include "tools/rsu_link_relay/impaired_direction.h"
#include "vehicle_client/udp_endpoint_text.h"

namespace rsu::tools {
namespace {

constexpr const char* kAbout =
    "rsu-link-relay: relays V2I datagrams between a vehicle and an RSU on loopback, impairing the link\n"
    "\n"
    "usage: rsu-link-relay --vehicle ADDR:PORT --listen ADDR:PORT --rsu HOST:PORT [--rsu-side ADDR]\n"
    "                      [--delay-ms D] [--jitter-ms J] [--loss L] [--reorder R] [--seed S]\n"
    "\n"
    "The vehicle announces to --listen instead of the RSU and is started with --reply-address equal to\n"
    "--rsu-side (default 127.0.0.2). The relay binds that address at the vehicle's own port (from\n"
    "--vehicle) and sends the announcements to the RSU from there, so that rsud (which answers only to the\n"
    "address an announcement came from) sends its corrections back to the relay, which passes them on to\n"
    "--vehicle. Each direction, independently: lost with probability L; otherwise sent D ms plus a\n"
    "uniform jitter within +-J ms after it came (a later datagram may overtake it); a share R held back\n"
    "and sent right after the next datagram of that direction (or 100 ms after its time if none comes).\n"
    "Every draw is keyed by --seed, the direction and the datagram's index.\n"
    "\n"
    "Runs until SIGINT or SIGTERM, then prints its counters (and writes --stats FILE) and exits 0.\n"
    "Exit 2 on a usage error.\n"
    "\n"
    "options";

namespace po = boost::program_options;
namespace asio = boost::asio;
using udp = asio::ip::udp;

struct Options {
  udp::endpoint vehicle, listen, rsu;
  asio::ip::address rsu_side;
  LinkImpairment link;
  std::uint64_t seed = 1;
  std::string stats_path;
};

double option_in(const po::variables_map& vm, const char* name, double low, double high) {
  const double v = vm[name].as<double>();
  if (!(v >= low && v < high))
    throw po::error(std::string("--") + name + " must be within [" + std::to_string(low) + ", " +
                    std::to_string(high) + ")");
  return v;
}

std::optional<Options> parse_options(int argc, char** argv) {
  po::options_description d(kAbout);
  std::string vehicle, listen, rsu, rsu_side;
  Options o;
  d.add_options()("help,h", "show this help")("vehicle", po::value<std::string>(&vehicle)->required(),
                                              "ADDR:PORT where the vehicle receives corrections")(
      "listen", po::value<std::string>(&listen)->required(), "ADDR:PORT taking the vehicle's announcements")(
      "rsu", po::value<std::string>(&rsu)->required(), "HOST:PORT of the RSU's V2I port")(
      "rsu-side", po::value<std::string>(&rsu_side)->default_value("127.0.0.2"),
      "the relay's RSU-side address (the vehicle's --reply-address)")(
      "delay-ms", po::value<double>()->default_value(0.0), "added one-way latency, each direction, ms")(
      "jitter-ms", po::value<double>()->default_value(0.0), "uniform jitter within +-this, ms")(
      "loss", po::value<double>()->default_value(0.0), "fraction of datagrams lost, [0, 1)")(
      "reorder", po::value<double>()->default_value(0.0), "fraction held back behind the next one, [0, 1)")(
      "seed", po::value<std::uint64_t>(&o.seed)->default_value(1), "seed of every impairment draw")(
      "stats", po::value<std::string>(&o.stats_path), "write the counters to FILE at the end");
  po::variables_map vm;
  po::store(po::parse_command_line(argc, argv, d), vm);
  if (vm.count("help")) {
    std::cout << d << "\n";
    return std::nullopt;
  }
  po::notify(vm);
  o.vehicle = vehicle_client::parse_udp_endpoint(vehicle);
  o.listen = vehicle_client::parse_udp_endpoint(listen);
  o.rsu = vehicle_client::parse_udp_endpoint(rsu);
  boost::system::error_code ec;
  o.rsu_side = asio::ip::make_address(rsu_side, ec);
  if (ec)
    throw po::error("--rsu-side: \"" + rsu_side + "\" is not an IP address");
  o.link.delay_ms = option_in(vm, "delay-ms", 0.0, 60000.0);
  o.link.jitter_ms = option_in(vm, "jitter-ms", 0.0, 60000.0);
  o.link.loss = option_in(vm, "loss", 0.0, 1.0);
  o.link.reorder = option_in(vm, "reorder", 0.0, 1.0);
  return o;
}

TimeNs steady_now() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

// Two sockets: the vehicle side (bound at --listen: announcements in, corrections out to --vehicle) and
// the RSU side (bound at --rsu-side and the vehicle's port: announcements out to --rsu, corrections in).
class LinkRelay {
 public:
  LinkRelay(asio::io_context& io, const Options& o)
      : options_(o),
        vehicle_side_(io, o.listen),
        rsu_side_(io, udp::endpoint(o.rsu_side, o.vehicle.port())),
        timer_(io),
        directions_{ImpairedDirection(o.link, o.seed, 0), ImpairedDirection(o.link, o.seed, 1)} {
    receive(vehicle_side_, kUplink);
    receive(rsu_side_, kDownlink);
  }

  const ImpairedDirectionStats& stats(int direction) const { return directions_[direction].stats(); }
  std::uint64_t send_errors(int direction) const { return send_errors_[direction]; }

 private:
  static constexpr int kUplink = 0, kDownlink = 1;

  void receive(udp::socket& socket, int direction) {
    socket.async_receive_from(asio::buffer(buffers_[direction]), senders_[direction],
                              [this, &socket, direction](const boost::system::error_code& ec, std::size_t n) {
                                if (ec == asio::error::operation_aborted)
                                  return;
                                if (!ec) {
                                  const auto* data = buffers_[direction].data();
                                  directions_[direction].push(steady_now(),
                                                              ImpairedDirection::Datagram(data, data + n));
                                  flush();
                                }
                                receive(socket, direction);
                              });
  }

  // Sends what is due and waits for the next due time.
  void flush() {
    const TimeNs now = steady_now();
    for (int d : {kUplink, kDownlink}) {
      for (const auto& bytes : directions_[d].pop_due(now)) {
        boost::system::error_code ec;
        if (d == kUplink)
          rsu_side_.send_to(asio::buffer(bytes), options_.rsu, 0, ec);
        else
          vehicle_side_.send_to(asio::buffer(bytes), options_.vehicle, 0, ec);
        send_errors_[d] += ec ? 1 : 0;
      }
    }
    std::optional<TimeNs> next;
    for (const auto& direction : directions_) {
      const auto due = direction.next_due();
      if (due && (!next || *due < *next))
        next = due;
    }
    if (!next)
      return;
    timer_.expires_after(std::chrono::nanoseconds(std::max<TimeNs>(0, *next - now)));
    timer_.async_wait([this](const boost::system::error_code& ec) {
      if (!ec)
        flush();
    });
  }

  Options options_;
  udp::socket vehicle_side_, rsu_side_;
  asio::steady_timer timer_;
  std::array<ImpairedDirection, 2> directions_;
  std::array<std::array<std::uint8_t, 65536>, 2> buffers_{};
  std::array<udp::endpoint, 2> senders_;
  std::array<std::uint64_t, 2> send_errors_{};
};

void write_stats(std::FILE* out, const LinkRelay& relay) {
  const char* names[] = {"uplink", "downlink"};
  for (int d = 0; d < 2; ++d) {
    const ImpairedDirectionStats& s = relay.stats(d);
    std::fprintf(
        out, "%s.received %llu\n%s.forwarded %llu\n%s.dropped %llu\n%s.reordered %llu\n%s.send_errors %llu\n",
        names[d], static_cast<unsigned long long>(s.received), names[d],
        static_cast<unsigned long long>(s.forwarded), names[d], static_cast<unsigned long long>(s.dropped),
        names[d], static_cast<unsigned long long>(s.reordered), names[d],
        static_cast<unsigned long long>(relay.send_errors(d)));
  }
}

int run(const Options& o) {
  asio::io_context io;
  LinkRelay relay(io, o);
  asio::signal_set signals(io, SIGINT, SIGTERM);
  signals.async_wait([&](const boost::system::error_code&, int) { io.stop(); });
  std::fprintf(
      stderr,
      "rsu-link-relay: ready: vehicle %s <-> listen %s | %s <-> rsu %s; delay %.1f ms, jitter %.1f ms, "
      "loss %.3f, reorder %.3f, seed %llu\n",
      vehicle_client::to_text(o.vehicle).c_str(), vehicle_client::to_text(o.listen).c_str(),
      o.rsu_side.to_string().c_str(), vehicle_client::to_text(o.rsu).c_str(), o.link.delay_ms,
      o.link.jitter_ms, o.link.loss, o.link.reorder, static_cast<unsigned long long>(o.seed));
  io.run();
  std::fprintf(stderr, "rsu-link-relay: stopped:\n");
  write_stats(stderr, relay);
  if (!o.stats_path.empty()) {
    std::FILE* f = std::fopen(o.stats_path.c_str(), "w");
    if (f == nullptr) {
      std::fprintf(stderr, "rsu-link-relay: cannot write --stats \"%s\"\n", o.stats_path.c_str());
      return 1;
    }
    write_stats(f, relay);
    std::fclose(f);
  }
  return 0;
}

}  // namespace
}  // namespace rsu::tools

int main(int argc, char** argv) {
  std::optional<rsu::tools::Options> options;
  try {
    options = rsu::tools::parse_options(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rsu-link-relay: %s (--help for usage)\n", e.what());
    return 2;
  }
  if (!options)
    return 0;
  try {
    return rsu::tools::run(*options);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rsu-link-relay: %s\n", e.what());
    return 1;
  }
}
