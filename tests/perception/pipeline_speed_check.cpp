// SPDX-License-Identifier: Apache-2.0
// The per-frame pipeline's speed regression check (issue 16): the pipeline on a simulated VLP-32C
// corridor frame (the frame bench_perception's BM_Pipeline times) against a fixed reference computation
// on the same points, both timed alternately in this one process. The check is on their ratio, never on
// an absolute time: a slower or busier machine slows both. It fails when the ratio is more than
// kAllowedSlowdown times the ratio recorded when the check was written (kBaselineRatio).
//
// Timings on a shared machine are noisy: each repetition times the reference and then the pipeline
// back to back, each over enough frames to last a few milliseconds, and the check uses the median of the
// per-repetition ratios, so that a build preempting one block shifts one ratio, not the result.
//
// Usage: pipeline_speed_check [--slowdown N]
//   --slowdown N  runs the pipeline N times per frame (a pipeline N times slower): the second ctest
//                 runs it with N = 4 and expects the check to report a regression, so that the check is
//                 shown to be able to fail.
// Exit status 0: within the limit; 1: a regression (the line "REGRESSION" says by how much); 2: usage.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "corridor_frames.h"
#include "perception/pipeline.h"

namespace {

using rsu::lidar::LidarPoint;
using namespace rsu::perception;

// Pipeline time / reference time per frame: GCC Release, 2 cores shared with other engineers' builds.
// When this check was written (load average 5-6) 9 runs gave 0.24-0.28; the pipeline has been made
// faster since (prepared fixes, the incremental clustering): at d5713de, load average 2-4, 6 runs gave
// 0.16-0.21, and with --slowdown 3 only 0.41-0.48, under the old limit (0.52): the check could no
// longer fail. Re-measure and update this when the pipeline gets faster.
constexpr double kBaselineRatio = 0.18;
constexpr double kAllowedSlowdown = 2.0;
constexpr int kRepetitions = 21;
// The reference costs about 4 pipeline frames: one of it per block balances the two blocks' lengths.
constexpr int kPipelineFramesPerBlock = 4;
constexpr int kReferenceFramesPerBlock = 1;

// The fixed reference: each point's range and azimuth, the points sorted by (elevation row, azimuth)
// as a range image would order them, and a count of neighbours closer than 0.5 m along that order.
// Plain float math, a sort and a scan over the same points: the kind of work the pipeline does, in
// code that does not change when the pipeline does.
std::size_t reference_computation(const std::vector<LidarPoint>& frame, const Eigen::Vector3d& lidar) {
  struct Keyed {
    float key;
    float range;
  };
  std::vector<Keyed> keyed;
  keyed.reserve(frame.size());
  for (const LidarPoint& p : frame) {
    const float dx = p.x - static_cast<float>(lidar.x());
    const float dy = p.y - static_cast<float>(lidar.y());
    const float dz = p.z - static_cast<float>(lidar.z());
    const float horizontal = std::sqrt(dx * dx + dy * dy);
    const float row = std::round(std::atan2(dz, horizontal) * 180.0F);
    keyed.push_back({row * 8.0F + std::atan2(dy, dx), std::sqrt(horizontal * horizontal + dz * dz)});
  }
  std::sort(keyed.begin(), keyed.end(), [](const Keyed& a, const Keyed& b) { return a.key < b.key; });
  std::size_t close = 0;
  for (std::size_t i = 1; i < keyed.size(); ++i) {
    close += std::abs(keyed[i].range - keyed[i - 1].range) < 0.5F ? 1U : 0U;
  }
  return close;
}

using Clock = std::chrono::steady_clock;

template <typename Work>
double seconds_of(Work&& work) {
  const auto start = Clock::now();
  work();
  return std::chrono::duration<double>(Clock::now() - start).count();
}

int parse_slowdown(int argc, char** argv) {
  if (argc == 1) {
    return 1;
  }
  if (argc == 3 && std::string(argv[1]) == "--slowdown") {
    const int n = std::atoi(argv[2]);
    if (n >= 1 && n <= 100) {
      return n;
    }
  }
  std::fprintf(stderr, "usage: %s [--slowdown N]  (N in 1..100)\n", argv[0]);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  const int slowdown = parse_slowdown(argc, argv);
  if (slowdown == 0) {
    return 2;
  }
  const rsu::bench::CorridorFrames f = rsu::bench::make_corridor_frames("vlp32c");
  LidarGeometry lidar;
  lidar.position = f.lidar_position;
  PerceptionPipeline pipeline({}, lidar);
  for (const auto& b : f.background) {
    pipeline.add_background_frame(b);
  }
  const AnnouncedVehicle vehicle{{f.vehicle_shape.length, f.vehicle_shape.width, f.vehicle_shape.height},
                                 YawPrior{f.vehicle_pose.yaw + 0.05, 0.17}};

  std::size_t sink = 0;
  std::size_t objects = 0;
  const auto run_pipeline = [&] {
    for (int k = 0; k < kPipelineFramesPerBlock * slowdown; ++k) {
      const PerceptionResult result = pipeline.process(f.frame);
      objects = result.objects.size();
      for (const Detection& object : result.objects) {
        if (object.fit.ok()) {
          sink += pipeline.correct(object, vehicle).ok() ? 1U : 0U;
        }
      }
    }
  };
  const auto run_reference = [&] {
    for (int k = 0; k < kReferenceFramesPerBlock; ++k) {
      sink += reference_computation(f.frame, f.lidar_position);
    }
  };
  run_pipeline();  // warm caches and the allocator
  run_reference();
  if (objects == 0) {
    std::printf("FAILED: the pipeline found no object in the frame; nothing representative is timed\n");
    return 1;
  }

  std::vector<double> ratios;
  double pipeline_s = 0.0;
  double reference_s = 0.0;
  for (int r = 0; r < kRepetitions; ++r) {
    const double ref = seconds_of(run_reference) / kReferenceFramesPerBlock;
    const double pipe = seconds_of(run_pipeline) / kPipelineFramesPerBlock;
    reference_s += ref;
    pipeline_s += pipe;
    ratios.push_back(pipe / ref);
  }
  std::nth_element(ratios.begin(), ratios.begin() + kRepetitions / 2, ratios.end());
  const double ratio = ratios[kRepetitions / 2];
  std::printf(
      "%zu points, %zu objects; per frame: pipeline %.3f ms, reference %.3f ms (means; checksum %zu)\n",
      f.frame.size(), objects, 1e3 * pipeline_s / kRepetitions, 1e3 * reference_s / kRepetitions,
      sink % 1000);
  std::printf("median ratio pipeline/reference over %d repetitions: %.2f (baseline %.2f, limit %.2f)\n",
              kRepetitions, ratio, kBaselineRatio, kAllowedSlowdown * kBaselineRatio);
  if (ratio > kAllowedSlowdown * kBaselineRatio) {
    std::printf("REGRESSION: the per-frame pipeline is %.1fx slower than its baseline (allowed %.1fx)\n",
                ratio / kBaselineRatio, kAllowedSlowdown);
    return 1;
  }
  std::printf("OK: %.2fx the baseline ratio\n", ratio / kBaselineRatio);
  return 0;
}
