// SPDX-License-Identifier: Apache-2.0
// RsuCore end to end, with real Velodyne packets of a simulated roadside LiDAR (issue #4 targets:
// p99 latency <= 5 ms, >= 20k announcements/s on one core), and an Ouster OS1-128's at 2048x10
// (issue 16 item 3: a dense sensor; sim/ouster_simulator.h).
//
// Latency is defined as in the issue: from the arrival of the last packet that holds a point of the
// vehicle (a return the simulator labels as the vehicle's: the points its cluster is made of) to the
// moment the correction's bytes are ready. It has two parts:
//  - waiting for the sweep: the cluster is released only once the sweep is far enough past it that no
//    later point can join (sweep_clusterer.h), i.e. a few more packets must arrive;
//  - compute: the measured time RsuCore spends on every packet.
// Both are accounted by replaying the packets through a single-server queue on one core: packet k
// arrives when its last firing is over (the sensor's own timing), its processing starts when it has
// arrived and the previous packet is done, and takes the measured wall time. The latency of a
// correction emitted while processing packet e is finish(e) - arrival(last packet with the vehicle).
// The queue is run twice: with each packet's wall time (latency_*: what this run's core gave, other
// processes' preemption included) and with its thread CPU time (latency_cpu_*: a core of its own, the
// figure that stays comparable on a shared machine).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <memory>
#include <string>
#include <vector>

#include "common/angles.h"
#include "core/rsu_core.h"
#include "lidar/point_eigen.h"
#include "lidar/velodyne_packet.h"
#include "sim/lidar_simulator.h"
#include "sim/ouster_simulator.h"
#include "sim/scene.h"
#include "v2i/wire_codec.h"

