// SPDX-License-Identifier: Apache-2.0
// rsu-vehicle: the vehicle side of RSU-assisted localization on the command line. Reads the vehicle's
// NDT poses as CSV on stdin, announces the vehicle to the RSU(s), receives their corrections, fuses
// both, and prints the fused poses as CSV on stdout (issue 4, item 3). The decisions are the vehicle
// core's (lib/vehicle); this file reads, paces, sends and writes.
#include <utility>  // before Asio: Boost 1.74's awaitable.hpp uses std::exchange under C++20

#include <boost/program_options.hpp>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "edge/address_text.h"
#include "io/text_file.h"
#include "tools/cli/renamed_options.h"
#include "tools/cli/version.h"
#include "v2i/security/key_text.h"
#include "v2i/security/trust_list.h"
#include "vehicle/vehicle_core.h"
#include "vehicle_client/cli/csv_writers.h"
#include "vehicle_client/cli/stats_report.h"
#include "vehicle_client/ndt_csv.h"
#include "vehicle_client/vehicle_client.h"

namespace rsu::vehicle_client::cli {
namespace {

namespace po = boost::program_options;
using Steady = std::chrono::steady_clock;

constexpr const char* kAbout =
    "rsu-vehicle: announce a vehicle to roadside LiDAR units, receive their corrections and fuse them\n"
    "with the vehicle's own NDT poses.\n"
    "\n"
    "usage: rsu-vehicle --vehicle-id ID --rsu HOST:PORT --key VEHICLE.key --trust-list TRUST.list\n"
    "                   [options] < ndt.csv > fused.csv\n"
    "\n"
    "Security (proto/v2i.proto): announcements are signed with --key (Ed25519, made by rsu-keygen; the\n"
    "RSUs' trust lists must bind its public key to --vehicle-id), and corrections are used only when\n"
    "signed by an RSU key in --trust-list, generated within --max-age-ms of this host's clock and not\n"
    "replayed. --insecure signs and verifies nothing: local development only (it warns).\n"
    "\n"
    "stdin: NDT poses, CSV with a header line naming the columns: time_ns,x,y,yaw, then any of\n"
    "  sxx,syy,syaw (all three) and converged,iterations,fitness,degeneracy, in any order:\n"
    "  time_ns on the common clock (ns; GNSS/PTP time, or host time since the Unix epoch in tests);\n"
    "  x, y in the map frame (ENU, m) of the vehicle's reference point; yaw rad CCW from east;\n"
    "  sxx, syy, syaw: variances (m^2, m^2, rad^2); without them --ndt-sigma-xy-m/--ndt-sigma-yaw-rad "
    "apply;\n"
    "  converged (0/1), iterations, fitness (PCL's score, m^2), degeneracy (how many times more weakly\n"
    "  the match holds the vehicle in its weakest horizontal direction than in its strongest): the\n"
    "  match's quality indicator. A pose not converged, at --ndt-max-iterations, above --ndt-max-fitness-m2\n"
    "  or --ndt-max-degeneracy is DEGRADED: only then may RSU fixes take over the pose. Without these\n"
    "  columns the poses are taken at their word.\n"
    "  Bad input stops the program with the line number.\n"
    "\n"
    "stdout: fused poses, CSV with the header\n"
    "  time_ns,x,y,yaw,source,sxx,syy,syaw,speed_mps,yaw_rate_rps\n"
    "  source ndt: the estimate at an NDT pose's time after fusing it; source rsu: at a correction's sweep\n"
    "  time after fusing it (rows need not be in time order: corrections arrive late). sxx, syy, syaw:\n"
    "  variances; speed_mps, yaw_rate_rps: the filter's motion estimate.\n"
    "\n"
    "--corrections FILE: every correction received, CSV with the header\n"
    "  time_ns,x,y,yaw,cxx,cxy,cxyaw,cyy,cyyaw,cyawyaw,points_used,faces_seen,range_m,yaw_resolution,\n"
    "  confidence,rsu_id,sequence,announcement_sequence,received_ns,fusion\n"
    "  time_ns is the LiDAR sweep time; x, y the box centre; c*: covariance; fusion: the decision:\n"
    "  accepted, rejected_gate, rejected_yaw_branch, ... (the filter's), or probation, excluded, barred,\n"
    "  inconsistent (refused by the integrity check: each RSU is checked against the vehicle's own\n"
    "  estimate and the other RSUs; one that disagrees beyond both covariances is excluded, logged,\n"
    "  counted, and readmitted only after a run of consistent fixes).\n"
    "\n"
    "stderr: what the RSUs say when they send no correction, each logged when its reason changes, else\n"
    "  once a minute: an announcement refused (\"RSU 1 (ADDR:PORT) refused announcement 12: ...\"), and a\n"
    "  rotation that swept this vehicle without a fix (\"RSU 1 (ADDR:PORT) withheld the fix of sweep T:\n"
    "  position_unbounded (sigma S m, at most B m)\"; the reasons: position_unbounded,\n"
    "  yaw_unobserved, inconsistent, no_own_cluster, no_fit, out_of_coverage, mount), counted in --stats as\n"
    "  refusal.<reason> and fix_withheld.<reason>.\n"
    "\n"
    "On EOF it waits --drain-ms for late corrections, prints statistics on stderr (--stats FILE: every\n"
    "counter as \"key value\" lines) and exits 0.\n"
    "\n"
    "options";

struct Options {
  VehicleClientConfig client;
  bool announce_only = false;
  bool realtime = false;
  std::string corrections_path;
  TimeNs drain = 300 * kNsPerMs;
  double ndt_sigma_xy = 0.2;
  double ndt_sigma_yaw = 0.02;
  std::string stats_path;
  vehicle::VehicleCoreConfig core;
};

std::string read_file(const std::string& path, const char* option) {
  try {
    return io::read_whole_file(path);
  } catch (const io::FileError& e) {
    throw std::runtime_error(std::string(option) + ": " + e.what());
  }
}

void warn_insecure() {
  std::fprintf(stderr,
               "rsu-vehicle: *** INSECURE MODE: announcements are NOT signed and corrections are NOT "
               "verified; anyone can forge or replay corrections. Local development only. ***\n");
}

// When the vehicle's own NDT counts as degraded, and whether corrections are checked at all (issue 18).
void add_integrity_options(po::options_description& d, Options& o) {
  d.add_options()("ndt-max-fitness-m2",
                  po::value<double>(&o.core.ndt_quality.max_fitness_m2)->default_value(0.5, "0.5"),
                  "a fitness (m^2) above this marks the pose degraded")(
      "ndt-max-iterations", po::value<int>(&o.core.ndt_quality.max_iterations)->default_value(30),
      "a match that used this many iterations hit its cap: degraded")(
      "ndt-max-degeneracy", po::value<double>(&o.core.ndt_quality.max_degeneracy)->default_value(7.0, "7"),
      "a degeneracy above this marks the pose degraded")(
      "no-integrity",
      "fuse every correction the filter's gate lets through, unchecked against the vehicle's own "
      "estimate (for comparison only)")("stats", po::value<std::string>(&o.stats_path),
                                        "write every counter to FILE at the end");
}

// Empty when --help was given (and printed).
std::optional<Options> parse_options(int argc, char** argv) {
  Options o;
  std::string bind = "0.0.0.0:0";
  double drain_ms = 300.0;
  double announce_period_ms = 100.0;
  std::uint64_t vehicle_id = 0;
  std::string key_path;
  std::string trust_path;
  double max_age_ms = 1000.0;
  po::options_description d(kAbout);
  d.add_options()("help,h", "show this help")("version", rsu::tools::cli::kVersionHelp)(
      "vehicle-id", po::value<std::uint64_t>(&vehicle_id)->required(),
      "non-zero vehicle id (stable for the trip)")(
      "length-m", po::value<double>(&o.client.size.length_m)->default_value(4.89, "4.89"),
      "footprint box length, m")("width-m",
                                 po::value<double>(&o.client.size.width_m)->default_value(1.92, "1.92"),
                                 "footprint box width, m")(
      "height-m", po::value<double>(&o.client.size.height_m)->default_value(1.70, "1.70"), "box height, m")(
      "ref-offset-x-m", po::value<double>()->default_value(0.0),
      "reference point minus box centre along vehicle x (forward), m; e.g. -1.3 for a rear axle")(
      "ref-offset-y-m", po::value<double>()->default_value(0.0), "the same along vehicle y (left), m")(
      "rsu", po::value<std::vector<std::string>>(&o.client.rsu_endpoints)->required(),
      "RSU announcement endpoint HOST:PORT ([ADDR]:PORT for IPv6); repeat for several RSUs")(
      "bind", po::value<std::string>(&bind)->default_value(bind),
      "local ADDR:PORT receiving corrections (port 0: any free port; it is announced)")(
      "reply-address", po::value<std::string>(&o.client.reply_address),
      "address announced for corrections (default: the bound one, or the one routed to the RSU)")(
      "announce-period-ms", po::value<double>(&announce_period_ms)->default_value(announce_period_ms, "100"),
      "repeat the latest pose when no new one came for this long (0: never)")(
      "announce-only",
      "announce and record corrections (--corrections) but do not fuse them: the output "
      "is then the NDT-only filter, a baseline")(
      "realtime",
      "pace the input by its time_ns column (as a live vehicle would) instead of as fast as "
      "lines come")("corrections", po::value<std::string>(&o.corrections_path),
                    "write the corrections received to FILE (CSV)")(
      "drain-ms", po::value<double>(&drain_ms)->default_value(drain_ms, "300"),
      "wait this long for corrections after EOF")("key", po::value<std::string>(&key_path),
                                                  "the vehicle's Ed25519 secret key file (rsu-keygen)")(
      "trust-list", po::value<std::string>(&trust_path),
      "trust list file: the RSU keys whose corrections are accepted")(
      "max-age-ms", po::value<double>(&max_age_ms)->default_value(max_age_ms, "1000"),
      "refuse corrections generated more than this before (or after) this host's clock")(
      "insecure", "send unsigned announcements and accept unsigned corrections (local development only)")(
      "ndt-sigma-xy-m", po::value<double>(&o.ndt_sigma_xy)->default_value(o.ndt_sigma_xy, "0.2"),
      "NDT position standard deviation, m, for rows without variances")(
      "ndt-sigma-yaw-rad", po::value<double>(&o.ndt_sigma_yaw)->default_value(o.ndt_sigma_yaw, "0.02"),
      "NDT yaw standard deviation, rad, for rows without variances");
  add_integrity_options(d, o);
  po::variables_map vm;
  po::store(po::parse_command_line(argc, argv, d), vm);
  if (vm.count("help")) {
    std::cout << d << "\n";
    return std::nullopt;
  }
  po::notify(vm);
  o.client.vehicle_id = vehicle_id;
  if (vehicle_id == 0) {
    throw std::invalid_argument("--vehicle-id must be non-zero");
  }
  for (const std::string& rsu : o.client.rsu_endpoints) {
    edge::parse_udp_endpoint(rsu);  // throws naming the bad one
  }
  o.client.reference_offset = {vm["ref-offset-x-m"].as<double>(), vm["ref-offset-y-m"].as<double>()};
  const auto bind_endpoint = edge::parse_udp_endpoint(bind, true);
  o.client.bind_address = bind_endpoint.address().is_unspecified() ? "" : bind_endpoint.address().to_string();
  o.client.bind_port = bind_endpoint.port();
  o.announce_only = vm.count("announce-only") > 0;
  o.realtime = vm.count("realtime") > 0;
  if (!(drain_ms >= 0.0 && drain_ms <= 60'000.0)) {
    throw std::invalid_argument("--drain-ms must be within [0, 60000]");
  }
  if (!(announce_period_ms >= 0.0 && announce_period_ms <= 60'000.0)) {
    throw std::invalid_argument("--announce-period-ms must be within [0, 60000]");
  }
  if (!(o.ndt_sigma_xy > 0.0 && o.ndt_sigma_yaw > 0.0)) {
    throw std::invalid_argument("--ndt-sigma-xy-m and --ndt-sigma-yaw-rad must be positive");
  }
  if (!(o.core.ndt_quality.max_fitness_m2 > 0.0) || o.core.ndt_quality.max_iterations < 1 ||
      !(o.core.ndt_quality.max_degeneracy >= 1.0)) {
    throw std::invalid_argument(
        "--ndt-max-fitness-m2 must be positive, --ndt-max-iterations and --ndt-max-degeneracy at least 1");
  }
  o.core.check_integrity = vm.count("no-integrity") == 0;
  o.core.fuse_corrections = !o.announce_only;
  o.drain = from_seconds(drain_ms * 1e-3);
  if (vm.count("insecure")) {
    o.client.security.mode = v2i::SecurityMode::kInsecure;
  } else {
    if (key_path.empty() || trust_path.empty()) {
      throw std::invalid_argument(
          "--key and --trust-list are required (or --insecure for local development)");
    }
    if (!(max_age_ms > 0.0 && max_age_ms <= 60'000.0)) {
      throw std::invalid_argument("--max-age-ms must be within (0, 60000]");
    }
    o.client.security.replay.max_age = o.client.security.replay.max_future = from_seconds(max_age_ms * 1e-3);
    o.client.signing_key = v2i::security::parse_secret_key_text(read_file(key_path, "--key"), key_path);
    o.client.trust_list =
        v2i::security::parse_trust_list_text(read_file(trust_path, "--trust-list"), trust_path);
  }
  o.client.announce_period = from_seconds(announce_period_ms * 1e-3);
  return o;
}

// Whether a line about `what` is due: when it differs from the last one logged, else once a minute.
class RepeatLimiter {
 public:
  bool due(const std::string& what) {
    const auto now = Steady::now();
    if (what == last_ && now - at_ < std::chrono::minutes(1))
      return false;
    last_ = what;
    at_ = now;
    return true;
  }

 private:
  std::string last_;
  Steady::time_point at_{};
};

class Session {
 public:
  explicit Session(const Options& options)
      : options_(options), threaded_(options.client), core_(core_config()) {
    if (!options_.corrections_path.empty()) {
      corrections_.reset(std::fopen(options_.corrections_path.c_str(), "w"));
      if (!corrections_) {
        throw std::runtime_error("--corrections: " + options_.corrections_path +
                                 ": cannot open: " + io::errno_text());
      }
      std::fprintf(corrections_.get(), "%s\n", kCorrectionHeader);
    }
    if (options_.client.security.mode == v2i::SecurityMode::kInsecure) {
      warn_insecure();  // at start-up, then every minute while running (on_ndt)
      last_insecure_warning_ = Steady::now();
    }
    std::printf("%s\n", kFusedHeader);
    std::fflush(stdout);
  }

  void on_ndt(const NdtPoseRow& row) {
    if (options_.client.security.mode == v2i::SecurityMode::kInsecure &&
        Steady::now() - last_insecure_warning_ >= std::chrono::minutes(1)) {
      warn_insecure();
      last_insecure_warning_ = Steady::now();
    }
    const Eigen::Matrix3d covariance =
        row.variances ? Eigen::Matrix3d(row.variances->asDiagonal())
                      : Eigen::Matrix3d(Eigen::Vector3d(options_.ndt_sigma_xy * options_.ndt_sigma_xy,
                                                        options_.ndt_sigma_xy * options_.ndt_sigma_xy,
                                                        options_.ndt_sigma_yaw * options_.ndt_sigma_yaw)
                                            .asDiagonal());
    handle_corrections();  // first, so that the row below includes every correction received so far
    const vehicle::NdtStep step = core_.on_ndt({row.time, row.pose, covariance, row.quality});
    announce(step.announce);
    if (step.fused) {
      write_fused_row(stdout, *step.fused, "ndt");
    }
    std::fflush(stdout);
  }

  // An RSU said why it refused an announcement: logged when the reason changes, else once a minute.
  void log_refusals() {
    const VehicleClientStats stats = threaded_.client().stats();
    if (!stats.last_refusal || stats.refusals.total() == refusals_seen_)
      return;
    refusals_seen_ = stats.refusals.total();
    const v2i::AnnouncementRefusal& r = stats.last_refusal->refusal;
    if (!refusal_log_.due(std::to_string(r.rsu_id) + " " + v2i::to_string(r.reason) + ":" + r.detail))
      return;
    std::fprintf(stderr,
                 "rsu-vehicle: RSU %llu (%s) refused announcement %u: %s (%s); %llu refusal(s) so far\n",
                 static_cast<unsigned long long>(r.rsu_id), stats.last_refusal->sender.c_str(),
                 r.announcement_sequence, v2i::to_string(r.reason), r.detail.c_str(),
                 static_cast<unsigned long long>(refusals_seen_));
  }

  // An RSU swept this vehicle and says why it sends no fix: logged when the reason changes, else once a
  // minute.
  void log_fixes_withheld() {
    const VehicleClientStats stats = threaded_.client().stats();
    if (!stats.last_fix_withheld || stats.fixes_withheld.total() == withheld_seen_)
      return;
    withheld_seen_ = stats.fixes_withheld.total();
    const v2i::FixWithheld& n = stats.last_fix_withheld->notice;
    if (!withheld_log_.due(std::to_string(n.rsu_id) + " " + v2i::to_string(n.reason)))
      return;
    std::fprintf(
        stderr, "rsu-vehicle: RSU %llu (%s) withheld the fix of sweep %lld: %s; %llu such notice(s) so far\n",
        static_cast<unsigned long long>(n.rsu_id), stats.last_fix_withheld->sender.c_str(),
        static_cast<long long>(n.sweep_time), describe(n).c_str(),
        static_cast<unsigned long long>(withheld_seen_));
  }

  // An RSU's advertisement says it withholds its fixes (its LiDAR moved), or that it sends them again:
  // logged when that RSU's word changes.
  void log_advertisements() {
    const VehicleClientStats stats = threaded_.client().stats();
    if (!stats.last_advertisement)
      return;
    const v2i::RsuAdvertisement& a = stats.last_advertisement->advertisement;
    const auto known = rsu_withholding_.find(a.rsu_id);
    const v2i::FixesWithheld before =
        known == rsu_withholding_.end() ? v2i::FixesWithheld::kNone : known->second;
    rsu_withholding_[a.rsu_id] = a.fixes_withheld;
    if (a.fixes_withheld == before)
      return;
    if (a.fixes_withheld == v2i::FixesWithheld::kNone) {
      std::fprintf(stderr, "rsu-vehicle: RSU %llu (%s) sends corrections again\n",
                   static_cast<unsigned long long>(a.rsu_id), stats.last_advertisement->sender.c_str());
      return;
    }
    std::fprintf(stderr,
                 "rsu-vehicle: RSU %llu (%s) withholds its corrections: %s (its estimate of the error a fix "
                 "would carry at %.0f m: %.3f m)\n",
                 static_cast<unsigned long long>(a.rsu_id), stats.last_advertisement->sender.c_str(),
                 v2i::to_string(a.fixes_withheld), a.coverage_radius_m, a.mount_error_at_radius_m);
  }

  // Fuses and records whatever corrections arrived.
  void handle_corrections() {
    log_refusals();
    log_fixes_withheld();
    log_advertisements();
    for (const ReceivedCorrection& r : threaded_.client().poll()) {
      const vehicle::CorrectionStep step = core_.on_correction(r.correction);
      if (step.check && events_logged_ < kMaxEventsLogged) {
        const std::string event = integrity_event(r.correction, *step.check, core_.integrity());
        if (!event.empty()) {
          std::fprintf(stderr, "rsu-vehicle: %s%s\n", event.c_str(),
                       ++events_logged_ == kMaxEventsLogged ? " (no more such lines)" : "");
        }
      }
      if (step.fused) {
        write_fused_row(stdout, *step.fused, "rsu");
      }
      if (corrections_) {
        write_correction_row(corrections_.get(), r, step.label());
      }
    }
  }

  void print_stats() const {
    const VehicleClientStats client = threaded_.client().stats();
    print_summary(stderr, client, core_, options_.client.security.mode);
    if (!options_.stats_path.empty()) {
      write_stats_file(options_.stats_path, client, core_);
    }
  }

 private:
  static constexpr int kMaxEventsLogged = 100;

  vehicle::VehicleCoreConfig core_config() const {
    vehicle::VehicleCoreConfig config = options_.core;
    config.fuser.ekf.reference_offset = options_.client.reference_offset;
    return config;
  }

  void announce(const VehicleState& state) {
    const v2i::AnnouncementReason reason = threaded_.client().announce(state);
    if (reason != v2i::AnnouncementReason::kValid && refusals_logged_ < 10) {
      ++refusals_logged_;
      std::fprintf(stderr, "rsu-vehicle: announcement at %lld not sent: %s\n",
                   static_cast<long long>(state.time), v2i::to_string(reason));
    }
  }

  struct FileCloser {
    void operator()(std::FILE* f) const { std::fclose(f); }
  };

  const Options& options_;
  ThreadedVehicleClient threaded_;
  vehicle::VehicleCore core_;
  std::unique_ptr<std::FILE, FileCloser> corrections_;
  int refusals_logged_ = 0;
  int events_logged_ = 0;
  std::uint64_t refusals_seen_ = 0;
  RepeatLimiter refusal_log_;
  std::uint64_t withheld_seen_ = 0;
  RepeatLimiter withheld_log_;
  std::map<std::uint64_t, v2i::FixesWithheld> rsu_withholding_;  // each RSU's latest advertised word
  Steady::time_point last_insecure_warning_{};
};

// Waits until `until`, fusing corrections as they come (10 ms slices).
void wait_handling_corrections(Session& session, Steady::time_point until) {
  while (Steady::now() < until) {
    std::this_thread::sleep_for(
        std::min<Steady::duration>(std::chrono::milliseconds(10), until - Steady::now()));
    session.handle_corrections();
    std::fflush(stdout);
  }
}

int run(const Options& options) {
  Session session(options);
  NdtCsvParser parser;
  std::optional<TimeNs> first_time;
  const Steady::time_point wall_start = Steady::now();
  std::string line;
  while (std::getline(std::cin, line)) {
    std::optional<NdtPoseRow> row;
    try {
      row = parser.parse_line(line);
    } catch (const NdtCsvError& e) {
      std::fprintf(stderr, "rsu-vehicle: stdin %s\n", e.what());
      session.print_stats();
      return 1;
    }
    if (!row) {
      continue;
    }
    if (options.realtime) {
      if (!first_time) {
        first_time = row->time;
      }
      wait_handling_corrections(session, wall_start + std::chrono::nanoseconds(row->time - *first_time));
    }
    session.on_ndt(*row);
  }
  if (!parser.has_header()) {
    std::fprintf(stderr, "rsu-vehicle: stdin ended before the header line\n");
  }
  wait_handling_corrections(session, Steady::now() + std::chrono::nanoseconds(options.drain));
  session.print_stats();
  return 0;
}

}  // namespace
}  // namespace rsu::vehicle_client::cli

int main(int argc, char** argv) {
  if (rsu::tools::cli::print_version_if_asked(argc, argv, "rsu-vehicle"))
    return 0;
  rsu::tools::cli::accept_renamed_options(argc, argv,
                                          {{"length", "length-m"},
                                           {"width", "width-m"},
                                           {"height", "height-m"},
                                           {"ref-offset-x", "ref-offset-x-m"},
                                           {"ref-offset-y", "ref-offset-y-m"},
                                           {"ndt-sigma-xy", "ndt-sigma-xy-m"},
                                           {"ndt-sigma-yaw", "ndt-sigma-yaw-rad"},
                                           {"ndt-max-fitness", "ndt-max-fitness-m2"}},
                                          "rsu-vehicle");
  std::optional<rsu::vehicle_client::cli::Options> options;
  try {
    options = rsu::vehicle_client::cli::parse_options(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rsu-vehicle: %s (see --help)\n", e.what());
    return 2;
  }
  if (!options) {
    return 0;
  }
  try {
    return rsu::vehicle_client::cli::run(*options);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rsu-vehicle: %s\n", e.what());
    return 1;
  }
}
