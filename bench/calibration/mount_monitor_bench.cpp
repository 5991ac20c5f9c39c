// SPDX-License-Identifier: Apache-2.0
// One rotation of the corridor (scenarios/corridor.yaml, VLP-32C and a 128-ring sensor) checked by the
// mount monitor (rsud does it once per rotation), and the baseline in the same run: the range-image
// background test of the rotation's every point, which every rotation costs already.
#include <benchmark/benchmark.h>

#include "bench/perception/corridor_frames.h"
#include "calibration/mount_monitor.h"
#include "lidar/point_eigen.h"
#include "perception/range_image_background.h"

namespace rsu::bench {
namespace {

const char* const kModels[] = {"vlp32c", "generic128"};

struct SensorFrames {
  std::vector<std::vector<lidar::LidarPoint>> reference;  // sensor frame
  std::vector<lidar::LidarPoint> rotation;                // sensor frame, the rotation checked
  std::vector<lidar::LidarPoint> rotation_map;            // the same in the map frame
  Pose3 mount;
};

SensorFrames frames(int model) {
  const sim::Scenario scenario = sim::load_scenario_file(RSU_SOURCE_DIR "/scenarios/corridor.yaml");
  lidar::SensorModel sensor = *lidar::sensor_model_by_name(kModels[model]);
  sensor.rpm = scenario.lidar.model.rpm;
  sim::Scene empty = scenario.scene;
  empty.vehicles.clear();
  const sim::LidarSimulator simulator(sensor, scenario.lidar.mount, scenario.lidar.noise, empty);
  SensorFrames out;
  out.mount = scenario.lidar.mount;
  for (int k = 0; k < 3; ++k)
    out.reference.push_back(simulator.simulate_frame(from_seconds(1.0 + 0.35 * k)).frame.points);
  const lidar::LidarFrame f = simulator.simulate_frame(from_seconds(3.0)).frame;
  out.rotation = f.points;
  out.rotation_map = to_map_frame(f, out.mount);
  return out;
}

void BM_MountCheck(benchmark::State& state, int model) {
  const SensorFrames f = frames(model);
  calibration::MountMonitor monitor(f.reference, f.mount, 50.0, f.mount.z, {});
  // rsud hands the monitor every 4th point of those the background calls static.
  std::vector<lidar::LidarPoint> sample;
  for (std::size_t i = 0; i < f.rotation.size(); i += 4)
    sample.push_back(f.rotation[i]);
  TimeNs t = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(monitor.check_rotation(sample, t));
    t += 100'000'000;
  }
  state.counters["matched"] = static_cast<double>(monitor.last().matches);
  state.counters["points"] = static_cast<double>(f.rotation.size());
}

void BM_BaselineBackgroundTest(benchmark::State& state, int model) {
  const SensorFrames f = frames(model);
  perception::RangeImageBackground background(Eigen::Vector2d(f.mount.x, f.mount.y));
  for (const auto& frame : f.reference) {
    std::vector<lidar::LidarPoint> map = frame;
    const Eigen::Isometry3d t = f.mount.to_isometry();
    for (lidar::LidarPoint& p : map) {
      const Eigen::Vector3d q = t * lidar::position_of(p);
      p.x = static_cast<float>(q.x());
      p.y = static_cast<float>(q.y());
      p.z = static_cast<float>(q.z());
    }
    background.add_training_frame(map);
  }
  for (auto _ : state) {
    std::size_t foreground = 0;
    for (const lidar::LidarPoint& p : f.rotation_map)
      foreground += background.classify(p) == perception::PointClass::foreground;
    benchmark::DoNotOptimize(foreground);
  }
  state.counters["points"] = static_cast<double>(f.rotation_map.size());
}

BENCHMARK_CAPTURE(BM_MountCheck, vlp32c, 0)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_BaselineBackgroundTest, vlp32c, 0)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_MountCheck, generic128, 1)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_BaselineBackgroundTest, generic128, 1)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace rsu::bench