namespace rsu::core {
namespace {

constexpr int kLearnRotations = 4;
constexpr int kBusyRotations = 40;
const Pose3 kMount{.x = 0.0, .y = -8.5, .z = 2.0};  // the corridor's sidewalk RSU (scenarios/corridor.yaml)

sim::Scene street() {
  sim::Scene s;
  s.ground.half_extent_m = 80.0;
  s.buildings.push_back({.x = 0.0, .y = -26.0, .length = 120.0, .width = 30.0, .height = 30.0});
  s.buildings.push_back({.x = 0.0, .y = 26.0, .length = 120.0, .width = 30.0, .height = 30.0});
  s.poles.push_back({.x = -12.5, .y = -7.4, .radius = 0.12, .height = 8.0});
  s.poles.push_back({.x = 12.5, .y = -7.4, .radius = 0.12, .height = 8.0});
  return s;
}

struct Packet {
  std::vector<std::uint8_t> bytes;
  TimeNs arrival = 0;  // last firing of the packet: when the sensor sends it
  bool has_vehicle = false;
};

// How the vehicle moves during the recording (kBusyRotations rotations, 4 s).
// Where the mount check of a completed rotation runs (BM_EndToEndLatency's fourth argument).
enum class MountCheck { kBeforeBatch = 0, kAfterSend = 1, kOwnThread = 2 };

enum class Drive {
  // From `range_m` east along the lane towards the LiDAR: 8 m at 2 m/s, but no nearer than the issue's
  // 5 m (issue 16: "the vehicle at 5-40 m and driving in"; from 10 m that is 5.7 m at 1.4 m/s).
  approach = 0,
  hold = 1,  // 2 m along the lane centred on `range_m`: stays within ~0.4 m of it
  // 8 m at 2 m/s whatever the range: from 10 m to 3.6 m, nearer than the 5 m (the near car's
  // cluster at its largest; the case this benchmark ran as "approach" before).
  approach_past = 2,
};

// Where the vehicle drives in this street: along the lane 3.25 m beside the LiDAR, east from x0 (west of
// the mast) at `speed` for kBusyRotations rotations.
struct DriveGeometry {
  double lane_y = -5.25;
  double x0 = 0.0;  // the vehicle centre starts at x = -x0
  double speed_mps = 0.0;
  double travel_m = 0.0;
  double min_range_m = 0.0;  // of the vehicle's centre from the LiDAR over the drive
  double max_range_m = 0.0;
};

DriveGeometry drive_geometry(double range_m, Drive drive) {
  constexpr double kNearestM = 5.0;  // Drive::approach ends here at the nearest
  constexpr double kSeconds = kBusyRotations * 0.1;
  DriveGeometry g;
  const double lateral = g.lane_y - kMount.y;
  const auto x_at = [&](double r) { return std::sqrt(std::max(0.0, r * r - lateral * lateral)); };
  const double x_at_range = x_at(range_m);
  if (drive == Drive::hold) {
    g.speed_mps = 0.5;
    g.travel_m = g.speed_mps * kSeconds;
    g.x0 = x_at_range + g.travel_m / 2.0;
  } else {
    g.x0 = x_at_range;
    g.travel_m = drive == Drive::approach ? std::min(8.0, std::max(0.0, g.x0 - x_at(kNearestM))) : 8.0;
    g.speed_mps = g.travel_m / kSeconds;
  }
  g.max_range_m = std::hypot(g.x0, lateral);
  g.min_range_m = std::hypot(std::max(0.0, g.x0 - g.travel_m), lateral);
  return g;
}

const char* drive_name(Drive drive) {
  return drive == Drive::approach ? "approach" : drive == Drive::hold ? "hold" : "approach past 5 m";
}

// Packets of `rotations` rotations: empty street for the first kLearnRotations, then a vehicle
// driving east along the road (so each rotation sees it at a new place).
struct Recording {
  std::string model;
  double range_m = 0.0;
  Drive drive = Drive::approach;
  double speed_mps = 0.0;
  double min_range_m = 0.0;  // of the vehicle's centre over the recording
  double max_range_m = 0.0;
  std::vector<Packet> packets;
  std::size_t first_busy = 0;
  Pose2 vehicle_at_start;  // at t_busy, then east at speed_mps
  TimeNs t_busy = 0;
  std::size_t packets_per_100ms = 75;  // the announcements' cadence (10 Hz) in packets
};

// The dense sensor: a simulated OS1-128 at 2048 columns x 10 Hz (2.6 M pixels/s), 24.8 kB packets.
const sim::OusterSpec kOuster{"os1-128", "2048x10", lidar::ouster::UdpProfile::rng19_rfl8_sig16_nir16};
bool is_ouster(const std::string& model) {
  return model == kOuster.model;
}
const std::string& ouster_metadata() {
  static const std::string json = sim::ouster_metadata_json(kOuster);
  return json;
}

// The Ouster's packets of the same drive (sim_empty before busy_from, sim_busy after), each marked when
// a return of it is the vehicle's (the ray caster's truth).
void record_ouster(Recording& r, const sim::Scene& empty, const sim::Scene& busy, TimeNs t_busy,
                   TimeNs t_end) {
  const lidar::ouster::Metadata m = lidar::ouster::parse_metadata(ouster_metadata(), "simulated");
  const sim::Raycaster rc_empty(empty);
  const sim::Raycaster rc_busy(busy);
  const sim::NoiseModel noise;
  const sim::OusterSimulator sim_empty(m, kMount, noise, rc_empty);
  const sim::OusterSimulator sim_busy(m, kMount, noise, rc_busy);
  const std::int64_t busy_from = sim_busy.packet_index_at(t_busy);
  const std::int64_t last = sim_busy.packet_index_at(t_end);
  r.first_busy = static_cast<std::size_t>(busy_from);
  r.packets_per_100ms = static_cast<std::size_t>(sim_busy.packets_per_frame() * m.frequency_hz / 10);
  for (std::int64_t k = 0; k < last; ++k) {
    Packet p;
    const std::size_t vehicle = (k < busy_from ? sim_empty : sim_busy).packet(k, 0, p.bytes);
    p.arrival = sim_busy.packet_time_ns(k + 1);  // sent once its last column has fired
    p.has_vehicle = vehicle > 0;
    r.packets.push_back(std::move(p));
  }
}

TimeNs busy_from_time(const sim::LidarSimulator& sim, std::int64_t busy_from) {
  return sim.simulate_packet(busy_from).blocks.first_firing_ns;
}

Recording record(const std::string& model_name, double range_m, Drive drive) {
  Recording r;
  r.model = model_name;
  r.range_m = range_m;
  r.drive = drive;
  const DriveGeometry g = drive_geometry(range_m, drive);
  const double lane_y = g.lane_y;
  const double speed = g.speed_mps;
  const double x0 = g.x0;
  r.speed_mps = speed;
  r.max_range_m = g.max_range_m;
  r.min_range_m = g.min_range_m;
  sim::Scene empty = street();
  sim::Scene busy = empty;
  sim::Vehicle v;
  v.id = 1;
  const TimeNs t_busy = (kLearnRotations + 0.5) * 100 * kNsPerMs;
  const TimeNs t_end = t_busy + kBusyRotations * 100 * kNsPerMs;
  v.trajectory = sim::Waypoints{
      {{t_busy, {-x0, lane_y, 0.0}}, {t_end, {-x0 + speed * to_seconds(t_end - t_busy), lane_y, 0.0}}}};
  r.t_busy = t_busy;
  busy.vehicles.push_back(v);
  r.vehicle_at_start = {-x0, lane_y, 0.0};
  if (is_ouster(model_name)) {
    record_ouster(r, empty, busy, t_busy, t_end);
    return r;
  }
  const lidar::SensorModel model = *lidar::sensor_model_by_name(model_name);
  const sim::NoiseModel noise;
  const sim::LidarSimulator sim_empty(model, kMount, noise, empty);
  const sim::LidarSimulator sim_busy(model, kMount, noise, busy);
  const std::int64_t busy_from = sim_busy.packet_index_at(t_busy);
  const std::int64_t last = sim_busy.packet_index_at(t_end);
  for (std::int64_t k = 0; k < last; ++k) {
    const sim::LidarSimulator& source = k < busy_from ? sim_empty : sim_busy;
    const lidar::PacketReturns returns = source.simulate_packet(k);
    Packet p;
    p.bytes.resize(lidar::kPacketBytes);
    lidar::encode_packet(model, returns,
                         std::span<std::uint8_t, lidar::kPacketBytes>(p.bytes.data(), lidar::kPacketBytes));
    const TimeNs next_start =
        source.simulate_packet(k + 1).blocks.first_firing_ns;  // packets are back to back
    p.arrival = next_start;
    if (k < busy_from)
      r.first_busy = static_cast<std::size_t>(k + 1);
    r.packets.push_back(p);
  }
  // Ground truth of "holds a point of the vehicle": the simulator's label of every return (the same
  // returns, bit for bit, as the packets), so no box test guesses which points the cluster has.
  for (TimeNs t = busy_from_time(sim_busy, busy_from); t < t_end; t += sim_busy.rotation_period_ns()) {
    const sim::SimulatedFrame frame = sim_busy.simulate_frame(t);
    for (std::size_t i = 0; i < frame.frame.points.size(); ++i) {
      if (frame.truth[i].surface != sim::SurfaceClass::kVehicle)
        continue;
      const std::int64_t k = sim_busy.packet_index_at(frame.frame.points[i].time_ns);
      if (k >= busy_from && k < last)
        r.packets[static_cast<std::size_t>(k)].has_vehicle = true;
    }
  }
  return r;
}

const Recording& recording(int model_index, int range_m, Drive drive) {
  static std::vector<std::unique_ptr<Recording>> cache;  // benchmark fixtures only: built once per case
  const std::string model = model_index == 0 ? "vlp16" : model_index == 1 ? "vlp32c" : kOuster.model;
  for (const auto& r : cache) {
    if (r->model == model && r->range_m == range_m && r->drive == drive)
      return *r;
  }
  // An Ouster recording is ~140 MB: one kept at a time (its cases run one after the other).
  std::erase_if(cache, [](const auto& r) { return is_ouster(r->model); });
  cache.push_back(std::make_unique<Recording>(record(model, range_m, drive)));
  return *cache.back();
}

RsuCoreConfig bench_config(const std::string& model) {
  RsuCoreConfig c;
  c.sensor_model = model;
  if (is_ouster(model))
    c.sensor_options.metadata_text = ouster_metadata();
  c.mount = kMount;
  // The mount check runs as rsud runs it (its cost is on the path measured). This street holds the
  // LiDAR weakly along it (two facades, two poles): judged one rotation at a time, its noise there had
  // stopped the fixes falsely (40-95 % of the corrections withheld) until the monitor decided such
  // directions on a second's mean (calibration/mount_monitor.h, weak_evidence_window).
  c.background.learning_frames = kLearnRotations - 2;  // the first rotation is partial
  // Unsigned: this measures the LiDAR path and the registry; bench/v2i measures signing and verifying.
  c.security.mode = v2i::SecurityMode::kInsecure;
  return c;
}

TimeNs thread_cpu_ns() {
  timespec t{};
  ::clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<TimeNs>(t.tv_sec) * kNsPerSecond + t.tv_nsec;
}

double percentile(std::vector<double> v, double q) {
  if (v.empty())
    return 0.0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<std::size_t>(q * static_cast<double>(v.size())))];
}

