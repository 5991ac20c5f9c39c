// SPDX-License-Identifier: Apache-2.0
// Per-frame perception on simulated corridor frames (scenarios/corridor.yaml; VLP-16, VLP-32C and a
// generic 128-ring sensor): this library's pipeline against a baseline written as a PCL user would
// write the paper's pipeline (k-d tree nearest neighbour against the reference frame,
// pcl::EuclideanClusterExtraction, exhaustive 1 deg closeness search, Algorithm 1).
//
// Both sides get the same inputs and the same parameters: reference = three frames with the vehicles
// removed, ground points (z < 0.2 m) dropped first, match radius 0.3 m, clustering in 2D (Autoware's
// use_height: false) with tolerance 0.7 m and 10..20000 points. The baseline's cloud is converted to
// PCL outside the timed loop.
#include <benchmark/benchmark.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/search/kdtree.h>
#include <pcl/segmentation/extract_clusters.h>

#include "corridor_frames.h"
#include "lidar/point_eigen.h"
#include "perception/azimuth_thinning.h"
#include "perception/pipeline.h"
#include "perception/vehicle_fix.h"

namespace {

using rsu::lidar::LidarPoint;
using namespace rsu::perception;

constexpr std::array<const char*, 3> kModels = {"vlp16", "vlp32c", "generic128"};
constexpr float kGroundZ = 0.2F;
constexpr float kMatchRadius = 0.3F;

// Simulating a frame takes longer than processing it: each model's frames are made once.
const rsu::bench::CorridorFrames& frames(int model) {
  static std::array<std::unique_ptr<rsu::bench::CorridorFrames>, kModels.size()> cache;
  auto& slot = cache[static_cast<std::size_t>(model)];
  if (!slot) {
    slot = std::make_unique<rsu::bench::CorridorFrames>(
        rsu::bench::make_corridor_frames(kModels[static_cast<std::size_t>(model)]));
  }
  return *slot;
}

VehicleSize vehicle_size(const rsu::bench::CorridorFrames& f) {
  return {f.vehicle_shape.length, f.vehicle_shape.width, f.vehicle_shape.height};
}

// The vehicle's own yaw estimate as it would announce it, a few degrees off.
YawPrior vehicle_prior(const rsu::bench::CorridorFrames& f) {
  return {f.vehicle_pose.yaw + 0.05, 0.17};
}

LidarGeometry lidar_of(const rsu::bench::CorridorFrames& f) {
  LidarGeometry lidar;
  lidar.position = f.lidar_position;
  return lidar;
}

PerceptionPipeline make_pipeline(const rsu::bench::CorridorFrames& f, const PerceptionConfig& config = {}) {
  PerceptionPipeline p(config, lidar_of(f));
  for (const auto& b : f.background) {
    p.add_background_frame(b);
  }
  return p;
}

void set_counters(benchmark::State& state, const rsu::bench::CorridorFrames& f, std::size_t objects) {
  state.counters["points"] = static_cast<double>(f.frame.size());
  state.counters["objects"] = static_cast<double>(objects);
}

// --- this library -------------------------------------------------------------------------------------

void BM_Pipeline(benchmark::State& state, int model) {
  const auto& f = frames(model);
  const PerceptionPipeline pipeline = make_pipeline(f);
  std::size_t objects = 0;
  for (auto _ : state) {
    const PerceptionResult result = pipeline.process(f.frame);
    for (const auto& object : result.objects) {
      if (object.fit.ok()) {
        benchmark::DoNotOptimize(pipeline.correct(object, {vehicle_size(f), vehicle_prior(f)}));
      }
    }
    objects = result.objects.size();
  }
  set_counters(state, f, objects);
}

void BM_PipelineReferenceFrame(benchmark::State& state, int model) {
  const auto& f = frames(model);
  PerceptionConfig config;
  config.background = BackgroundMethod::reference_frame;
  const PerceptionPipeline pipeline = make_pipeline(f, config);
  std::size_t objects = 0;
  for (auto _ : state) {
    const PerceptionResult result = pipeline.process(f.frame);
    for (const auto& object : result.objects) {
      if (object.fit.ok()) {
        benchmark::DoNotOptimize(pipeline.correct(object, {vehicle_size(f), vehicle_prior(f)}));
      }
    }
    objects = result.objects.size();
  }
  set_counters(state, f, objects);
}

void BM_BackgroundRangeImage(benchmark::State& state, int model) {
  const auto& f = frames(model);
  RangeImageBackground model_bg(f.lidar_xy);
  for (const auto& b : f.background) {
    model_bg.add_training_frame(b);
  }
  const GroundHeightFilter ground;
  for (auto _ : state) {
    benchmark::DoNotOptimize(select_foreground(f.frame, [&](const LidarPoint& p) {
      const PointClass c = ground.classify(p);
      return c == PointClass::foreground ? model_bg.classify(p) : c;
    }));
  }
  set_counters(state, f, 0);
}

std::vector<LidarPoint> concatenated_background(const rsu::bench::CorridorFrames& f) {
  std::vector<LidarPoint> ref;
  for (const auto& b : f.background) {
    for (const auto& p : b) {
      if (p.z >= kGroundZ) {
        ref.push_back(p);
      }
    }
  }
  return ref;
}

void BM_BackgroundReferenceGrid(benchmark::State& state, int model) {
  const auto& f = frames(model);
  const ReferenceFrameBackground model_bg(concatenated_background(f),
                                          {.match_radius_m = static_cast<double>(kMatchRadius)});
  const GroundHeightFilter ground;
  for (auto _ : state) {
    benchmark::DoNotOptimize(select_foreground(f.frame, [&](const LidarPoint& p) {
      const PointClass c = ground.classify(p);
      return c == PointClass::foreground ? model_bg.classify(p) : c;
    }));
  }
  set_counters(state, f, 0);
}

// --- the PCL baseline -----------------------------------------------------------------------------------

using Cloud = pcl::PointCloud<pcl::PointXYZ>;

Cloud::Ptr to_cloud(const std::vector<LidarPoint>& points) {
  Cloud::Ptr cloud(new Cloud);
  cloud->reserve(points.size());
  for (const auto& p : points) {
    cloud->push_back(pcl::PointXYZ(p.x, p.y, p.z));
  }
  return cloud;
}

struct Baseline {
  Cloud::Ptr reference;
  pcl::KdTreeFLANN<pcl::PointXYZ> tree;
  Cloud::Ptr frame;
  Eigen::Vector2d lidar_xy;
};

Cloud::Ptr baseline_background(const Baseline& b) {
  Cloud::Ptr foreground(new Cloud);
  std::vector<int> index(1);
  std::vector<float> d2(1);
  for (const auto& p : b.frame->points) {
    if (p.z < kGroundZ) {
      continue;
    }
    if (b.tree.nearestKSearch(p, 1, index, d2) < 1 || d2[0] > kMatchRadius * kMatchRadius) {
      foreground->push_back(pcl::PointXYZ(p.x, p.y, 0.0F));  // flattened, as Autoware clusters
    }
  }
  return foreground;
}

std::vector<pcl::PointIndices> baseline_clusters(const Cloud::Ptr& foreground) {
  std::vector<pcl::PointIndices> clusters;
  if (foreground->empty()) {
    return clusters;
  }
  pcl::search::KdTree<pcl::PointXYZ>::Ptr tree(new pcl::search::KdTree<pcl::PointXYZ>);
  tree->setInputCloud(foreground);
  pcl::EuclideanClusterExtraction<pcl::PointXYZ> ec;
  ec.setClusterTolerance(0.7);
  ec.setMinClusterSize(10);
  ec.setMaxClusterSize(20000);
  ec.setSearchMethod(tree);
  ec.setInputCloud(foreground);
  ec.extract(clusters);
  return clusters;
}

LShapeFitConfig exhaustive_1deg() {
  LShapeFitConfig config;
  config.search.method = OrientationSearchMethod::exhaustive;
  config.search.exhaustive_step_deg = 1.0;
  return config;
}

std::unique_ptr<Baseline> make_baseline(const rsu::bench::CorridorFrames& f) {
  auto b = std::make_unique<Baseline>();
  b->reference = to_cloud(concatenated_background(f));
  b->tree.setInputCloud(b->reference);
  b->frame = to_cloud(f.frame);
  b->lidar_xy = f.lidar_xy;
  return b;
}

void BM_BaselinePipeline(benchmark::State& state, int model) {
  const auto& f = frames(model);
  const auto b = make_baseline(f);
  const LShapeFitConfig fit_config = exhaustive_1deg();
  std::size_t objects = 0;
  for (auto _ : state) {
    const Cloud::Ptr foreground = baseline_background(*b);
    const auto clusters = baseline_clusters(foreground);
    for (const auto& c : clusters) {
      std::vector<Eigen::Vector2d> xy;
      xy.reserve(c.indices.size());
      for (const int i : c.indices) {
        const auto& p = (*foreground)[static_cast<std::size_t>(i)];
        xy.emplace_back(static_cast<double>(p.x), static_cast<double>(p.y));
      }
      const RectangleFit fit = fit_rectangle(xy, b->lidar_xy, fit_config);
      benchmark::DoNotOptimize(correct_algorithm1(fit, vehicle_size(f), b->lidar_xy));
    }
    objects = clusters.size();
  }
  set_counters(state, f, objects);
}

void BM_BaselineBackgroundKdTree(benchmark::State& state, int model) {
  const auto& f = frames(model);
  const auto b = make_baseline(f);
  for (auto _ : state) {
    benchmark::DoNotOptimize(baseline_background(*b));
  }
  set_counters(state, f, 0);
}

// --- clustering and fitting alone, on this frame's foreground -----------------------------------------

// The foreground of the frame after this library's default background removal.
std::vector<std::uint32_t> foreground_of(const rsu::bench::CorridorFrames& f) {
  RangeImageBackground model_bg(f.lidar_xy);
  for (const auto& b : f.background) {
    model_bg.add_training_frame(b);
  }
  const GroundHeightFilter ground;
  return select_foreground(f.frame,
                           [&](const LidarPoint& p) {
                             const PointClass c = ground.classify(p);
                             return c == PointClass::foreground ? model_bg.classify(p) : c;
                           })
      .indices;
}

const ClusteringConfig kClustering{.tolerance_m = 0.7, .min_points = 10, .max_points = 20000};

void BM_ClusterGrid(benchmark::State& state, int model) {
  const auto& f = frames(model);
  const auto fg = foreground_of(f);
  std::size_t objects = 0;
  for (auto _ : state) {
    const Clustering c = cluster_grid(f.frame, fg, kClustering);
    objects = c.clusters.size();
    benchmark::DoNotOptimize(c);
  }
  set_counters(state, f, objects);
  state.counters["foreground"] = static_cast<double>(fg.size());
}

void BM_BaselineClusterPcl(benchmark::State& state, int model) {
  const auto& f = frames(model);
  const auto fg = foreground_of(f);
  Cloud::Ptr cloud(new Cloud);
  for (const std::uint32_t i : fg) {
    cloud->push_back(pcl::PointXYZ(f.frame[i].x, f.frame[i].y, 0.0F));
  }
  std::size_t objects = 0;
  for (auto _ : state) {
    const auto clusters = baseline_clusters(cloud);
    objects = clusters.size();
    benchmark::DoNotOptimize(clusters);
  }
  set_counters(state, f, objects);
  state.counters["foreground"] = static_cast<double>(fg.size());
}

// The vehicle's cluster (the largest), map frame.
std::vector<Eigen::Vector3d> vehicle_points(const rsu::bench::CorridorFrames& f) {
  const Clustering c = cluster_grid(f.frame, foreground_of(f), kClustering);
  std::vector<Eigen::Vector3d> points;
  const Cluster* largest = nullptr;
  for (const auto& cluster : c.clusters) {
    if (largest == nullptr || cluster.size() > largest->size()) {
      largest = &cluster;
    }
  }
  if (largest != nullptr) {
    for (const std::uint32_t i : *largest) {
      const LidarPoint& p = f.frame[i];
      points.push_back(rsu::lidar::position_of(p));
    }
  }
  return points;
}

std::vector<Eigen::Vector2d> vehicle_cluster(const rsu::bench::CorridorFrames& f) {
  std::vector<Eigen::Vector2d> xy;
  for (const Eigen::Vector3d& p : vehicle_points(f))
    xy.push_back(p.head<2>());
  return xy;
}

void run_fit(benchmark::State& state, int model, const LShapeFitConfig& config) {
  const auto& f = frames(model);
  const auto xy = vehicle_cluster(f);
  for (auto _ : state) {
    benchmark::DoNotOptimize(fit_rectangle(xy, f.lidar_xy, config));
  }
  state.counters["cluster_points"] = static_cast<double>(xy.size());
}

void BM_FitCoarseToFine(benchmark::State& state, int model) {
  run_fit(state, model, LShapeFitConfig{});
}

void BM_BaselineFitExhaustive1deg(benchmark::State& state, int model) {
  run_fit(state, model, exhaustive_1deg());
}

void BM_FitExhaustive0p1deg(benchmark::State& state, int model) {
  LShapeFitConfig config = exhaustive_1deg();
  config.search.exhaustive_step_deg = 0.1;
  run_fit(state, model, config);
}

// One vehicle's whole fix (rectangle fit and improved correction), as rsud runs it per vehicle.
void BM_FixVehicle(benchmark::State& state, int model) {
  const auto& f = frames(model);
  const auto points = vehicle_points(f);
  const LidarGeometry lidar = lidar_of(f);
  const AnnouncedVehicle vehicle{vehicle_size(f), vehicle_prior(f)};
  for (auto _ : state) {
    benchmark::DoNotOptimize(fix_vehicle(points, vehicle, lidar));
  }
  state.counters["cluster_points"] = static_cast<double>(points.size());
}

// A car near the LiDAR (2 m up), its own returns only (the simulator's truth), as rsud fixes it: the lasers'
// elevations and azimuth step known. A near car is where a dense sensor's clusters are large (issue 16:
// 5,600-17,600 points for an OS1-128 within 10 m).
struct NearCar {
  std::vector<Eigen::Vector3d> points;
  LidarGeometry lidar;
  AnnouncedVehicle announced;
  rsu::Pose2 truth;
};

// model: 1 = VLP-32C, 2 = 128 rings; distance_dm: the car's distance from the LiDAR in decimetres.
NearCar near_car(std::int64_t model_index, std::int64_t distance_dm) {
  const auto model = *rsu::lidar::sensor_model_by_name(kModels[static_cast<std::size_t>(model_index)]);
  const double distance = static_cast<double>(distance_dm) / 10.0;
  const rsu::sim::VehicleShape shape;
  NearCar car;
  car.truth = rsu::Pose2{1.5, distance, rsu::deg_to_rad(8.0)};
  rsu::sim::Scene scene;
  scene.ground.half_extent_m = 60.0;
  rsu::sim::Vehicle vehicle;
  vehicle.id = 1;
  vehicle.shape = shape;
  vehicle.trajectory = rsu::sim::StaticPose{car.truth};
  scene.vehicles.push_back(vehicle);
  rsu::Pose3 mount;
  mount.z = 2.0;
  const rsu::sim::LidarSimulator simulator(model, mount, rsu::sim::NoiseModel{}, scene);
  const rsu::sim::SimulatedFrame frame = simulator.simulate_frame(0);
  for (std::size_t i = 0; i < frame.frame.points.size(); ++i) {
    const LidarPoint& p = frame.frame.points[i];
    // The ground filter's 0.2 m (the pilot drops those returns too); the mount is level at the origin.
    if (frame.truth[i].surface == rsu::sim::SurfaceClass::kVehicle && p.z + 2.0F >= 0.2F)
      car.points.emplace_back(static_cast<double>(p.x), static_cast<double>(p.y),
                              static_cast<double>(p.z) + 2.0);
  }
  car.lidar.position = {0.0, 0.0, 2.0};
  for (const double e : model.elevation_deg)
    car.lidar.elevations_rad.push_back(rsu::deg_to_rad(e));
  car.lidar.azimuth_step_rad = rsu::deg_to_rad(model.azimuth_step_deg());
  car.announced = {{shape.length, shape.width, shape.height}, YawPrior{car.truth.yaw + 0.05, 0.17}};
  return car;
}

// A near car's whole fix. Args: model, distance (dm), VehicleFixConfig::thin_above_points (0: never
// thinned, the baseline; 3000: the default until issue 16's trace of the live latency).
void BM_FixVehicleNear(benchmark::State& state) {
  const NearCar car = near_car(state.range(0), state.range(1));
  VehicleFixConfig config;
  config.thin_above_points = static_cast<std::size_t>(state.range(2));
  VehicleFix fix;
  for (auto _ : state) {
    fix = fix_vehicle(car.points, car.announced, car.lidar, config);
    benchmark::DoNotOptimize(fix);
  }
  state.counters["cluster_points"] = static_cast<double>(car.points.size());
  state.counters["points_used"] = static_cast<double>(fix.points_used);
  state.counters["error_m"] =
      std::hypot(fix.corrected.pose.x - car.truth.x, fix.corrected.pose.y - car.truth.y);
  state.counters["ok"] = fix.ok() ? 1.0 : 0.0;
}

// A near car's detection and fix as rsud makes them: the rectangle fitted to the thinned cluster
// (detect with FitThinning), then the fix. Args: model, distance (dm); 1 as the last: the fix takes the
// detection's thinning (rsud since issue 16's reuse), 0: it thins the points again (the baseline).
void BM_DetectAndFixNear(benchmark::State& state) {
  const NearCar car = near_car(state.range(0), state.range(1));
  std::vector<LidarPoint> cloud;
  for (const Eigen::Vector3d& p : car.points) {
    LidarPoint q;
    q.x = static_cast<float>(p.x());
    q.y = static_cast<float>(p.y());
    q.z = static_cast<float>(p.z());
    cloud.push_back(q);
  }
  const VehicleFixConfig config;
  const bool reuse = state.range(2) != 0;
  VehicleFix fix;
  for (auto _ : state) {
    const Detection d = detect(cloud, car.lidar.xy(), config.fit, {&car.lidar, config.thin_above_points});
    fix = reuse ? fix_vehicle(d.points, *d.thinning, car.announced, car.lidar, config)
                : fix_vehicle(d.points, car.announced, car.lidar, config);
    benchmark::DoNotOptimize(fix);
  }
  state.counters["cluster_points"] = static_cast<double>(cloud.size());
  state.counters["error_m"] =
      std::hypot(fix.corrected.pose.x - car.truth.x, fix.corrected.pose.y - car.truth.y);
}

// The thinning alone (rsud runs it once per dense cluster, for the detection's rectangle; the fix of a
// vehicle of that detection alone reuses it). Args: model, distance (dm), as BM_FixVehicleNear; thinned to
// the default's 800 points.
void BM_ThinNear(benchmark::State& state) {
  const NearCar car = near_car(state.range(0), state.range(1));
  const std::size_t above = VehicleFixConfig{}.thin_above_points;
  AzimuthThinning thinned;
  for (auto _ : state) {
    thinned = thin_along_azimuth(car.points, car.lidar, above);
    benchmark::DoNotOptimize(thinned);
  }
  state.counters["cluster_points"] = static_cast<double>(car.points.size());
  state.counters["kept"] = static_cast<double>(thinned.points.size());
  state.counters["stride"] = static_cast<double>(thinned.stride);
}

// The thinning's azimuths (the angle of each of a near car's points from the first's direction, seen
// from the LiDAR): azimuth_angle against float's atan2f, which the thinning used before, on the same
// points in the same run. Args: model, distance (dm); 0 / 1 as the last: atan2f / azimuth_angle.
void BM_ThinningAzimuths(benchmark::State& state) {
  const NearCar car = near_car(state.range(0), state.range(1));
  std::vector<Eigen::Vector2d> cross_dot;
  const Eigen::Vector2d reference = car.points.front().head<2>() - car.lidar.xy();
  for (const Eigen::Vector3d& p : car.points) {
    const Eigen::Vector2d d = p.head<2>() - car.lidar.xy();
    cross_dot.emplace_back(reference.x() * d.y() - reference.y() * d.x(), reference.dot(d));
  }
  const bool ours = state.range(2) != 0;
  const auto angle = [ours](const Eigen::Vector2d& c) {
    return ours ? azimuth_angle(c.x(), c.y())
                : static_cast<double>(std::atan2(static_cast<float>(c.x()), static_cast<float>(c.y())));
  };
  for (auto _ : state) {
    double sum = 0.0;
    for (const Eigen::Vector2d& c : cross_dot)
      sum += angle(c);
    benchmark::DoNotOptimize(sum);
  }
  double worst = 0.0;
  for (const Eigen::Vector2d& c : cross_dot)
    worst = std::max(worst, std::abs(angle(c) - std::atan2(c.x(), c.y())));
  state.counters["points"] = static_cast<double>(cross_dot.size());
  state.counters["worst_error_rad"] = worst;
}

}  // namespace

