// SPDX-License-Identifier: Apache-2.0
#include "eval/corridor/experiment_config.h"

#include <filesystem>

#include "io/yaml_field.h"

namespace rsu::eval {

CorridorExperimentConfig load_corridor_experiment(const std::string& path) {
  using io::YamlField;
  const YAML::Node root = io::parse_yaml(io::read_text_file(path), path);
  const YamlField doc(root, "", path, 1);
  doc.expect_map({"scenario", "vehicle_id", "traffic_connected", "rsu_models", "duration_s", "seed",
                  "vehicle_lidar", "map", "ndt"});
  CorridorExperimentConfig c;
  c.source = path;
  const YamlField scenario = doc.required("scenario");
  const std::filesystem::path scenario_path = std::filesystem::path(path).parent_path() / scenario.text();
  c.scenario = sim::load_scenario_file(scenario_path.string());
  c.vehicle_id = static_cast<std::uint32_t>(doc.number_or("vehicle_id", 1));
  bool found = false;
  for (const auto& v : c.scenario.scene.vehicles)
    found = found || v.id == c.vehicle_id;
  if (!found)
    doc.child("vehicle_id").fail("no vehicle with this id in " + scenario_path.string());
  if (doc.has("traffic_connected")) {
    for (const YamlField& id : doc.child("traffic_connected").items()) {
      const auto v = static_cast<std::uint32_t>(id.number());
      bool in_scenario = false;
      for (const auto& sv : c.scenario.scene.vehicles)
        in_scenario = in_scenario || sv.id == v;
      if (!in_scenario || v == c.vehicle_id)
        id.fail("not another vehicle of " + scenario_path.string());
      c.traffic_connected.push_back(v);
    }
  }
  for (const YamlField& m : doc.required("rsu_models").items()) {
    if (!lidar::sensor_model_by_name(m.text()) || !lidar::sensor_model_by_name(m.text())->has_packet_format())
      m.fail("not a LiDAR model with a Velodyne packet format (vlp16, vlp32c)");
    c.rsu_models.push_back(m.text());
  }
  c.duration_s = doc.positive_or("duration_s", c.duration_s);
  c.seed = static_cast<std::uint64_t>(doc.number_or("seed", 11));

  const YamlField lidar = doc.required("vehicle_lidar");
  lidar.expect_map({"model", "mount", "noise"});
  c.vehicle_lidar_model = lidar.required("model").text();
  if (!lidar::sensor_model_by_name(c.vehicle_lidar_model))
    lidar.child("model").fail("unknown LiDAR model");
  const YamlField mount = lidar.required("mount");
  mount.expect_map({"x", "y", "z", "roll_deg", "pitch_deg", "yaw_deg"});
  c.vehicle_lidar_mount = Pose3{mount.number_or("x", 0),
                                mount.number_or("y", 0),
                                mount.number_or("z", 0),
                                mount.angle_deg_or("roll_deg", 0),
                                mount.angle_deg_or("pitch_deg", 0),
                                mount.angle_deg_or("yaw_deg", 0)};
  if (lidar.has("noise")) {
    const YamlField n = lidar.child("noise");
    n.expect_map({"range_sigma_m", "angle_sigma_rad"});
    c.vehicle_lidar_noise.range_sigma_m =
        n.non_negative_or("range_sigma_m", c.vehicle_lidar_noise.range_sigma_m);
    c.vehicle_lidar_noise.angle_sigma_rad =
        n.non_negative_or("angle_sigma_rad", c.vehicle_lidar_noise.angle_sigma_rad);
  }
  c.vehicle_lidar_noise.seed = c.seed;

  if (doc.has("map")) {
    const YamlField map = doc.child("map");
    map.expect_map({"sample_spacing_m"});
    c.map_spacing_m = map.positive_or("sample_spacing_m", c.map_spacing_m);
  }
  const YamlField ndt = doc.required("ndt");
  ndt.expect_map({"resolution_m", "step_size_m", "transformation_epsilon", "max_iterations", "crop_range_m",
                  "voxel_leaf_m", "random_sample_points", "output_covariance", "output_sigma_xy_m",
                  "output_sigma_yaw_rad", "laplace_scale", "laplace_min_sigma_xy_m",
                  "laplace_min_sigma_yaw_rad", "fitness_nominal_m2", "fitness_sigma_m_per_m2",
                  "fitness_sigma_rad_per_m2", "initial_pose_error"});
  c.ndt.resolution_m = ndt.positive_or("resolution_m", c.ndt.resolution_m);
  c.ndt.step_size_m = ndt.positive_or("step_size_m", c.ndt.step_size_m);
  c.ndt.transformation_epsilon = ndt.positive_or("transformation_epsilon", c.ndt.transformation_epsilon);
  c.ndt.max_iterations = static_cast<int>(ndt.positive_or("max_iterations", c.ndt.max_iterations));
  c.ndt.crop_range_m = ndt.positive_or("crop_range_m", c.ndt.crop_range_m);
  c.ndt.voxel_leaf_m = ndt.positive_or("voxel_leaf_m", c.ndt.voxel_leaf_m);
  c.ndt.random_sample_points =
      static_cast<int>(ndt.positive_or("random_sample_points", c.ndt.random_sample_points));
  c.ndt.output_sigma_xy_m = ndt.positive_or("output_sigma_xy_m", c.ndt.output_sigma_xy_m);
  c.ndt.output_sigma_yaw_rad = ndt.positive_or("output_sigma_yaw_rad", c.ndt.output_sigma_yaw_rad);
  if (ndt.has("output_covariance")) {
    const YamlField kind = ndt.child("output_covariance");
    const std::string name = kind.text();
    if (name != "fixed" && name != "laplace") {
      kind.fail("expected fixed or laplace, got \"" + name + "\"");
    }
    c.ndt.covariance_estimate =
        name == "laplace" ? NdtConfig::CovarianceEstimate::kLaplace : NdtConfig::CovarianceEstimate::kFixed;
  }
  c.ndt.laplace_scale = ndt.positive_or("laplace_scale", c.ndt.laplace_scale);
  c.ndt.laplace_min_sigma_xy_m = ndt.positive_or("laplace_min_sigma_xy_m", c.ndt.laplace_min_sigma_xy_m);
  c.ndt.laplace_min_sigma_yaw_rad =
      ndt.positive_or("laplace_min_sigma_yaw_rad", c.ndt.laplace_min_sigma_yaw_rad);
  c.ndt.fitness_nominal_m2 = ndt.positive_or("fitness_nominal_m2", c.ndt.fitness_nominal_m2);
  c.ndt.fitness_sigma_m_per_m2 = ndt.non_negative_or("fitness_sigma_m_per_m2", c.ndt.fitness_sigma_m_per_m2);
  c.ndt.fitness_sigma_rad_per_m2 =
      ndt.non_negative_or("fitness_sigma_rad_per_m2", c.ndt.fitness_sigma_rad_per_m2);
  if (ndt.has("initial_pose_error")) {
    const YamlField e = ndt.child("initial_pose_error");
    e.expect_map({"x", "y", "yaw_deg"});
    c.initial_pose_error = Pose2{e.number_or("x", 0), e.number_or("y", 0), e.angle_deg_or("yaw_deg", 0)};
  }
  return c;
}

}  // namespace rsu::eval