void BM_EndToEndLatency(benchmark::State& state) {
  const Recording& rec = recording(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)),
                                   static_cast<Drive>(state.range(2)));
  const auto mount_check = static_cast<MountCheck>(state.range(3));
  RsuCoreConfig config = bench_config(rec.model);
  config.prepare_fixes = state.range(4) >= 1;
  config.release_fixed_open = state.range(4) != 3;
  const bool prepare_elsewhere = state.range(4) == 2;
  std::vector<double> latency_ms;
  std::vector<double> latency_cpu_ms;
  std::vector<double> wait_ms;
  std::vector<double> compute_us;
  std::vector<double> compute_cpu_us;
  std::size_t corrections = 0;
  std::uint64_t mount_stops = 0;    // over the iterations (the fixes the check stopped are not measured)
  std::uint64_t prepared_used = 0;  // fixes prepared ahead of the release and used by it
  std::uint64_t prepared = 0;       // fixes prepared
  for (auto _ : state) {
    state.PauseTiming();
    RsuCore core(config);
    for (std::size_t k = 0; k < rec.first_busy; ++k)
      core.on_lidar_packet(rec.packets[k].bytes, rec.packets[k].arrival);
    v2i::VehicleAnnouncement a;
    a.vehicle_id = 1;
    a.sequence = 1;
    a.size = {4.89, 1.92, 1.70};
    a.pose = rec.vehicle_at_start;
    a.pose_covariance = Eigen::Vector3d(0.25, 0.25, 0.01).asDiagonal();
    a.speed_mps = rec.speed_mps;
    a.yaw_rate_rps = 0.0;
    a.reply_to = {"192.0.2.1", 47001};
    a.generation_time = rec.packets[rec.first_busy].arrival;
    core.on_datagram(v2i::encode_v2i_message(a), {"192.0.2.1", 47001}, a.generation_time);
    state.ResumeTiming();

    TimeNs finish = 0;
    TimeNs finish_cpu = 0;
    TimeNs last_vehicle_arrival = -1;
    for (std::size_t k = rec.first_busy; k < rec.packets.size(); ++k) {
      const Packet& p = rec.packets[k];
      if (p.has_vehicle)
        last_vehicle_arrival = p.arrival;
      const TimeNs c0 = thread_cpu_ns();
      const auto t0 = std::chrono::steady_clock::now();
      const LidarStepResult out = core.on_lidar_packet(p.bytes, p.arrival);
      const auto t1 = std::chrono::steady_clock::now();
      const TimeNs compute_cpu = thread_cpu_ns() - c0;
      const TimeNs compute = std::chrono::duration_cast<std::chrono::nanoseconds>(t1 - t0).count();
      compute_us.push_back(static_cast<double>(compute) * 1e-3);
      compute_cpu_us.push_back(static_cast<double>(compute_cpu) * 1e-3);
      finish = std::max(finish, p.arrival) + compute;
      finish_cpu = std::max(finish_cpu, p.arrival) + compute_cpu;
      // Announcements keep coming at 10 Hz (outside the latency path, but on the same core).
      if ((k - rec.first_busy) % rec.packets_per_100ms == 0) {
        a.sequence += 1;
        a.generation_time = p.arrival;
        a.pose.x = rec.vehicle_at_start.x + rec.speed_mps * to_seconds(p.arrival - rec.t_busy);
        core.on_datagram(v2i::encode_v2i_message(a), {"192.0.2.1", 47001}, p.arrival);
      }
      for (std::size_t i = 0; i < out.corrections.size(); ++i) {
        ++corrections;
        if (last_vehicle_arrival < 0)
          continue;
        latency_ms.push_back(static_cast<double>(finish - last_vehicle_arrival) * 1e-6);
        latency_cpu_ms.push_back(static_cast<double>(finish_cpu - last_vehicle_arrival) * 1e-6);
        wait_ms.push_back(static_cast<double>(p.arrival - last_vehicle_arrival) * 1e-6);
      }
      // What the step prepares for the next releases (fits and fixes), once its corrections are sent: as
      // rsud by default, on this core, where the next packet waits for it; or on a thread of its own
      // (perception.prepare_thread), modelled as one that always keeps up (each result back before the
      // next packet: a bound, which rsud's thread did not reach on 2 cores).
      if (prepare_elsewhere) {
        for (Preparation w = core.take_preparation(); !w.empty(); w = core.take_preparation())
          core.record_prepared(prepare(std::move(w)));
      }
      const TimeNs q0 = thread_cpu_ns();
      const auto qw = std::chrono::steady_clock::now();
      core.prepare_pending();
      const TimeNs prepare_cpu = thread_cpu_ns() - q0;
      const TimeNs prepare =
          std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() - qw).count();
      finish += prepare;
      finish_cpu += prepare_cpu;
      compute_us.back() += static_cast<double>(prepare) * 1e-3;
      compute_cpu_us.back() += static_cast<double>(prepare_cpu) * 1e-3;
      // The mount check of a completed rotation. As rsud: on its own thread (another core), so the next
      // packet does not wait for it; its cost is not on this core's queue. Baselines: after the
      // corrections are sent, on this core (the next packet waits for it), or not called here, so that
      // the next step runs it before its own batch (on the corrections' path, as before issue 16).
      if (mount_check == MountCheck::kBeforeBatch)
        continue;
      if (mount_check == MountCheck::kOwnThread) {
        core.record_mount_checks(check_mount_rotations(core.take_mount_rotations()));
        continue;
      }
      const TimeNs m0 = thread_cpu_ns();
      const auto w0 = std::chrono::steady_clock::now();
      core.check_mount_pending();
      finish +=
          std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() - w0).count();
      finish_cpu += thread_cpu_ns() - m0;
    }
    mount_stops += core.mount_monitor() ? core.mount_monitor()->stats().stops : 0;
    prepared_used += core.lidar_stats().fixes_prepared_used;
    prepared += core.lidar_stats().fixes_prepared;
  }
  state.counters["mount_stops"] = static_cast<double>(mount_stops);
  const auto per_rotation = [&](std::uint64_t n) {
    return static_cast<double>(n) / static_cast<double>(state.iterations() * kBusyRotations);
  };
  state.counters["fixes_prepared_per_rotation"] = per_rotation(prepared);
  state.counters["prepared_fixes_used_per_rotation"] = per_rotation(prepared_used);
  state.counters["corrections_per_rotation"] =
      static_cast<double>(corrections) / static_cast<double>(state.iterations() * kBusyRotations);
  state.counters["latency_p50_ms"] = percentile(latency_ms, 0.50);
  state.counters["latency_p99_ms"] = percentile(latency_ms, 0.99);
  state.counters["latency_max_ms"] = percentile(latency_ms, 1.0);
  state.counters["latency_cpu_p50_ms"] = percentile(latency_cpu_ms, 0.50);
  state.counters["latency_cpu_p99_ms"] = percentile(latency_cpu_ms, 0.99);
  state.counters["packet_compute_cpu_p99_us"] = percentile(compute_cpu_us, 0.99);
  state.counters["packet_compute_cpu_max_us"] = percentile(compute_cpu_us, 1.0);
  state.counters["sweep_wait_p99_ms"] = percentile(wait_ms, 0.99);
  state.counters["packet_compute_p99_us"] = percentile(compute_us, 0.99);
  state.counters["packet_compute_max_us"] = percentile(compute_us, 1.0);
  char label[192];
  std::snprintf(label, sizeof label, "%s %s, vehicle centre %.1f-%.1f m%s%s", rec.model.c_str(),
                drive_name(rec.drive), rec.min_range_m, rec.max_range_m,
                mount_check == MountCheck::kOwnThread ? ""
                : mount_check == MountCheck::kAfterSend
                    ? ", mount check on the loop after the send (baseline)"
                    : ", mount check before the batch (baseline)",
                !config.prepare_fixes        ? ", fixes not prepared (baseline)"
                : !config.release_fixed_open ? ", no cluster released open (baseline)"
                : prepare_elsewhere          ? ", fixes prepared on a thread that keeps up"
                                             : "");
  state.SetLabel(label);
}
// Args: sensor (0 = VLP-16, 1 = VLP-32C, 2 = OS1-128 2048x10), range of the vehicle from the LiDAR (m), the
// issue's 5-40 m, drive (Drive: 0 = approach: starts at that range and drives in, to 5 m at the nearest;
// 1 = hold: stays there; 2 = approach past 5 m: 8 m in, from 10 m to 3.6 m), mount check (MountCheck:
// 2 = on a thread of its own, as rsud does; 1 = on the loop after the corrections are sent; 0 = before the
// next batch), fixes prepared while the sweep closes the cluster (RsuCoreConfig::prepare_fixes: 1 = on the
// loop after the send, as rsud by default; 2 = on another thread, modelled as one whose results are always
// back before the next packet, so a bound; 0 = not, the baseline; 3 = on the loop, every cluster released
// only once closed: RsuCoreConfig::release_fixed_open false, its baseline).
BENCHMARK(BM_EndToEndLatency)
    ->ArgsProduct({{0, 1}, {10, 20, 30, 40}, {0, 1}, {0, 1, 2}, {1}})
    ->ArgsProduct({{0, 1}, {10, 20, 30, 40}, {0, 1}, {2}, {3}})
    ->Args({0, 10, 2, 2, 3})
    ->Args({1, 10, 2, 2, 3})
    ->ArgsProduct({{0, 1}, {10, 20, 30, 40}, {0, 1}, {2}, {0}})
    ->ArgsProduct({{1}, {10, 20, 30, 40}, {0, 1}, {2}, {2}})
    ->Args({0, 10, 2, 2, 1})
    ->Args({1, 10, 2, 2, 1})
    ->Args({0, 10, 2, 2, 0})
    ->Args({1, 10, 2, 2, 0})
    ->Iterations(3)
    ->Unit(benchmark::kMillisecond);
