// SPDX-License-Identifier: Apache-2.0
// rsu-calibrate: where the RSU's LiDAR is, from its background scan and the street's map.
//   rsu-calibrate --background bg.pcd [--background ...] --map map.pcd --initial x,y,z,roll,pitch,yaw
// The initial mount is a rough one (a hand-held GNSS and a compass; angles in degrees). Prints the mount
// with its covariance, the residuals, a verdict and the `lidar.mount:` block for rsud's configuration.
// Exit status: 0 good, 3 ambiguous, 4 failed, 1 an error (a file), 2 usage.
#include <boost/program_options.hpp>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "io/pcd_io.h"
#include "tools/cli/version.h"
#include "tools/rsu_calibrate/mount_calibration.h"

namespace po = boost::program_options;
using namespace rsu;

namespace {

Pose3 parse_pose(const std::string& text) {
  std::vector<double> v;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    std::size_t used = 0;
    double value = 0.0;
    try {
      value = std::stod(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || !std::isfinite(value))
      throw std::invalid_argument("--initial: \"" + item + "\" is not a number");
    v.push_back(value);
  }
  if (v.size() != 6)
    throw std::invalid_argument("--initial: expected x,y,z,roll_deg,pitch_deg,yaw_deg (6 numbers), got " +
                                std::to_string(v.size()));
  return Pose3{v[0], v[1], v[2], deg_to_rad(v[3]), deg_to_rad(v[4]), deg_to_rad(v[5])};
}

std::string mount_text(const Pose3& p) {
  char text[256];
  std::snprintf(text, sizeof text,
                "{x: %.4f, y: %.4f, z: %.4f, roll_deg: %.4f, pitch_deg: %.4f, yaw_deg: %.4f}", p.x, p.y, p.z,
                rad_to_deg(p.roll), rad_to_deg(p.pitch), rad_to_deg(p.yaw));
  return text;
}

std::string report(const tools::CalibrationResult& r) {
  std::ostringstream out;
  out.precision(6);
  const auto& c = r.uncertainty.covariance;
  auto sigma = [&](int i) { return std::sqrt(c(i, i)); };
  out << "verdict: " << calibration::verdict_name(r.verdict.verdict) << "\n"
      << "reason: \"" << r.verdict.reason << "\"\n"
      << "mount: " << mount_text(r.pose) << "\n"
      << "sigma: {x_m: " << sigma(0) << ", y_m: " << sigma(1) << ", z_m: " << sigma(2)
      << ", roll_deg: " << rad_to_deg(sigma(3)) << ", pitch_deg: " << rad_to_deg(sigma(4))
      << ", yaw_deg: " << rad_to_deg(sigma(5)) << "}\n"
      << "# covariance of x, y, z (m), roll, pitch, yaw (rad), row by row\ncovariance: [";
  for (int i = 0; i < 36; ++i)
    out << (i ? ", " : "") << c(i / 6, i % 6);
  out << "]\n"
      << "residuals: {rms_m: " << r.fit.rms_m << ", scale: " << r.fit.scale << ", matched: " << r.fit.matches
      << ", on_walls_and_poles: " << r.fit.vertical_matches << ", background_points: " << r.background_points
      << ", map_points_in_reach: " << r.map_points << "}\n"
      << "search: {initial: " << mount_text(r.initial) << ", coarse: " << mount_text(r.coarse)
      << ", coarse_hits: " << r.search.hits << "/" << r.search.points << ", iterations: " << r.iterations
      << "}\n";
  if (r.verdict.verdict == calibration::Verdict::kGood)
    out << "# paste into rsud's configuration:\nlidar:\n  mount: " << mount_text(r.pose) << "\n";
  else
    out << "# not good: no lidar.mount block to paste (see the reason)\n";
  return out.str();
}

}  // namespace

int main(int argc, char** argv) {
  if (rsu::tools::cli::print_version_if_asked(argc, argv, "rsu-calibrate"))
    return 0;
  po::options_description options(
      "rsu-calibrate --background PCD [--background PCD ...] --map PCD --initial x,y,z,roll,pitch,yaw\n"
      "The LiDAR's mount from its background scan (sensor frame) registered against the street's map\n"
      "(map frame), from a rough initial mount (metres; degrees). Exit: 0 good, 3 ambiguous, 4 failed");
  options.add_options()("help,h", "show this help")("version", rsu::tools::cli::kVersionHelp)(
      "background", po::value<std::vector<std::string>>(), "background scan(s), PCD in the sensor frame")(
      "map", po::value<std::string>(), "the street's map, PCD in the map frame")(
      "initial", po::value<std::string>(), "rough mount: x,y,z,roll_deg,pitch_deg,yaw_deg")(
      "search-radius-m", po::value<double>()->default_value(3.0), "coarse search: +- metres in x and y")(
      "search-yaw-deg", po::value<double>()->default_value(20.0), "coarse search: +- degrees of yaw")(
      "out,o", po::value<std::string>(), "also write the report to this file");
  po::variables_map vm;
  try {
    po::store(po::parse_command_line(argc, argv, options), vm);
    po::notify(vm);
    if (vm.count("help") || !vm.count("background") || !vm.count("map") || !vm.count("initial")) {
      std::cout << options;
      return vm.count("help") ? 0 : 2;
    }
    const Pose3 initial = parse_pose(vm["initial"].as<std::string>());
    tools::CalibrationConfig config;
    config.coarse.half_extent_m = vm["search-radius-m"].as<double>();
    config.coarse.half_yaw_rad = deg_to_rad(vm["search-yaw-deg"].as<double>());
    if (!(config.coarse.half_extent_m >= 0.0 && config.coarse.half_extent_m <= 50.0) ||
        !(config.coarse.half_yaw_rad >= 0.0 && config.coarse.half_yaw_rad <= kPi))
      throw std::invalid_argument(
          "--search-radius-m must be in [0, 50] m and --search-yaw-deg in [0, 180] deg");
    std::vector<Eigen::Vector3d> background;
    for (const std::string& file : vm["background"].as<std::vector<std::string>>())
      for (const lidar::LidarPoint& p : io::read_pcd(file))
        background.emplace_back(p.x, p.y, p.z);
    std::vector<Eigen::Vector3f> map;
    for (const lidar::LidarPoint& p : io::read_pcd(vm["map"].as<std::string>()))
      map.emplace_back(p.x, p.y, p.z);
    const tools::CalibrationResult result = tools::calibrate_mount(background, map, initial, config);
    const std::string text = report(result);
    std::cout << text;
    if (vm.count("out")) {
      std::ofstream file(vm["out"].as<std::string>());
      file << text;
      if (!file)
        throw std::runtime_error("cannot write " + vm["out"].as<std::string>());
    }
    switch (result.verdict.verdict) {
      case calibration::Verdict::kGood:
        return 0;
      case calibration::Verdict::kAmbiguous:
        return 3;
      case calibration::Verdict::kFailed:
        return 4;
    }
    return 4;
  } catch (const po::error& e) {  // unknown option, missing value: a usage error
    std::fprintf(stderr, "rsu-calibrate: %s (see --help)\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rsu-calibrate: %s\n", e.what());
    return 1;
  }
}
