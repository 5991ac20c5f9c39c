// Scratch: accuracy of the pipeline on the corridor (not a benchmark).
#include <cstdio>
#include "common/angles.h"
#include "corridor_frames.h"
#include "perception/pipeline.h"
using namespace rsu;
using namespace rsu::perception;
int main(int argc, char** argv) {
  const std::string model = argc > 1 ? argv[1] : "vlp32c";
  const sim::Scenario scenario = sim::load_scenario_file(RSU_SOURCE_DIR "/scenarios/corridor.yaml");
  auto bg = bench::make_corridor_frames(model, 6.0, 3);
  PerceptionConfig cfg;
  if (argc > 2) cfg.background = BackgroundMethod::reference_frame;
  PerceptionPipeline pipe(cfg, bg.lidar_xy);
  for (auto& f : bg.background) pipe.add_background_frame(f);
  SensorModel m = *sensor_model_by_name(model);
  const sim::LidarSimulator sim(m, scenario.lidar.mount, scenario.lidar.noise, scenario.scene);
  for (double t = 0.0; t < 11.0; t += 0.25) {
    auto f = bench::to_map_frame(sim.simulate_frame(from_seconds(t)).frame, scenario.lidar.mount);
    auto truth = sim::pose_at(scenario.scene.vehicles[0].trajectory, from_seconds(t) + 50'000'000);
    auto r = pipe.process(f);
    const DetectedObject* best = nullptr; double bd = 1e9;
    for (auto& o : r.objects) { if (!o.fit.ok()) continue; double d = (o.fit.center - Eigen::Vector2d(truth.x, truth.y)).norm(); if (d < bd) { bd = d; best = &o; } }
    if (!best || bd > 4) { printf("t %.2f x %.1f: no object (fg %zu, objs %zu)\n", t, truth.x, r.stats.foreground_points, r.objects.size()); continue; }
    truth = sim::pose_at(scenario.scene.vehicles[0].trajectory, best->sweep_time_ns);
    VehicleSize size{4.89, 1.92};
    auto a1 = correct_algorithm1(best->fit, size, bg.lidar_xy);
    auto im = pipe.correct(*best, size, YawPrior{truth.yaw + 0.1, 0.17});
    auto ge = pipe.correct(*best, size, std::nullopt);
    auto err = [&](const CorrectedPose& c) { return std::hypot(c.pose.x - truth.x, c.pose.y - truth.y); };
    auto yerr = [&](const CorrectedPose& c) { return rad_to_deg(std::abs(std::remainder(c.pose.yaw - truth.yaw, kPi))); };
    printf("t %.2f x %6.1f y %5.2f n %4zu objs %zu fit %.2fx%.2f seen %d%d%d%d | raw %.3f | alg1 %.3f (%4.1f) | prior %.3f (%4.1f) | geo %.3f (%4.1f) %s %.2f sd %.3f\n", t, truth.x, truth.y,
           best->point_indices.size(), r.objects.size(), best->fit.length0, best->fit.length1, best->fit.edges[0].seen, best->fit.edges[1].seen, best->fit.edges[2].seen, best->fit.edges[3].seen,
           (best->fit.center - Eigen::Vector2d(truth.x, truth.y)).norm(), err(a1), yerr(a1), err(im), yerr(im), err(ge), yerr(ge), std::string(to_string(ge.resolution)).c_str(), ge.confidence, std::sqrt(ge.covariance(0,0) + ge.covariance(1,1)));
  }
}