// The dense sensor, as rsud runs it (the mount check on its own thread), and with the check on the loop.
BENCHMARK(BM_EndToEndLatency)
    ->ArgsProduct({{2}, {10, 20, 30, 40}, {0, 1}, {2, 1}, {1}})
    ->ArgsProduct({{2}, {10, 20, 30, 40}, {0, 1}, {2}, {2}})
    ->ArgsProduct({{2}, {10, 20, 30, 40}, {0, 1}, {2}, {3}})
    ->Args({2, 10, 2, 2, 1})
    ->Args({2, 10, 2, 1, 1})
    ->Args({2, 10, 2, 2, 0})
    ->Args({2, 10, 2, 2, 3})
    ->Iterations(3)
    ->Unit(benchmark::kMillisecond);

// The release rule alone (sweep_clusterer.h), both variants on the same simulated frames: the vehicle's
// returns (simulator truth, so background removal plays no part) and everything else as background,
// fed packet by packet. The wait is counted in packets, from the last packet that holds a point of
// the released cluster (read from the cluster's own points) to the packet after which it is released,
// i.e. sensor time, without compute. Args: sensor, range (m), rule (0 = offset spread only,
// 1 = laser-aware), drive (Drive: 0 = approach, 1 = hold, 2 = approach past 5 m).
void BM_SweepReleaseWait(benchmark::State& state) {
  const std::string model_name = state.range(0) == 0 ? "vlp16" : "vlp32c";
  const bool laser_aware = state.range(2) == 1;
  const auto drive = static_cast<Drive>(state.range(3));
  const lidar::SensorModel model = *lidar::sensor_model_by_name(model_name);
  const DriveGeometry g = drive_geometry(static_cast<double>(state.range(1)), drive);
  const double lane_y = g.lane_y;
  const double x0 = g.x0;
  const double travel = g.travel_m;
  sim::Scene scene = street();
  sim::Vehicle v;
  v.id = 1;
  const TimeNs t_end = kBusyRotations * 100 * kNsPerMs;
  v.trajectory = sim::Waypoints{{{0, {-x0, lane_y, 0.0}}, {t_end, {-x0 + travel, lane_y, 0.0}}}};
  scene.vehicles.push_back(v);
  const sim::LidarSimulator sim(model, kMount, sim::NoiseModel{}, scene);
  const Eigen::Isometry3d to_map = kMount.to_isometry();
  std::vector<std::vector<lidar::LidarPoint>> frames;
  std::vector<std::vector<bool>> vehicle;
  for (TimeNs t = 0; t < t_end; t += sim.rotation_period_ns()) {
    const sim::SimulatedFrame f = sim.simulate_frame(t);
    frames.emplace_back();
    vehicle.emplace_back();
    for (std::size_t i = 0; i < f.frame.points.size(); ++i) {
      lidar::LidarPoint p = f.frame.points[i];
      const Eigen::Vector3d m = to_map * lidar::position_of(p);
      p.x = static_cast<float>(m.x());
      p.y = static_cast<float>(m.y());
      p.z = static_cast<float>(m.z());
      frames.back().push_back(p);
      vehicle.back().push_back(f.truth[i].surface == sim::SurfaceClass::kVehicle);
    }
  }
  std::vector<double> offsets;
  for (const double o : model.azimuth_offset_deg)
    offsets.push_back(deg_to_rad(o));
  const double spread =
      *std::max_element(offsets.begin(), offsets.end()) - *std::min_element(offsets.begin(), offsets.end());
  const double packet_ms =
      12.0 * model.sequence_period_us * static_cast<double>(model.sequences_per_block) * 1e-3;
  const RsuCoreConfig config = bench_config(model_name);
  std::vector<double> wait_ms;
  for (auto _ : state) {
    perception::SweepClusterer sweep =
        laser_aware
            ? perception::SweepClusterer(config.sweep, config.perception.clustering, {kMount.x, kMount.y},
                                         model.rotation_hz(), std::span<const double>(offsets))
            : perception::SweepClusterer(config.sweep, config.perception.clustering, {kMount.x, kMount.y},
                                         model.rotation_hz(), spread);
    std::int64_t packet = -1;
    const auto release = [&] {
      for (const perception::SweptCluster& c : sweep.release_closed()) {
        std::int64_t last = 0;
        for (const lidar::LidarPoint& p : c.points)
          last = std::max(last, sim.packet_index_at(p.time_ns));
        wait_ms.push_back(static_cast<double>(packet - last) * packet_ms);
      }
    };
    for (std::size_t f = 0; f < frames.size(); ++f) {
      for (std::size_t i = 0; i < frames[f].size(); ++i) {
        const std::int64_t k = sim.packet_index_at(frames[f][i].time_ns);
        if (k != packet && packet >= 0)
          release();
        packet = k;
        sweep.add(frames[f][i], vehicle[f][i]);
      }
    }
    release();
  }
  state.counters["releases_per_rotation"] =
      static_cast<double>(wait_ms.size()) / static_cast<double>(state.iterations() * frames.size());
  state.counters["wait_p50_ms"] = percentile(wait_ms, 0.50);
  state.counters["wait_p99_ms"] = percentile(wait_ms, 0.99);
  state.counters["wait_max_ms"] = percentile(wait_ms, 1.0);
  char label[128];
  std::snprintf(label, sizeof label, "%s %s rule, %s, vehicle centre %.1f-%.1f m", model_name.c_str(),
                laser_aware ? "laser-aware" : "spread", drive_name(drive), g.min_range_m, g.max_range_m);
  state.SetLabel(label);
}
BENCHMARK(BM_SweepReleaseWait)
    ->ArgsProduct({{0, 1}, {10, 20, 30, 40}, {0, 1}, {0, 1}})
    ->ArgsProduct({{0, 1}, {10}, {0, 1}, {2}})
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond);

