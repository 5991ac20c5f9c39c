// SPDX-License-Identifier: Apache-2.0
// rsu-vehicle-replay: a recorded drive through the vehicle core again, offline and deterministic: the NDT
// poses rsu-vehicle read (its stdin) and the corrections it received (its --corrections file, with their
// arrival times), merged by time as the live client met them (the corrections received by an NDT pose's
// time are handled before it). Same decisions as live, for the same inputs; with --no-integrity, what the
// vehicle would have done without its integrity checks. Writes the fused poses (rsu-vehicle's stdout
// format) to stdout and the corrections with the replay's decisions to --corrections.
#include <boost/program_options.hpp>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "io/text_file.h"
#include "tools/cli/renamed_options.h"
#include "tools/cli/version.h"
#include "vehicle/vehicle_core.h"
#include "vehicle_client/cli/csv_writers.h"
#include "vehicle_client/ndt_csv.h"

namespace rsu::tools {
namespace {

namespace po = boost::program_options;

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream in(line);
  for (std::string cell; std::getline(in, cell, ',');) {
    out.push_back(cell);
  }
  return out;
}

// rsu-vehicle's --corrections file (vehicle_client/cli/csv_writers.h's columns).
std::vector<vehicle_client::ReceivedCorrection> read_corrections(const std::string& path) {
  std::ifstream in(path);
  if (!in) {
    throw std::runtime_error(path + ": cannot open: " + io::errno_text());
  }
  std::string line;
  std::getline(in, line);
  if (line.rfind(vehicle_client::cli::kCorrectionHeader, 0) != 0) {
    throw std::runtime_error(path + ": not an rsu-vehicle corrections file");
  }
  std::vector<vehicle_client::ReceivedCorrection> out;
  for (std::size_t n = 2; std::getline(in, line); ++n) {
    const std::vector<std::string> f = split(line);
    if (f.size() < 19) {
      throw std::runtime_error(path + ":" + std::to_string(n) + ": too few fields");
    }
    vehicle_client::ReceivedCorrection r;
    v2i::Correction& c = r.correction;
    c.sweep_time = std::stoll(f[0]);
    c.pose = {std::stod(f[1]), std::stod(f[2]), std::stod(f[3])};
    c.pose_covariance << std::stod(f[4]), std::stod(f[5]), std::stod(f[6]), std::stod(f[5]), std::stod(f[7]),
        std::stod(f[8]), std::stod(f[6]), std::stod(f[8]), std::stod(f[9]);
    c.quality.points_used = static_cast<std::uint32_t>(std::stoul(f[10]));
    c.quality.faces_seen = static_cast<std::uint32_t>(std::stoul(f[11]));
    c.quality.range_m = std::stod(f[12]);
    c.quality.yaw_resolution = f[13] == "geometry" ? v2i::YawResolution::kGeometry
                               : f[13] == "prior"  ? v2i::YawResolution::kPrior
                                                   : v2i::YawResolution::kUnresolved;
    c.quality.confidence = std::stod(f[14]);
    c.rsu_id = std::stoull(f[15]);
    c.sequence = static_cast<std::uint32_t>(std::stoul(f[16]));
    c.announcement_sequence = static_cast<std::uint32_t>(std::stoul(f[17]));
    r.received_time = std::stoll(f[18]);
    out.push_back(r);
  }
  std::stable_sort(out.begin(), out.end(),
                   [](const auto& a, const auto& b) { return a.received_time < b.received_time; });
  return out;
}

int run(const po::variables_map& vm) {
  vehicle::VehicleCoreConfig config;
  config.check_integrity = vm.count("no-integrity") == 0;
  config.degraded_ndt_variance_scale = vm["degraded-variance-scale"].as<double>();
  config.integrity.degraded_own_correlation_time =
      static_cast<rsu::TimeNs>(vm["own-correlation-ms"].as<double>() * 1e6);
  const auto corrections = read_corrections(vm["corrections-in"].as<std::string>());
  std::FILE* decisions = nullptr;
  if (vm.count("corrections")) {
    decisions = std::fopen(vm["corrections"].as<std::string>().c_str(), "w");
    if (decisions == nullptr) {
      throw std::runtime_error("--corrections: cannot open: " + io::errno_text());
    }
    std::fprintf(decisions, "%s\n", vehicle_client::cli::kCorrectionHeader);
  }
  vehicle::VehicleCore core(config);
  std::printf("%s\n", vehicle_client::cli::kFusedHeader);
  const double sigma_xy = vm["ndt-sigma-xy-m"].as<double>();
  const double sigma_yaw = vm["ndt-sigma-yaw-rad"].as<double>();
  std::size_t next = 0;
  const auto handle_until = [&](TimeNs t) {
    for (; next < corrections.size() && corrections[next].received_time <= t; ++next) {
      const vehicle::CorrectionStep step = core.on_correction(corrections[next].correction);
      if (step.fused) {
        vehicle_client::cli::write_fused_row(stdout, *step.fused, "rsu");
      }
      if (decisions != nullptr) {
        vehicle_client::cli::write_correction_row(decisions, corrections[next], step.label());
      }
    }
  };
  vehicle_client::NdtCsvParser parser;
  for (std::string line; std::getline(std::cin, line);) {
    const auto row = parser.parse_line(line);
    if (!row) {
      continue;
    }
    handle_until(row->time);
    const Eigen::Matrix3d covariance =
        row->variances
            ? Eigen::Matrix3d(row->variances->asDiagonal())
            : Eigen::Matrix3d(Eigen::Vector3d(sigma_xy * sigma_xy, sigma_xy * sigma_xy, sigma_yaw * sigma_yaw)
                                  .asDiagonal());
    const vehicle::NdtStep step = core.on_ndt({row->time, row->pose, covariance, row->quality});
    if (step.fused) {
      vehicle_client::cli::write_fused_row(stdout, *step.fused, "ndt");
    }
  }
  handle_until(std::numeric_limits<TimeNs>::max());
  if (decisions != nullptr) {
    std::fclose(decisions);
  }
  const vehicle::IntegrityTotals& t = core.integrity().totals();
  std::fprintf(stderr,
               "rsu-vehicle-replay: %zu corrections; RSU accepted %llu, re-anchored %llu; exclusions %llu\n",
               corrections.size(), static_cast<unsigned long long>(core.fuser_stats().rsu_accepted),
               static_cast<unsigned long long>(core.fuser_stats().rsu_reanchors),
               static_cast<unsigned long long>(t.exclusions.total()));
  return 0;
}

}  // namespace
}  // namespace rsu::tools

