// SPDX-License-Identifier: Apache-2.0
// rsu-autoware-sidecar: an RSU's fixes of this vehicle, from DDS, as the vehicle's base_link pose for
// Autoware's ekf_localizer (issue 14 item 3); no ROS installation needed, the DDS types are ROS 2's
// (dds/idl). It reads the RSU's geometry_msgs/PoseWithCovarianceStamped of the vehicle's footprint box
// (rsud's dds.pose_topic, on the RSU's DDS domain) and the vehicle's own pose (Autoware's NDT output), and
// publishes each fix as the base_link pose, yaw resolved with the own heading (lib/ros/base_link_pose.h).
// The loop: Cyclone's listeners only wake the main thread, which takes, converts and writes.
#include <boost/program_options.hpp>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <csignal>
#include <cstdio>
#include <deque>
#include <iostream>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "common/angles.h"
#include "dds/participant.h"
#include "dds/pose_messages.h"
#include "dds/typed_entities.h"
#include "geometry_msgs.h"
#include "ros/base_link_pose.h"
#include "tools/cli/version.h"

namespace rsu::tools::autoware_sidecar {
namespace {

namespace po = boost::program_options;
using PoseStamped = geometry_msgs_msg_dds__PoseWithCovarianceStamped_;
using Clock = std::chrono::steady_clock;

constexpr const char* kAbout =
    "rsu-autoware-sidecar: a roadside unit's fixes of this vehicle as the vehicle's base_link pose for\n"
    "Autoware's ekf_localizer, over DDS (ROS 2 types, Cyclone DDS; no ROS installation needed).\n"
    "\n"
    "usage: rsu-autoware-sidecar --vehicle-id ID [options]\n"
    "\n"
    "Reads the RSU's geometry_msgs/PoseWithCovarianceStamped of the vehicle's footprint box (--rsu-topic on\n"
    "--rsu-domain: rsud's dds.pose_topic, brought to the vehicle by the operator's DDS bridge) and the\n"
    "vehicle's own pose (--own-pose-topic, Autoware's NDT output, on --vehicle-domain), and publishes each\n"
    "fix on --output-topic: the base_link pose (box centre + R(yaw) * the reference offset), the yaw the\n"
    "box's (known modulo pi) on the branch of the own heading, the yaw's variance carried into x and y,\n"
    "z and its variance from the own pose, roll and pitch unknown (variance 1e6), stamped with the sweep\n"
    "time, in --map-frame. Both inputs must be in --map-frame: the RSU's LiDAR pose is surveyed in the\n"
    "vehicle's HD map frame (README, \"Autoware\"). A fix is refused (counted, logged) when no own pose\n"
    "lies within --max-own-pose-age-s of its sweep time, or its yaw is farther than\n"
    "--max-heading-disagreement-deg from the own heading modulo 180 deg (an off-by-90 fit).\n"
    "Feed --output-topic to ekf_localizer's pose input (README). Prints its counters on exit.\n"
    "Exit codes: 0 done, 1 a DDS error, 2 bad usage.\n"
    "\n"
    "options";

struct Options {
  std::uint64_t vehicle_id = 0;
  std::string rsu_topic = "vehicles/{vehicle_id}/rsu/pose_with_covariance";
  std::uint32_t rsu_domain = 0;
  std::string own_pose_topic = "/localization/pose_estimator/pose_with_covariance";
  std::string output_topic = "/localization/pose_estimator/rsu/pose_with_covariance";
  std::uint32_t vehicle_domain = 0;
  std::string cyclone_config;
  std::string map_frame = "map";
  ros::BaseLinkConfig base_link;
  double duration_s = 0.0;
};

// A command line that cannot be run as given: exit code 2.
class UsageError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

std::optional<Options> parse_options(int argc, char** argv) {
  Options o;
  double max_disagreement_deg = 30.0;
  po::options_description desc(kAbout);
  desc.add_options()("help,h", "this help")("version", cli::kVersionHelp)(
      "vehicle-id", po::value(&o.vehicle_id)->required(), "this vehicle's id (as announced to the RSUs)")(
      "rsu-topic", po::value(&o.rsu_topic)->default_value(o.rsu_topic),
      "the RSU's pose topic (ROS name; {vehicle_id} is replaced)")(
      "rsu-domain", po::value(&o.rsu_domain)->default_value(o.rsu_domain), "DDS domain of the RSU's topic")(
      "own-pose-topic", po::value(&o.own_pose_topic)->default_value(o.own_pose_topic),
      "the vehicle's own PoseWithCovarianceStamped (ROS name)")(
      "output-topic", po::value(&o.output_topic)->default_value(o.output_topic),
      "where the base_link poses go (ROS name)")(
      "vehicle-domain", po::value(&o.vehicle_domain)->default_value(o.vehicle_domain),
      "DDS domain of the own pose and the output (ROS_DOMAIN_ID)")(
      "cyclone-config", po::value(&o.cyclone_config),
      "Cyclone DDS XML configuration file (default: Cyclone's defaults or CYCLONEDDS_URI)")(
      "map-frame", po::value(&o.map_frame)->default_value(o.map_frame),
      "frame_id both inputs must carry; the output's")(
      "ref-offset-x-m", po::value(&o.base_link.base_link_offset.x())->default_value(0.0),
      "base_link minus the footprint box centre, forward (m; as rsu-vehicle's)")(
      "ref-offset-y-m", po::value(&o.base_link.base_link_offset.y())->default_value(0.0),
      "base_link minus the footprint box centre, left (m)")(
      "max-own-pose-age-s", po::value(&o.base_link.max_own_pose_age_s)->default_value(0.5),
      "an own pose this close to the sweep time must exist")(
      "max-heading-disagreement-deg", po::value(&max_disagreement_deg)->default_value(max_disagreement_deg),
      "largest box yaw minus own heading (modulo 180 deg) accepted")(
      "duration-s", po::value(&o.duration_s)->default_value(0.0),
      "stop after this long (0: at SIGINT/SIGTERM)");
  po::variables_map vm;
  try {
    po::store(po::parse_command_line(argc, argv, desc), vm);
    if (vm.count("help")) {
      std::cout << desc << "\n";
      return std::nullopt;
    }
    po::notify(vm);
  } catch (const po::error& e) {
    throw UsageError(e.what());
  }
  if (o.vehicle_id == 0)
    throw UsageError("--vehicle-id must not be 0");
  if (!(o.base_link.max_own_pose_age_s > 0.0 && o.base_link.max_own_pose_age_s <= 10.0))
    throw UsageError("--max-own-pose-age-s must be in (0, 10]");
  if (!(max_disagreement_deg > 0.0 && max_disagreement_deg < 90.0))
    throw UsageError("--max-heading-disagreement-deg must be in (0, 90)");
  if (!(o.duration_s >= 0.0))
    throw UsageError("--duration-s must be >= 0");
  if (o.rsu_topic.empty() || o.own_pose_topic.empty() || o.output_topic.empty())
    throw UsageError("topics must not be empty");
  o.base_link.max_heading_disagreement_rad = deg_to_rad(max_disagreement_deg);
  const std::string placeholder = "{vehicle_id}";
  if (const auto at = o.rsu_topic.find(placeholder); at != std::string::npos)
    o.rsu_topic.replace(at, placeholder.size(), std::to_string(o.vehicle_id));
  return o;
}

std::atomic<bool> g_stop{false};
extern "C" void on_signal(int) {
  g_stop = true;
}

// Wakes the main loop from Cyclone's listener threads.
class Wakeup {
 public:
  void notify() {
    {
      std::lock_guard lock(mutex_);
      pending_ = true;
    }
    cv_.notify_one();
  }
  void wait_for(std::chrono::milliseconds timeout) {
    std::unique_lock lock(mutex_);
    cv_.wait_for(lock, timeout, [this] { return pending_; });
    pending_ = false;
  }