void BM_AnnouncementThroughput(benchmark::State& state) {
  // 1000 vehicles from 1000 hosts, each announcing at 20 Hz: 20k datagrams per second of time.
  constexpr int kVehicles = 1000;
  constexpr int kRounds = 40;
  constexpr TimeNs kSpacing = 50 * kNsPerUs;
  const TimeNs t0 = 1'700'000'000 * kNsPerSecond;
  std::vector<std::vector<std::uint8_t>> datagrams;
  std::vector<SourceEndpoint> sources;
  for (int v = 0; v < kVehicles; ++v) {
    sources.push_back({"10.0." + std::to_string(v / 250) + "." + std::to_string(v % 250 + 1), 47000});
  }
  for (int round = 0; round < kRounds; ++round) {
    for (int v = 0; v < kVehicles; ++v) {
      v2i::VehicleAnnouncement a;
      a.vehicle_id = static_cast<std::uint64_t>(v + 1);
      a.sequence = static_cast<std::uint32_t>(round + 1);
      a.generation_time = t0 + static_cast<TimeNs>(datagrams.size()) * kSpacing;
      a.size = {4.89, 1.92, 1.70};
      a.pose = {static_cast<double>(v), 3.0, 0.1};
      a.pose_covariance = Eigen::Vector3d(0.25, 0.25, 0.01).asDiagonal();
      a.speed_mps = 10.0;
      a.yaw_rate_rps = 0.0;
      a.reply_to = {sources[static_cast<std::size_t>(v)].address, 47000};
      datagrams.push_back(v2i::encode_v2i_message(a));
    }
  }
  RsuCoreConfig config = bench_config("vlp16");
  config.registry.capacity = 2 * kVehicles;
  auto core = std::make_unique<RsuCore>(config);
  std::size_t i = 0;
  std::uint64_t accepted = 0;
  for (auto _ : state) {
    if (i == datagrams.size()) {
      state.PauseTiming();
      core = std::make_unique<RsuCore>(config);
      i = 0;
      state.ResumeTiming();
    }
    const TimeNs now = t0 + static_cast<TimeNs>(i) * kSpacing;
    const DatagramOutcome out = core->on_datagram(datagrams[i], sources[i % kVehicles], now);
    accepted += out.accepted();
    ++i;
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
  state.counters["accepted_fraction"] =
      static_cast<double>(accepted) / static_cast<double>(state.iterations());
}
BENCHMARK(BM_AnnouncementThroughput);

}  // namespace
}  // namespace rsu::core