int main(int argc, char** argv) {
  if (rsu::tools::cli::print_version_if_asked(argc, argv, "rsu-vehicle-replay"))
    return 0;
  rsu::tools::cli::accept_renamed_options(
      argc, argv, {{"ndt-sigma-xy", "ndt-sigma-xy-m"}, {"ndt-sigma-yaw", "ndt-sigma-yaw-rad"}},
      "rsu-vehicle-replay");
  namespace po = boost::program_options;
  po::options_description d(
      "rsu-vehicle-replay --corrections-in CORRECTIONS.csv [--corrections OUT.csv] [--no-integrity] < "
      "ndt.csv "
      "> fused.csv\n(the NDT CSV and the corrections file rsu-vehicle read and wrote in a live "
      "run)\n\noptions");
  d.add_options()("help,h", "show this help")("version", rsu::tools::cli::kVersionHelp)(
      "corrections-in", po::value<std::string>()->required(),
      "the corrections rsu-vehicle received (its --corrections file)")(
      "corrections", po::value<std::string>(), "write them again with the replay's decisions")(
      "no-integrity", "fuse without the integrity checks (rsu-vehicle --no-integrity)")(
      "degraded-variance-scale",
      po::value<double>()->default_value(rsu::vehicle::VehicleCoreConfig{}.degraded_ndt_variance_scale),
      "a degraded NDT pose's covariance times this")(
      "own-correlation-ms",
      po::value<double>()->default_value(
          static_cast<double>(rsu::vehicle::IntegrityConfig{}.degraded_own_correlation_time) / 1e6),
      "the degraded own estimate's error correlation time the integrity checks count fixes by (0: fix by "
      "fix)")("ndt-sigma-xy-m", po::value<double>()->default_value(0.2), "as rsu-vehicle's")(
      "ndt-sigma-yaw-rad", po::value<double>()->default_value(0.02), "as rsu-vehicle's");
  po::variables_map vm;
  try {
    po::store(po::parse_command_line(argc, argv, d), vm);
    if (vm.count("help")) {
      std::cout << d << "\n";
      return 0;
    }
    po::notify(vm);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rsu-vehicle-replay: %s (see --help)\n", e.what());
    return 2;
  }
  try {
    return rsu::tools::run(vm);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rsu-vehicle-replay: %s\n", e.what());
    return 1;
  }
}