BENCHMARK(BM_FixVehicleNear)
    ->ArgsProduct({{1, 2},
                   {36, 50, 70, 100},
                   {0, 3000, static_cast<std::int64_t>(VehicleFixConfig{}.thin_above_points)}})
    ->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_ThinNear)->ArgsProduct({{1, 2}, {36, 50, 70, 100}})->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_DetectAndFixNear)->ArgsProduct({{1, 2}, {36, 50, 100}, {0, 1}})->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_ThinningAzimuths)->ArgsProduct({{2}, {36, 100}, {0, 1}})->Unit(benchmark::kMicrosecond);

#define RSU_PER_MODEL(fn)                                          \
  BENCHMARK_CAPTURE(fn, vlp16, 0)->Unit(benchmark::kMicrosecond);  \
  BENCHMARK_CAPTURE(fn, vlp32c, 1)->Unit(benchmark::kMicrosecond); \
  BENCHMARK_CAPTURE(fn, generic128, 2)->Unit(benchmark::kMicrosecond)

RSU_PER_MODEL(BM_Pipeline);
RSU_PER_MODEL(BM_BaselinePipeline);
RSU_PER_MODEL(BM_PipelineReferenceFrame);
RSU_PER_MODEL(BM_BackgroundRangeImage);
RSU_PER_MODEL(BM_BackgroundReferenceGrid);
RSU_PER_MODEL(BM_BaselineBackgroundKdTree);
RSU_PER_MODEL(BM_ClusterGrid);
RSU_PER_MODEL(BM_BaselineClusterPcl);
RSU_PER_MODEL(BM_FitCoarseToFine);
RSU_PER_MODEL(BM_BaselineFitExhaustive1deg);
RSU_PER_MODEL(BM_FitExhaustive0p1deg);
RSU_PER_MODEL(BM_FixVehicle);