 private:
  std::mutex mutex_;
  std::condition_variable cv_;
  bool pending_ = false;
};

struct Counters {
  std::uint64_t own_poses = 0;
  std::uint64_t own_poses_refused = 0;  // bad stamp or another frame
  std::uint64_t fixes = 0;
  std::uint64_t fixes_bad_stamp_or_frame = 0;
  std::uint64_t published = 0;
  std::uint64_t write_errors = 0;
  std::array<std::uint64_t, static_cast<std::size_t>(ros::BaseLinkRefusal::kCount)> refused{};
};

// The first few of each kind of refusal on stderr, then only counted.
void log_refusal(const std::string& what, std::uint64_t count_so_far) {
  constexpr std::uint64_t kLogFirst = 5;
  if (count_so_far <= kLogFirst)
    std::fprintf(stderr, "rsu-autoware-sidecar: %s%s\n", what.c_str(),
                 count_so_far == kLogFirst ? " (further ones only counted)" : "");
}

std::optional<ros::StampedPose> stamped_in_frame(const PoseStamped& m, const std::string& frame) {
  const std::optional<TimeNs> stamp = dds::from_msg_time(m.header.stamp);
  if (!stamp || m.header.frame_id == nullptr || frame != m.header.frame_id)
    return std::nullopt;
  return ros::StampedPose{*stamp, dds::from_msg_pose(m.pose)};
}

int run(const Options& o) {
  dds::Participant vehicle_side({o.vehicle_domain, o.cyclone_config});
  std::unique_ptr<dds::Participant> rsu_own;
  if (o.rsu_domain != o.vehicle_domain)
    rsu_own = std::make_unique<dds::Participant>(dds::ParticipantConfig{o.rsu_domain, o.cyclone_config});
  const dds::Participant& rsu_side = rsu_own ? *rsu_own : vehicle_side;

  const auto& type = geometry_msgs_msg_dds__PoseWithCovarianceStamped__desc;
  dds::Topic own_topic(vehicle_side, dds::ros_topic(o.own_pose_topic), type);
  dds::Topic rsu_topic(rsu_side, dds::ros_topic(o.rsu_topic), type);
  dds::Topic output_topic(vehicle_side, dds::ros_topic(o.output_topic), type);
  Wakeup wakeup;
  // Own poses come at NDT's rate (10-50 Hz): the loop takes them at least every 100 ms.
  dds::QosConfig own_qos;
  own_qos.history_depth = 64;
  dds::QosConfig fix_qos;
  fix_qos.history_depth = 16;
  dds::Writer<PoseStamped> writer(vehicle_side, output_topic, fix_qos);
  dds::Reader<PoseStamped> own_reader(vehicle_side, own_topic, own_qos, [&wakeup] { wakeup.notify(); });
  dds::Reader<PoseStamped> fix_reader(rsu_side, rsu_topic, fix_qos, [&wakeup] { wakeup.notify(); });
  std::fprintf(
      stderr,
      "rsu-autoware-sidecar: vehicle %llu: fixes from %s (domain %u) + own poses from %s -> %s (domain %u)\n",
      static_cast<unsigned long long>(o.vehicle_id), dds::ros_topic(o.rsu_topic).c_str(), o.rsu_domain,
      dds::ros_topic(o.own_pose_topic).c_str(), dds::ros_topic(o.output_topic).c_str(), o.vehicle_domain);

  std::deque<ros::StampedPose> own;  // the last few seconds of own poses, by arrival
  constexpr std::size_t kOwnKept = 256;
  Counters n;
  const auto end =
      Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(o.duration_s));
  while (!g_stop && (o.duration_s == 0.0 || Clock::now() < end)) {
    wakeup.wait_for(std::chrono::milliseconds(100));
    own_reader.take(256, [&](const PoseStamped& m, const dds_sample_info_t&) {
      ++n.own_poses;
      const std::optional<ros::StampedPose> p = stamped_in_frame(m, o.map_frame);
      if (!p) {
        log_refusal("own pose refused: bad stamp or frame_id not " + o.map_frame, ++n.own_poses_refused);
        return;
      }
      own.push_back(*p);
      if (own.size() > kOwnKept)
        own.pop_front();
    });
    fix_reader.take(64, [&](const PoseStamped& m, const dds_sample_info_t&) {
      ++n.fixes;
      const std::optional<ros::StampedPose> fix = stamped_in_frame(m, o.map_frame);
      if (!fix) {
        log_refusal("fix refused: bad stamp or frame_id not " + o.map_frame, ++n.fixes_bad_stamp_or_frame);
        return;
      }
      const std::vector<ros::StampedPose> recent(own.begin(), own.end());
      const ros::BaseLinkResult r = ros::base_link_pose(*fix, recent, o.base_link);
      if (r.refusal != ros::BaseLinkRefusal::kNone) {
        log_refusal("fix refused: " + std::string(ros::refusal_name(r.refusal)),
                    ++n.refused[static_cast<std::size_t>(r.refusal)]);
        return;
      }
      PoseStamped out{};
      out.header.stamp = dds::to_msg_time(fix->stamp);  // when the LiDAR swept the vehicle
      out.header.frame_id = const_cast<char*>(o.map_frame.c_str());
      dds::to_msg_pose(r.pose, out.pose);
      try {
        writer.write(out);
        ++n.published;
      } catch (const std::exception& e) {
        log_refusal(std::string("write failed: ") + e.what(), ++n.write_errors);
      }
    });
  }
  std::printf(
      "own_poses %llu\nown_poses_refused %llu\nfixes %llu\nfixes_bad_stamp_or_frame %llu\npublished %llu\n"
      "write_errors %llu\n",
      static_cast<unsigned long long>(n.own_poses), static_cast<unsigned long long>(n.own_poses_refused),
      static_cast<unsigned long long>(n.fixes), static_cast<unsigned long long>(n.fixes_bad_stamp_or_frame),
      static_cast<unsigned long long>(n.published), static_cast<unsigned long long>(n.write_errors));
  for (std::size_t i = 1; i < n.refused.size(); ++i)
    std::printf("refused.%s %llu\n",
                std::string(ros::refusal_name(static_cast<ros::BaseLinkRefusal>(i))).c_str(),
                static_cast<unsigned long long>(n.refused[i]));
  return 0;
}

}  // namespace
}  // namespace rsu::tools::autoware_sidecar

int main(int argc, char** argv) {
  namespace sidecar = rsu::tools::autoware_sidecar;
  if (rsu::tools::cli::print_version_if_asked(argc, argv, "rsu-autoware-sidecar"))
    return 0;
  std::optional<sidecar::Options> options;
  try {
    options = sidecar::parse_options(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rsu-autoware-sidecar: %s (see --help)\n", e.what());
    return 2;
  }
  if (!options)
    return 0;
  std::signal(SIGINT, sidecar::on_signal);
  std::signal(SIGTERM, sidecar::on_signal);
  try {
    return sidecar::run(*options);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rsu-autoware-sidecar: %s\n", e.what());
    return 1;
  }
}
